"""threads = 2: the step kernel steps a Gauss-Seidel stage of components that feed none of each
other (the platform's trajectory and six drives) on two threads; the results are bit for bit those
of one thread (each member reads only what was there before the stage and writes its own slots)."""

from __future__ import annotations

import numpy as np

from cosim.engine import Algorithm, FixedStep
from cosim.engine.artifacts import ROOT
from cosim.engine.kernel import stages
from cosim.engine.settings import from_strings, to_strings
from cosim.platform.run.runner import run_scene
from cosim.platform.scene import load_scene


def test_a_stage_is_the_run_of_components_that_feed_none_of_each_other():
    drives = [f"pmsm{i}" for i in range(1, 7)]
    feeds = {"mechanics": [("trajectory", 0), *[(d, 0) for d in drives]], **{d: [("mechanics", 0)] for d in drives}}
    sequence = ["trajectory", *drives, "mechanics"]
    assert stages(sequence, feeds) == [7] * 7 + [8]  # trajectory and the drives, then the mechanics alone
    assert stages(["a", "b"], {"b": [("a", 0)]}) == [1, 2]  # a feeds b: one at a time
    assert stages(["a", "b"], {"a": [("b", 0)]}) == [1, 2]


def test_two_threads_give_the_results_of_one_bit_for_bit():
    runs = {}
    for threads in (1, 2):
        scene = load_scene(ROOT / "scenes" / "meng_eq35.toml", {"scene.duration": 3.0, "coupling.threads": threads})
        runs[threads] = run_scene(scene)
    (one, report_one), (two, report_two) = runs[1], runs[2]
    assert one.dtype.names == two.dtype.names and len(one) == len(two) > 2000
    for name in one.dtype.names:  # through the start-up, the finer start and the impact at 2.5 s
        assert np.array_equal(one[name], two[name]), name
    assert report_one.largest_energy_residual == report_two.largest_energy_residual
    assert 0.0 < report_two.fmi_seconds <= report_two.wall  # the helper's time is not counted twice


def test_threads_travel_with_the_settings():
    algorithm = Algorithm("gauss-seidel", 1, None, 20, False, 2)
    assert from_strings(to_strings(algorithm, FixedStep(1e-3)), 1e-3)[0] == algorithm
    assert "threads" not in to_strings(Algorithm(), FixedStep(1e-3))
