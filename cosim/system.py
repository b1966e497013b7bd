"""The platform system: the mechanics FMU and six drive FMUs wired as ../shared/INTERFACES.md says,
stepped together at a fixed communication step.

The wiring lives in DRIVES: swapping the drive kind changes those connections and nothing else.
Coupling: cosim.coupling's Gauss-Seidel with first-order extrapolation (by default): the drives
step first, their inputs extrapolated linearly from the mechanics' last two samples (so a drive
also sees the rate of its leg reference); the mechanics then steps with each drive effort
interpolated linearly between its values at t and t + h. cosim.runner runs a scene on it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping

import numpy as np
from fmpy import extract

from .coupling import Bond, Connection, Coupling, GaussSeidel, Jacobi
from .fmu_instance import FmuError, FmuInstance
from .fmus import fmu_path

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
    """An FMU failed mid-run: `error` says which instance, call and time; `result` holds the rows
    computed up to the last good communication point."""

    def __init__(self, error: FmuError, result: np.ndarray):
        super().__init__(str(error))
        self.error, self.result = error, result


PoseReference = Callable[[float], np.ndarray]
Wrench = Callable[[float], np.ndarray]  # [F (3), M (3)] on the platform, base frame
WRENCH = ("load.force.x", "load.force.y", "load.force.z", "load.torque.x", "load.torque.y", "load.torque.z")


class PlatformSystem:
    """Mechanics plus six drives of one kind, initialized with the given start values."""

    def __init__(self, drive: str, mechanics_values: Mapping[str, float] | None = None,
                 drive_values: Mapping[str, float] | None = None, order: int = 1,
                 algorithm: str = "gauss-seidel"):
        if drive not in DRIVES:
            raise ValueError(f"unknown drive kind '{drive}' (known: {', '.join(DRIVES)})")
        self.wiring = wiring = DRIVES[drive]
        mechanics_path, drive_path = fmu_path("mechanics"), fmu_path(wiring.fmu)
        drive_unzip = extract(str(drive_path))
        self.mechanics = FmuInstance(mechanics_path, "mechanics")
        self.drives = [FmuInstance(drive_path, f"{drive}{i}", unzip_dir=drive_unzip) for i in range(1, 7)]
        self.mechanics.initialize(dict(mechanics_values or {}))
        for d in self.drives:
            d.initialize(dict(drive_values or {}))
        instances = {"mechanics": self.mechanics, **{d.name: d for d in self.drives}}
        connections, bonds = [], []
        for i, d in enumerate(self.drives, start=1):
            for output, drive_input in (wiring.reference, wiring.position, wiring.velocity):
                connections.append(Connection(("mechanics", output.format(i=i)), (d.name, drive_input)))
            connections.append(Connection((d.name, wiring.effort[0]), ("mechanics", wiring.effort[1].format(i=i))))
            bonds.append(Bond(effort=connections[-1], flow=connections[-2]))  # torque x speed, force x velocity
        self.coupling = Coupling(instances, connections, bonds)
        if algorithm == "jacobi":
            self.algorithm = Jacobi(order)
        else:
            self.algorithm = GaussSeidel(order, [d.name for d in self.drives] + ["mechanics"])
        self._pose_ref = self.mechanics.real_group([f"pose_ref.{a}" for a in POSE])
        self._wrench = self.mechanics.real_group(list(WRENCH))
        self.pose = self.mechanics.real_group([f"pose.{a}" for a in POSE])
        self.record_names: list[str] = []
        self._record_mechanics = None
        self._record_drives: list = []

    def record(self, mechanics_outputs: list[str], drive_outputs: list[str]) -> None:
        """Also record these mechanics outputs and, for each drive, these outputs (columns
        `<name>` and `<drive output>[i]`)."""
        self._record_mechanics = self.mechanics.real_group(mechanics_outputs) if mechanics_outputs else None
        self._record_drives = [d.real_group(drive_outputs) for d in self.drives] if drive_outputs else []
        self.record_names = [*mechanics_outputs, *[f"{n}[{i}]" for n in drive_outputs for i in range(1, 7)]]

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

    def run(self, stop_time: float, step: float, pose_ref: PoseReference, wrench: Wrench | None = None,
            progress: Callable[[float], None] | None = None) -> np.ndarray:
        """Steps to stop_time; returns rows of time, pose_ref (6), pose (6) and the recorded
        outputs (column_names) at every communication point. pose_ref and the wrench are held over
        each step. `progress` is called with the fraction done every 100 steps."""
        n = int(round((stop_time - self.time) / step))
        out = np.zeros((n + 1, 13 + len(self.record_names)))

        def set_external(t: float) -> None:
            self._pose_ref.write(pose_ref(t))
            if wrench:
                self._wrench.write(wrench(t))

        set_external(self.time)
        self.algorithm.initialize(self.coupling, self.time)
        out[0] = np.r_[self.time, self._pose_ref.values, self.pose.read(), self._recorded()]
        for row in range(1, n + 1):
            try:
                self.algorithm.step(self.coupling, self.time, step)
            except FmuError as error:
                raise RunFailed(error, out[:row]) from error
            set_external(self.time)
            out[row] = np.r_[self.time, self._pose_ref.values, self.pose.read(), self._recorded()]
            if progress and row % 100 == 0:
                progress(row / n)
        return out

    @property
    def fmi_seconds(self) -> float:
        return sum(i.fmi_seconds for i in (self.mechanics, *self.drives))

    def free(self) -> None:
        for instance in (self.mechanics, *self.drives):
            instance.free()
