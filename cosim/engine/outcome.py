"""What a run gives back (cosim.engine.run makes them): its `Outcome` (the results, what the
execution measured, what the FMUs logged, and the failure if the run stopped early), the
`Report` that sums it up as a command prints it, and `RunStopped`, raised with both for a run that
stopped part way."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .execution import RunFailed
from .fmi import LogMessage
from .observers import Diverged, Observer
from .realtime import Pacing
from .results import message_kinds


@dataclass
class Outcome:
    """One run of a system: the results (named columns) up to where it got, per macro step the
    largest energy residual of a bond and the step taken, the rejected steps, the wall time of the
    stepping and the part of it inside the FMUs (in all and per instance), every FMU message, per
    bond the largest residual of a step, the observers that watched, and the failure (None for a
    run that reached its end)."""
    name: str
    result: np.ndarray
    energy_residuals: np.ndarray
    steps: np.ndarray
    rejected: int
    wall: float
    fmi_seconds: float
    control: str  # the step control's name: fixed, doubling, energy
    messages: list[tuple[str, LogMessage]] = field(default_factory=list)
    bond_residuals: dict[str, float] = field(default_factory=dict)  # [J]
    observers: list[Observer] = field(default_factory=list)
    failure: RunFailed | None = None
    fmi_seconds_by_instance: dict[str, float] = field(default_factory=dict)  # of the stepping, per instance
    pacing: Pacing | None = None  # a real-time run's lateness, stream and live input

    @property
    def warnings(self) -> list[str]:
        return [m.text for _, m in self.messages if m.status == "warning"]

    @property
    def simulated(self) -> float:
        return float(self.result["time"][-1] - self.result["time"][0]) if len(self.result) else 0.0

    @property
    def diverged(self) -> bool:
        return self.failure is not None and isinstance(self.failure.error, Diverged)

    def observer(self, kind: type) -> Observer | None:
        """The first observer of this kind that watched the run."""
        return next((o for o in self.observers if isinstance(o, kind)), None)


@dataclass
class Report:
    """A run's summary (what `python -m cosim run` prints): the application's own lines (an
    application's report adds `measured` after the energy line and `notes` after the warnings)."""
    name: str
    macro_steps: int
    simulated: float
    wall: float
    fmi_seconds: float
    largest_energy_residual: float  # [J] over the power bonds, per macro step
    warnings: list[str]
    failure: str | None = None
    rejected_steps: int = 0
    step_control: str = "fixed"
    warning_kinds: list[tuple[int, str]] = field(default_factory=list)  # (count, kind), most first
    log: Path | None = None  # where every FMU message was written
    messages: list[tuple[str, LogMessage]] = field(default_factory=list, repr=False)  # everything logged
    remarks: list[str] = field(default_factory=list)  # what the run chose that its input did not say
    fmi_seconds_by_instance: dict[str, float] = field(default_factory=dict, repr=False)  # of the stepping
    pacing: Pacing | None = field(default=None, repr=False)  # a real-time run's lateness, stream, live input
    bonds: int = 0  # the power bonds whose energy residual is measured (none: the line is left out)

    @classmethod
    def of(cls, outcome: Outcome, simulated: float | None = None, **extra) -> "Report":
        """The report of an outcome (simulated: the time the results cover, if thinned)."""
        return cls(outcome.name, len(outcome.steps), outcome.simulated if simulated is None else simulated,
                   outcome.wall, outcome.fmi_seconds, float(np.max(outcome.energy_residuals, initial=0.0)),
                   outcome.warnings, str(outcome.failure) if outcome.failure else None, outcome.rejected,
                   outcome.control, message_kinds(outcome.messages), messages=outcome.messages,
                   fmi_seconds_by_instance=dict(outcome.fmi_seconds_by_instance), pacing=outcome.pacing,
                   bonds=len(outcome.bond_residuals), **extra)

    @property
    def real_time_factor(self) -> float:
        return self.simulated / self.wall if self.wall > 0 else float("nan")

    @property
    def busy(self) -> float:
        """The stepping's wall time [s], less what a paced run slept until its deadlines."""
        return self.wall - (self.pacing.waited if self.pacing is not None else 0.0)

    @property
    def master_share(self) -> float:
        """The stepping's share outside the FMUs (a paced run's sleep not counted)."""
        return 1.0 - self.fmi_seconds / self.busy if self.busy > 0 else 0.0

    def measured(self) -> list[str]:
        return []

    def notes(self) -> list[str]:
        return list(self.remarks)

    def text(self) -> str:
        steps = (f"{self.macro_steps} output points of one solver (CVODE), no macro step" if self.step_control == "cvode"
                 else f"{self.macro_steps} macro steps" + (f" ({self.step_control} step control, {self.rejected_steps} "
                                                           "rejected)" if self.step_control != "fixed" else ""))
        lines = [f"{self.name}: {self.simulated:g} s simulated in {self.wall:.2f} s wall, {steps}, "
                 f"real-time factor {self.real_time_factor:.1f}, " + (
                     f"{100 * self.busy / self.wall:.0f} % of the wall time stepping (the rest waiting for deadlines), "
                     f"{100 * self.master_share:.0f} % of the stepping in the master outside the FMUs"
                     if self.pacing is not None and self.pacing.waited > 0 else
                     f"{100 * self.master_share:.0f} % of the wall time in the master outside the FMUs"),
                 *([f"largest energy residual of a power bond in one step: {self.largest_energy_residual:.2e} J"]
                   if self.bonds and self.step_control != "cvode" else []),  # (no bond, or no coupling: nothing to say)
                 *(self.pacing.lines() if self.pacing else []), *self.measured()]
        if self.warnings:
            kinds = "; ".join(f"{n} x {kind}" for n, kind in self.warning_kinds[:3])
            more = f"; {len(self.warning_kinds) - 3} more kinds" if len(self.warning_kinds) > 3 else ""
            lines.append(f"{len(self.warnings)} warnings from the FMUs ({kinds}{more}), first: {self.warnings[0]}"
                         + (f"; all in {self.log}" if self.log else ""))
        lines += self.notes()
        if self.failure:
            lines.append(f"FAILED: {self.failure}")
        return "\n".join(lines)

    def row(self) -> dict[str, float]:
        """The run's numbers as a sweep's row has them."""
        return {"steps": self.macro_steps, "rejected": self.rejected_steps, "energy_residual": self.largest_energy_residual,
                "real_time_factor": self.real_time_factor, "stepping_wall": self.wall,
                **(self.pacing.row() if self.pacing else {})}


class RunStopped(RuntimeError):
    """A run that stopped before its end, as a command reports it: its report (which says why),
    the results up to then, and whether the coupling diverged (rather than an FMU failing)."""

    def __init__(self, report: Report, result: np.ndarray, diverged: bool = False):
        super().__init__(report.failure)
        self.report, self.result, self.diverged = report, result, diverged
