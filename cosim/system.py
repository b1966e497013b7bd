"""The platform system: the mechanics FMU and six drive FMUs wired as ../shared/INTERFACES.md says,
stepped together at a fixed communication step.

This is the small fixed-step loop the drives' tests need until the master of issue 5 (scenes,
coupling strategies, step control, results) replaces it. The wiring lives in DRIVES: swapping the
drive kind changes those connections and nothing else.

Coupling (Gauss-Seidel): the drives step first from the mechanics' outputs at t, with the rate of
their reference (a backward difference of the leg references) as its input derivative; the
mechanics then steps with each drive effort interpolated linearly between its values at t and t + h
(through fmi2SetRealInputDerivatives), which keeps the coupling second order.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping

import numpy as np
from fmpy import extract

from .fmu_instance import FmuInstance
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

PoseReference = Callable[[float], np.ndarray]
Wrench = Callable[[float], np.ndarray]  # [F (3), M (3)] on the platform, base frame
WRENCH = ("load.force.x", "load.force.y", "load.force.z", "load.torque.x", "load.torque.y", "load.torque.z")


class PlatformSystem:
    """Mechanics plus six drives of one kind, initialized with the given start values."""

    def __init__(self, drive: str, mechanics_values: Mapping[str, float] | None = None,
                 drive_values: Mapping[str, float] | None = None):
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
        legs = range(1, 7)
        self._pose_ref = self.mechanics.real_group([f"pose_ref.{a}" for a in POSE])
        self._leg_outputs = self.mechanics.real_group(
            [name.format(i=i) for i in legs for name in (wiring.reference[0], wiring.position[0], wiring.velocity[0])])
        self._effort_names = [wiring.effort[1].format(i=i) for i in legs]
        self._efforts_in = self.mechanics.real_group(self._effort_names)
        self._drive_inputs = [d.real_group([wiring.reference[1], wiring.position[1], wiring.velocity[1]])
                              for d in self.drives]
        self._drive_efforts = [d.real_group([wiring.effort[0]]) for d in self.drives]
        self.pose = self.mechanics.real_group([f"pose.{a}" for a in POSE])
        self._wrench = self.mechanics.real_group(list(WRENCH))
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
            per_drive = np.array([g.read() for g in self._record_drives])  # 6 x outputs
            parts.append(per_drive.T.ravel())
        return np.concatenate(parts) if parts else np.zeros(0)

    @property
    def time(self) -> float:
        return self.mechanics.time

    def run(self, stop_time: float, step: float, pose_ref: PoseReference, wrench: Wrench | None = None) -> np.ndarray:
        """Steps to stop_time; returns rows of time, pose_ref (6), pose (6) and the recorded
        outputs at every communication point."""
        n = int(round((stop_time - self.time) / step))
        out = np.zeros((n + 1, 13 + len(self.record_names)))
        efforts = np.array([g.read()[0] for g in self._drive_efforts])
        self._pose_ref.write(pose_ref(self.time))
        if wrench:
            self._wrench.write(wrench(self.time))
        out[0] = np.r_[self.time, self._pose_ref.values, self.pose.read(), self._recorded()]
        previous_refs = self._leg_outputs.read().reshape(6, 3)[:, 0].copy()
        reference_input = [self.wiring.reference[1]]
        for row in range(1, n + 1):
            legs = self._leg_outputs.read().reshape(6, 3)
            reference_rates = (legs[:, 0] - previous_refs) / step  # backward difference
            previous_refs = legs[:, 0].copy()
            new_efforts = np.empty(6)
            for k, drive in enumerate(self.drives):
                self._drive_inputs[k].write(legs[k])
                drive.set_input_derivatives(reference_input, [reference_rates[k]])
                drive.do_step(step)
                new_efforts[k] = self._drive_efforts[k].read()[0]
            self._efforts_in.write(efforts)
            self.mechanics.set_input_derivatives(self._effort_names, (new_efforts - efforts) / step)
            self.mechanics.do_step(step)
            efforts = new_efforts
            self._efforts_in.write(efforts)
            self._pose_ref.write(pose_ref(self.time))
            if wrench:
                self._wrench.write(wrench(self.time))
            out[row] = np.r_[self.time, self._pose_ref.values, self.pose.read(), self._recorded()]
        return out

    def free(self) -> None:
        for instance in (self.mechanics, *self.drives):
            instance.free()
