"""A scene run in libcosim (libcosimpy, the Open Simulation Platform's engine): the FMUs, start
values, connections and power bonds of the scene's system structure (cosim.platform.run.runner
.scene_structure, the one wiring), stepped by libcosim's fixed-step or ECCO algorithm. Since
the trajectory is an FMU too, the scene needs nothing but FMUs and connections there.

Used to show the FMUs run in a second FMI tool and, in benchmarks, as the peer our master is
measured against.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from fmpy import read_model_description

from ...engine import EnergyControl
from ..ports import POSE
from .compile import scene_structure
from ..scene import Scene


@dataclass
class LibcosimRun:
    wall: float  # [s] inside simulate_until
    pose: np.ndarray  # final pose (6)
    pose_ref: np.ndarray  # final reference pose (6)
    checkpoints: np.ndarray | None = None  # times at which poses were taken
    poses: np.ndarray | None = None        # pose (n x 6) at the checkpoints


def run_in_libcosim(scene: Scene, duration: float | None = None, checkpoints: np.ndarray | None = None,
                    ecco: EnergyControl | None = None) -> LibcosimRun:
    """Runs `scene` (for `duration`, default the scene's) in libcosim: at its fixed step, or under
    libcosim's ECCO algorithm with a power bond per drive (torque x speed, force x velocity),
    configured with every number of `ecco` (our energy control's settings: gains, safety, change
    limits; libcosimpy's own EccoParams defaults, a safety of 0.8 and changes within [0.01, 0.2],
    only ever shrink the step). With `checkpoints` the run stops at each of those times to take the
    pose (the observer's last values)."""
    from libcosimpy.CosimAlgorithm import CosimAlgorithm, EccoParams
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.ERROR)
    algorithm = None
    structure = scene_structure(scene)
    if ecco is None:
        execution = CosimExecution.from_step_size(step_size=int(round(scene.step * 1e9)))
    else:
        algorithm = CosimAlgorithm.create_ecco_algorithm(EccoParams(
            safety_factor=ecco.safety, step_size=ecco.step, min_step_size=ecco.h_min, max_step_size=ecco.h_max,
            min_change_rate=ecco.change_min, max_change_rate=ecco.change_max, abs_tolerance=ecco.atol,
            rel_tolerance=ecco.rtol, p_gain=ecco.k_p, i_gain=ecco.k_i))
        execution = CosimExecution.from_algorithm(algorithm)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    instances = _wired(execution, structure)
    if algorithm is not None:
        for bond in structure.bonds:  # effort source -> flow side, as libcosim's power bond wants it
            (effort_side, a_vars), (flow_side, b_vars) = instances[bond.effort.source[0]], instances[bond.flow.source[0]]
            algorithm.add_power_bond(effort_side, a_vars[bond.effort.source[1]].valueReference,
                                     a_vars[bond.flow.target[1]].valueReference, flow_side,
                                     b_vars[bond.flow.source[1]].valueReference,
                                     b_vars[bond.effort.target[1]].valueReference)
    mechanics, trajectory = instances["mechanics"], instances["trajectory"]

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


def _wired(execution, structure) -> dict[str, tuple[int, dict]]:
    """The system's components added to the libcosim execution with their parameter values, and its
    connections made; per component its slave index and its variables by name."""
    from libcosimpy.CosimSlave import CosimLocalSlave
    instances: dict[str, tuple[int, dict]] = {}
    for component in structure.components:
        variables = {v.name: v for v in read_model_description(str(component.fmu)).modelVariables}
        index = execution.add_local_slave(CosimLocalSlave(fmu_path=str(component.fmu), instance_name=component.name))
        instances[component.name] = (index, variables)
        for name, value in component.parameters.items():
            v = variables[name]
            setter, cast = {"Real": (execution.real_initial_value, float),
                            "Boolean": (execution.boolean_initial_value, bool),
                            "String": (execution.string_initial_value, str)}.get(
                v.type, (execution.integer_initial_value, int))
            if not setter(index, v.valueReference, cast(value)):
                raise RuntimeError(f"libcosim: cannot set {component.name}.{name} = {value!r}")
    for c in structure.connections:
        (source, outputs), (target, inputs) = instances[c.source[0]], instances[c.target[0]]
        if not execution.connect_real_variables(source, outputs[c.source[1]].valueReference, target,
                                                inputs[c.target[1]].valueReference) == 0:
            raise RuntimeError(f"libcosim: cannot connect {c}")
    return instances
