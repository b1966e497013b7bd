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
    checkpoints: np.ndarray | None = None  # times at which poses were taken
    poses: np.ndarray | None = None        # pose (n x 6) at the checkpoints


@dataclass
class Ecco:
    """libcosim's ECCO algorithm (Sadjina and Pedersen 2020): step control from the power bonds'
    energy residual, PI gains as libcosim's defaults."""
    rtol: float = 1e-4
    atol: float = 1e-4
    h_min: float = 1e-5
    h_max: float = 1e-2


def run_in_libcosim(scene: Scene, duration: float | None = None, checkpoints: np.ndarray | None = None,
                    ecco: Ecco | None = None) -> LibcosimRun:
    """Runs `scene` (for `duration`, default the scene's) in libcosim: at its fixed step, or under
    ECCO with a power bond per drive (torque x speed, force x velocity). With `checkpoints` the run
    stops at each of those times to take the pose (the observer's last values)."""
    from libcosimpy.CosimAlgorithm import CosimAlgorithm, EccoParams
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    algorithm = None
    if ecco is None:
        execution = CosimExecution.from_step_size(step_size=int(round(scene.step * 1e9)))
    else:
        algorithm = CosimAlgorithm.create_ecco_algorithm(EccoParams(
            step_size=scene.step, min_step_size=ecco.h_min, max_step_size=ecco.h_max, abs_tolerance=ecco.atol,
            rel_tolerance=ecco.rtol))
        execution = CosimExecution.from_algorithm(algorithm)
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
        if algorithm is not None:
            flow_out, flow_in = wiring.velocity
            algorithm.add_power_bond(drive[0], drive[1][wiring.effort[0]].valueReference,
                                     drive[1][flow_in].valueReference, mechanics[0],
                                     mechanics[1][flow_out.format(i=i)].valueReference,
                                     mechanics[1][wiring.effort[1].format(i=i)].valueReference)

    def final(instance: tuple[int, dict], names: list[str]) -> np.ndarray:
        return np.array(observer.last_real_values(instance[0], [instance[1][n].valueReference for n in names]))

    stops = list(checkpoints) if checkpoints is not None else [duration or scene.duration]
    poses, wall = [], 0.0
    for stop in stops:
        start = time.perf_counter()
        if not execution.simulate_until(target_time=int(round(stop * 1e9))):
            raise RuntimeError("libcosim: the simulation failed")
        wall += time.perf_counter() - start
        poses.append(final(mechanics, [f"pose.{a}" for a in POSE]))
    return LibcosimRun(wall, poses[-1], final(trajectory, [f"pose_ref.{a}" for a in POSE]),
                       np.array(stops), np.array(poses))
