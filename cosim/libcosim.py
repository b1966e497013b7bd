"""A scene run in libcosim (libcosimpy, the Open Simulation Platform's engine): the same FMUs, start
values and connections as cosim.system builds, stepped by libcosim's fixed-step algorithm. Since
the trajectory is an FMU too, the scene needs nothing but FMUs and connections there.

Used to show the FMUs run in a second FMI tool and, in benchmarks, as the peer our master is
measured against.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from fmpy import read_model_description

from .fmus import fmu_path
from .parameter_sets import mechanics_start_values
from .scene import Scene
from .signals import scene_trajectory
from .system import DRIVES, POSE, WRENCH


@dataclass
class LibcosimRun:
    wall: float  # [s] inside simulate_until
    pose: np.ndarray  # final pose (6)
    pose_ref: np.ndarray  # final reference pose (6)


def run_in_libcosim(scene: Scene, duration: float | None = None) -> LibcosimRun:
    """Runs `scene` (for `duration`, default the scene's) at its fixed step in libcosim."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_step_size(step_size=int(round(scene.step * 1e9)))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)

    def add(fmu: str, instance: str, start_values: dict) -> tuple[int, dict]:
        path = fmu_path(fmu)
        variables = {v.name: v for v in read_model_description(str(path)).modelVariables}
        index = execution.add_local_slave(CosimLocalSlave(fmu_path=str(path), instance_name=instance))
        for name, value in start_values.items():
            v = variables[name]
            setter, cast = {"Real": (execution.real_initial_value, float),
                            "Boolean": (execution.boolean_initial_value, bool),
                            "String": (execution.string_initial_value, str)}.get(
                v.type, (execution.integer_initial_value, int))
            if not setter(index, v.valueReference, cast(value)):
                raise RuntimeError(f"libcosim: cannot set {instance}.{name} = {value!r}")
        return index, variables

    def connect(source: tuple[int, dict], output: str, target: tuple[int, dict], input_: str) -> None:
        if not execution.connect_real_variables(source[0], source[1][output].valueReference, target[0],
                                                target[1][input_].valueReference) == 0:
            raise RuntimeError(f"libcosim: cannot connect {output} -> {input_}")

    wiring = DRIVES[scene.drive]
    trajectory = add("trajectory", "trajectory", scene_trajectory(scene))
    mechanics = add("mechanics", "mechanics", {**mechanics_start_values(scene.parameter_set, scene.mass_set),
                                               **scene.mechanics_parameters})
    for name in [*[f"pose_ref.{a}" for a in POSE], *WRENCH]:
        connect(trajectory, name, mechanics, name)
    for i in range(1, 7):
        drive = add(wiring.fmu, f"{scene.drive}{i}", dict(scene.drive_parameters))
        for output, drive_input in (wiring.reference, wiring.position, wiring.velocity):
            connect(mechanics, output.format(i=i), drive, drive_input)
        connect(drive, wiring.effort[0], mechanics, wiring.effort[1].format(i=i))
    start = time.perf_counter()
    if not execution.simulate_until(target_time=int(round((duration or scene.duration) * 1e9))):
        raise RuntimeError("libcosim: the simulation failed")
    wall = time.perf_counter() - start

    def final(instance: tuple[int, dict], names: list[str]) -> np.ndarray:
        return np.array(observer.last_real_values(instance[0], [instance[1][n].valueReference for n in names]))

    return LibcosimRun(wall, final(mechanics, [f"pose.{a}" for a in POSE]),
                       final(trajectory, [f"pose_ref.{a}" for a in POSE]))
