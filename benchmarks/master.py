"""The Meng scene (scenes/meng_eq35.toml) at a 1 ms macro step: our master against libcosim
(libcosimpy, the Open Simulation Platform's engine) stepping the same seven FMUs with the same
connections at the same step, in one run.

Reports the real-time factor of each, their ratio, our master's overhead share (wall time outside
FMI calls), and how far the two runs' poses differ (libcosim's fixed-step algorithm holds inputs
constant over a step, like our order-0 Jacobi; ours runs the scene's Gauss-Seidel of order 1).

    python benchmarks/master.py [--duration 10]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from fmpy import read_model_description

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from cosim.fmus import ROOT, fmu_path  # noqa: E402
from cosim.parameter_sets import mechanics_start_values  # noqa: E402
from cosim.runner import run_scene  # noqa: E402
from cosim.scene import load_scene  # noqa: E402
from cosim.signals import pose_reference  # noqa: E402
from cosim.system import DRIVES, POSE  # noqa: E402


def run_libcosim(scene, duration: float) -> tuple[float, np.ndarray]:
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    wiring = DRIVES[scene.drive]
    mech_path, drive_path = fmu_path("mechanics"), fmu_path(wiring.fmu)
    mech_vars = {v.name: v for v in read_model_description(str(mech_path)).modelVariables}
    drive_vars = {v.name: v for v in read_model_description(str(drive_path)).modelVariables}
    step_ns = int(round(scene.step * 1e9))
    execution = CosimExecution.from_step_size(step_size=step_ns)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    mech = execution.add_local_slave(CosimLocalSlave(fmu_path=str(mech_path), instance_name="mechanics"))

    def initial(index, variables, name, value):
        v = variables[name]
        setter = {"Real": execution.real_initial_value, "Boolean": execution.boolean_initial_value}.get(
            v.type, execution.integer_initial_value)
        cast = {"Real": float, "Boolean": bool}.get(v.type, int)
        assert setter(index, v.valueReference, cast(value)), name

    for name, value in {**mechanics_start_values(scene.parameter_set, scene.mass_set),
                        **scene.mechanics_parameters}.items():
        initial(mech, mech_vars, name, value)
    for i in range(1, 7):
        drive = execution.add_local_slave(CosimLocalSlave(fmu_path=str(drive_path), instance_name=f"drive{i}"))
        for name, value in scene.drive_parameters.items():
            initial(drive, drive_vars, name, value)
        for output, drive_input in (wiring.reference, wiring.position, wiring.velocity):
            execution.connect_real_variables(mech, mech_vars[output.format(i=i)].valueReference, drive,
                                             drive_vars[drive_input].valueReference)
        execution.connect_real_variables(drive, drive_vars[wiring.effort[0]].valueReference, mech,
                                         mech_vars[wiring.effort[1].format(i=i)].valueReference)
    # The moving reference pose is set between steps through libcosim's override manipulator,
    # as our runner sets it between its steps.
    reference = pose_reference(scene)
    pose_vrs = [mech_vars[f"pose.{a}"].valueReference for a in POSE]
    ref_vrs = [mech_vars[f"pose_ref.{a}"].valueReference for a in POSE]
    from libcosimpy.CosimManipulator import CosimManipulator
    manipulator = CosimManipulator.create_override()
    execution.add_manipulator(manipulator)
    n = int(round(duration / scene.step))
    start = time.perf_counter()
    for k in range(n):
        manipulator.slave_real_values(mech, ref_vrs, list(reference(k * scene.step)))
        execution.step()
    wall = time.perf_counter() - start
    return wall, np.array(observer.last_real_values(mech, pose_vrs))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--duration", type=float, default=10.0)
    args = parser.parse_args()
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml")
    scene.duration = args.duration
    scene.pulses = []  # the impact needs a timed load; left out of both runs
    result, report = run_scene(scene)
    ours = np.array([result[f"pose.{a}"][-1] for a in POSE])
    wall_libcosim, theirs = run_libcosim(scene, args.duration)
    print(f"Meng scene, {args.duration:g} s at {scene.step * 1e3:g} ms, 7 FMUs")
    print(f"  ours (cosim, Gauss-Seidel order 1): wall {report.wall:.2f} s, real-time factor "
          f"{report.real_time_factor:.1f}, master overhead {100 * report.master_share:.0f} % of wall")
    print(f"  libcosim (fixed step):             wall {wall_libcosim:.2f} s, real-time factor "
          f"{args.duration / wall_libcosim:.1f}")
    print(f"  ratio libcosim wall / ours: {wall_libcosim / report.wall:.2f}")
    print(f"  final pose difference (ours - libcosim): {np.abs(ours - theirs).max():.2e}")


if __name__ == "__main__":
    main()
