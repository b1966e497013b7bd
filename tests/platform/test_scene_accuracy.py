"""Every shipped scene at its own defaults is accurate where people look (issue 24): against the
same scene at a 64th of its step throughout (no finer start, no edge windows), over its first 3 s,
- the pose within 1e-5 m/rad after the first 10 ms;
- every recorded drive effort (what the mechanics applies: `torque_applied` where the coupling
  corrects it by the interface Jacobian) within 2 % of its own change through the start-up's first
  0.2 s and through each load pulse and the 0.2 s after it;
- and within 1e-3 N m (a rotary drive) or 1e-3 of the legs' largest static force (a linear drive)
  in steady tracking.
A test that needs other numerics sets them itself; this one holds the shipped defaults, whatever
they are."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.platform.run.accuracy import (POSE_FROM, POSE_TOLERANCE, efforts, steady_bound, tolerance_ratio,
                                     window_errors, windows)
from cosim.platform.ports import DRIVES, POSE, per_leg
from cosim.platform.run.compile import scene_values
from cosim.platform.run.runner import run_scene
from cosim.platform.scene import load_scene, shipped_scenes
from cosim.platform.run.tuning import leg_plants

DURATION = 3.0


@pytest.mark.parametrize("name", shipped_scenes())
def test_a_shipped_scene_at_its_defaults_matches_its_converged_run(name):
    scene = load_scene(name, {"scene.duration": min(DURATION, load_scene(name).duration)})
    duration = scene.duration
    reference = load_scene(name, {"scene.duration": duration, "scene.step": scene.step / 64,
                                  "coupling.startup_time": 0.0, "coupling.edge_time": 0.0})
    result, ref = run_scene(scene)[0], run_scene(reference)[0]
    late = result["time"] >= POSE_FROM
    for a in POSE:
        gap = np.abs(result[f"pose.{a}"] - np.interp(result["time"], ref["time"], ref[f"pose.{a}"]))[late].max()
        assert gap < POSE_TOLERANCE, (a, gap)
    effort = DRIVES[scene.drive].effort[0]  # as the legs feel it: the applied one under the interface Jacobian
    errors = window_errors(efforts(result, effort), ref, per_leg(effort), windows(duration, scene.pulses))
    bound = steady_bound(scene.drive, [p.static_force for p in leg_plants(scene_values(scene)[0])])
    ratio, window = tolerance_ratio(errors, bound)
    assert ratio <= 1.0, (window, ratio, errors)
    assert any(e.window == "steady tracking" for e in errors)


def test_the_interface_jacobian_at_2ms_misses_the_steady_tolerance():
    """What docs/guide/scenes.md says keeps the interface Jacobian at 2 ms out of the shipped
    defaults: its applied torques are off a converged run by more than 1e-3 N m in steady tracking
    (measured 5.7e-3 over the first 3 s; the slopes' correction of a systematic extrapolation error),
    while the pose keeps 1e-5."""
    from conftest import INTERFACE_JACOBIAN_2MS, paper_scene
    scene = paper_scene("meng_eq35", {**INTERFACE_JACOBIAN_2MS, "scene.duration": DURATION})
    reference = paper_scene("meng_eq35", {"scene.duration": DURATION, "scene.step": scene.step / 64,
                                          "coupling.startup_time": 0.0})
    result, ref = run_scene(scene)[0], run_scene(reference)[0]
    errors = {e.window: e for e in window_errors(efforts(result, "torque"), ref, per_leg("torque"),
                                                 windows(DURATION, scene.pulses))}
    assert errors["steady tracking"].error > 3 * steady_bound("pmsm", [])
    late = result["time"] >= POSE_FROM
    assert max(np.abs(result[f"pose.{a}"] - np.interp(result["time"], ref["time"], ref[f"pose.{a}"]))[late].max()
               for a in POSE) < POSE_TOLERANCE
