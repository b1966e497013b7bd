"""The platform system: the trajectory FMU (reference pose and external wrench), the mechanics FMU
and six drive FMUs, wired as ../shared/INTERFACES.md says, stepped together at a fixed
communication step or under a step controller of cosim.coupling.

The wiring lives in DRIVES: swapping the drive kind changes those connections and nothing else.
Coupling: cosim.coupling's Gauss-Seidel with first-order extrapolation (by default): the
trajectory steps first and gives its outputs' exact derivatives; the drives step next, their
inputs extrapolated linearly from the mechanics' last two samples (so a drive also sees the rate of
its leg reference); the mechanics then steps with each drive effort interpolated linearly between
its values at t and t + h. cosim.runner runs a scene on it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping, Protocol, Sequence

import numpy as np
from fmpy import extract

from .coupling import (AdaptiveStep, Bond, Connection, Coupling, DivergenceMonitor, Diverged, GaussSeidel, Jacobi,
                       bond_names)
from .fmu_instance import FmuError, FmuInstance
from .fmus import fmu_path
from .native import NativeLoop

POSE = ("x", "y", "z", "roll", "pitch", "yaw")


@dataclass(frozen=True)
class DriveWiring:
    """Which mechanics outputs feed a drive and which drive output feeds the mechanics, per leg."""
    fmu: str
    reference: tuple[str, str]  # (mechanics output, drive input)
    position: tuple[str, str]
    velocity: tuple[str, str]
    effort: tuple[str, str]     # (drive output, mechanics input)


DRIVES = {
    "pmsm": DriveWiring("pmsm_drive", ("leg[{i}].angle_ref", "angle_ref"), ("leg[{i}].angle", "angle"),
                        ("leg[{i}].speed", "speed"), ("torque", "leg[{i}].torque")),
    "linear": DriveWiring("linear_motor", ("leg[{i}].length_ref", "position_ref"), ("leg[{i}].length", "position"),
                          ("leg[{i}].velocity", "velocity"), ("force", "leg[{i}].force")),
}


class RunFailed(RuntimeError):
    """An FMU failed mid-run (`error` an FmuError: which instance, call and time) or the coupling
    diverged (`error` a Diverged: when, how much, where, what to try); `result` holds the rows
    computed up to then."""

    def __init__(self, error: FmuError | Diverged, result: np.ndarray):
        super().__init__(str(error))
        self.error, self.result = error, result


WRENCH = ("load.force.x", "load.force.y", "load.force.z", "load.torque.x", "load.torque.y", "load.torque.z")


class StepControl(Protocol):
    """An adaptive macro-step controller of cosim.coupling (AdaptiveStep, EnergyStep)."""
    accepted: list[float]
    rejected: int
    before_step: Callable[[float], None]
    after_accept: Callable[[float], None]

    def advance(self, coupling: Coupling, t: float, t_end: float) -> float: ...


class PlatformSystem:
    """Trajectory, mechanics and six drives of one kind, initialized with the given start values
    (trajectory_values: the trajectory FMU's parameters, see cosim.signals; leg_values: per drive,
    start values on top of drive_values, e.g. each leg's force feedforward)."""

    def __init__(self, drive: str, mechanics_values: Mapping[str, float] | None = None,
                 drive_values: Mapping[str, float] | None = None, order: int = 1,
                 algorithm: str = "gauss-seidel", trajectory_values: Mapping[str, float | str] | None = None,
                 leg_values: Sequence[Mapping[str, float]] | None = None):
        if drive not in DRIVES:
            raise ValueError(f"unknown drive kind '{drive}' (known: {', '.join(DRIVES)})")
        self.wiring = wiring = DRIVES[drive]
        mechanics_path, drive_path = fmu_path("mechanics"), fmu_path(wiring.fmu)
        drive_unzip = extract(str(drive_path))
        self.trajectory = FmuInstance(fmu_path("trajectory"), "trajectory")
        self.mechanics = FmuInstance(mechanics_path, "mechanics")
        self.drives = [FmuInstance(drive_path, f"{drive}{i}", unzip_dir=drive_unzip) for i in range(1, 7)]
        self.trajectory.initialize(dict(trajectory_values or {}))
        self.mechanics.initialize(dict(mechanics_values or {}))
        for k, d in enumerate(self.drives):
            d.initialize({**(drive_values or {}), **(leg_values[k] if leg_values else {})})
        instances = {"trajectory": self.trajectory, "mechanics": self.mechanics, **{d.name: d for d in self.drives}}
        connections = [Connection(("trajectory", name), ("mechanics", name))
                       for name in [*[f"pose_ref.{a}" for a in POSE], *WRENCH]]
        bonds = []
        for i, d in enumerate(self.drives, start=1):
            for output, drive_input in (wiring.reference, wiring.position, wiring.velocity):
                connections.append(Connection(("mechanics", output.format(i=i)), (d.name, drive_input)))
            connections.append(Connection((d.name, wiring.effort[0]), ("mechanics", wiring.effort[1].format(i=i))))
            bonds.append(Bond(effort=connections[-1], flow=connections[-2]))  # torque x speed, force x velocity
        self.coupling = Coupling(instances, connections, bonds)
        if algorithm == "jacobi":
            self.algorithm = Jacobi(order)
        else:
            self.algorithm = GaussSeidel(order, ["trajectory", *[d.name for d in self.drives], "mechanics"])
        self.pose_ref = self.trajectory.real_group([f"pose_ref.{a}" for a in POSE])
        self.pose = self.mechanics.real_group([f"pose.{a}" for a in POSE])
        self.record_names: list[str] = []
        self._record_mechanics = None
        self._record_drives: list = []
        self._columns = [*[("trajectory", f"pose_ref.{a}") for a in POSE], *[("mechanics", f"pose.{a}") for a in POSE]]

    def record(self, mechanics_outputs: list[str], drive_outputs: list[str]) -> None:
        """Also record these mechanics outputs and, for each drive, these outputs (columns
        `<name>` and `<drive output>[i]`)."""
        self._record_mechanics = self.mechanics.real_group(mechanics_outputs) if mechanics_outputs else None
        self._record_drives = [d.real_group(drive_outputs) for d in self.drives] if drive_outputs else []
        self.record_names = [*mechanics_outputs, *[f"{n}[{i}]" for n in drive_outputs for i in range(1, 7)]]
        self._columns = [*[("trajectory", f"pose_ref.{a}") for a in POSE], *[("mechanics", f"pose.{a}") for a in POSE],
                         *[("mechanics", n) for n in mechanics_outputs],
                         *[(d.name, n) for n in drive_outputs for d in self.drives]]

    def _recorded(self) -> np.ndarray:
        parts = [self._record_mechanics.read()] if self._record_mechanics else []
        if self._record_drives:
            parts.append(np.array([g.read() for g in self._record_drives]).T.ravel())
        return np.concatenate(parts) if parts else np.zeros(0)

    @property
    def time(self) -> float:
        return self.mechanics.time

    @property
    def column_names(self) -> list[str]:
        return ["time", *[f"pose_ref.{a}" for a in POSE], *[f"pose.{a}" for a in POSE], *self.record_names]

    def _row(self) -> np.ndarray:
        return np.r_[self.time, self.pose_ref.read(), self.pose.read(), self._recorded()]

    def run(self, stop_time: float, step: float, control: StepControl | None = None,
            progress: Callable[[float], None] | None = None, native: bool = True,
            divergence_ratio: float | None = 0.05) -> np.ndarray:
        """Steps to stop_time, at the fixed macro step `step` or under `control` (an adaptive step
        controller of cosim.coupling that starts from `step`); returns rows of time, pose_ref (6),
        pose (6) and the recorded outputs (column_names) at every communication point.
        `progress` is called with the fraction done now and then. On an FMU error, raises RunFailed
        with the rows up to the last good communication point. At a fixed step, `native` runs the
        steps after the first in the C inner loop (cosim.native), which gives the same numbers, and
        a DivergenceMonitor (threshold divergence_ratio; None: off) stops a diverging coupling with
        RunFailed(Diverged) instead of returning garbage."""
        self.algorithm.initialize(self.coupling, self.time)
        start = self.time
        if control is None:
            n = int(round((stop_time - start) / step))
            out = np.zeros((n + 1, 13 + len(self.record_names)))
            out[0] = self._row()
            native = native and all(self.coupling.interpolating.values())  # the C loop always passes derivatives
            loop = NativeLoop(self.coupling, self.algorithm, self._columns, "mechanics") if native else None
            monitor = (DivergenceMonitor(bond_names(self.coupling), step, ratio=divergence_ratio)
                       if divergence_ratio and self.coupling.bonds else None)
            self.monitor = monitor
            row, batch_size = 1, 100
            while row <= n:
                first = row
                try:
                    if loop is None or row == 1:  # the first step (the start-up) always in Python
                        self.algorithm.step(self.coupling, self.time, step)
                        out[row] = self._row()
                        row += 1
                        if monitor:
                            monitor.add(self.time, *self.algorithm.bond_energies)
                    else:
                        batch = min(n + 1 - row, batch_size)
                        batch_size = min(2 * batch_size, 1000)  # small first: a divergence shows early
                        try:
                            loop.run(step, batch, out[row:row + batch])
                        finally:
                            row += loop.completed
                            if monitor:
                                monitor.add_batch(out[first:row, 0], loop.bond_energy[:row - first])
                except FmuError as error:
                    raise RunFailed(error, out[:row]) from error
                if monitor and monitor.message:
                    raise RunFailed(Diverged(monitor.message, monitor.time), out[:row])
                if progress and (loop is not None or row % 100 == 0):
                    progress(min(row / n, 1.0))
            return out
        rows = [self._row()]

        def record(t: float) -> None:
            rows.append(self._row())
            if progress and len(rows) % 100 == 0:
                progress((t - start) / (stop_time - start))

        control.after_accept = record
        native = (native and isinstance(control, AdaptiveStep) and not control.force_reject
                  and all(self.coupling.interpolating.values()))
        try:
            if not native:
                control.advance(self.coupling, start, stop_time)
            else:  # the first step (with the start-up) in Python, the rest in C with the same numbers
                t = control.advance(self.coupling, start, stop_time, max_accepted=1)
                loop = NativeLoop(self.coupling, self.algorithm, self._columns, "mechanics")

                def record_batch(batch: np.ndarray) -> None:
                    rows.extend(batch.copy())
                    if progress and len(batch):
                        progress((batch[-1, 0] - start) / (stop_time - start))

                loop.run_adaptive(control, t, stop_time, record_batch)
        except FmuError as error:
            raise RunFailed(error, np.array(rows)) from error
        return np.array(rows)

    @property
    def fmi_seconds(self) -> float:
        return sum(i.fmi_seconds for i in self.coupling.instances.values())

    def free(self) -> None:
        for instance in self.coupling.instances.values():
            instance.free()
