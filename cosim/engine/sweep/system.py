"""The SSP target of a sweep: a point of any SSP system, its names without a dot the engine's run
settings and `component.parameter` a parameter value, run through the one run path
(cosim.engine.run.run_system)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

from .points import Value
from .file import Target
from .table import statistics


@dataclass(frozen=True)
class SystemPoint:
    """Evaluates a point of an SSP system: names without a dot are the engine's settings
    (algorithm, order, step, ...: cosim.engine.settings), `component.parameter` a parameter value.
    Reports: steps, rejected, energy_residual, real_time_factor and the statistics asked for."""
    path: str
    stop_time: float | None = None
    outputs: tuple[tuple[str, tuple[str, ...]], ...] = ()
    fixed: tuple[tuple[str, Value], ...] = ()  # values every point takes (the sweep file's [sweep] set)

    def columns(self) -> list[str]:
        return ["steps", "rejected", "energy_residual", "real_time_factor",
                *[f"{s}.{c}" for c, stats in self.outputs for s in stats]]

    def structure(self):
        """The system for the length of a block (its unpacked copy removed afterwards)."""
        from ..ssp import opened
        return opened(Path(self.path))

    def recorded(self) -> list[str]:
        """The columns a run records (what `outputs` may name)."""
        from ..run import recording
        with self.structure() as structure:
            return ["time", *recording(structure)[1]]

    def files(self, points=()) -> list[Path]:
        """The files the system reads besides its .ssp archive (which holds its FMUs and values):
        an unpacked .ssd's folder; they travel to the Dask workers by content."""
        path = Path(self.path)
        return [] if path.suffix == ".ssp" else [p for p in sorted(path.parent.rglob("*")) if p.is_file() and p != path]

    def check(self, values: Mapping[str, Value]) -> None:
        """Raises ValueError (one line) when a point's names or values cannot run."""
        from ..checks import check_parameters
        from ..settings import system_settings
        values = {**dict(self.fixed), **values}
        with self.structure() as read:
            structure = self._with(read, values)
            system_settings(structure.settings, structure.experiment.step, self._settings(values))
            check_parameters(structure)

    @staticmethod
    def _settings(values: Mapping[str, Value]) -> dict[str, str]:
        # a sweep keeps every core busy with points: each steps on one thread unless an axis says
        return {"threads": "1", **{k: str(v) for k, v in values.items() if "." not in k}}

    @staticmethod
    def _with(structure, values: Mapping[str, Value]):
        from ..structure import with_parameters
        names = {c.name for c in structure.components}
        parameters: dict[str, dict] = {}
        for key, value in values.items():
            if "." in key:
                component, variable = key.split(".", 1)
                if component not in names:
                    raise ValueError(f"{key!r}: no component {component!r} (components: {', '.join(sorted(names))})")
                parameters.setdefault(component, {})[variable] = value
        return with_parameters(structure, parameters)

    def __call__(self, values: Mapping[str, Value]) -> dict[str, Value]:
        from ..outcome import RunStopped
        from ..run import run_system
        values = {**dict(self.fixed), **values}
        with self.structure() as read:
            try:
                result, report = run_system(self._with(read, values), self._settings(values), self.stop_time,
                                            source=self.path)
                status, message = "ok", ""
            except RunStopped as failed:
                result, report = failed.result, failed.report
                status, message = ("diverged" if failed.diverged else "failed"), str(failed)
        numbers = report.row()
        row = {key: numbers[key] for key in ("steps", "rejected", "energy_residual", "real_time_factor")}
        return {**row, **statistics(result, dict(self.outputs)), "status": status, "message": message}


def _system_point(target: Path, reports: tuple[str, ...], outputs: tuple, duration: float | None,
                  fixed: tuple = ()) -> SystemPoint:
    return SystemPoint(str(target), duration, outputs, fixed)


SYSTEM_REPORTS = {"energy_residual": "largest energy residual of a power bond in one macro step [J]",
                  "steps": "macro steps taken and rejected", "real_time_factor": "simulated time / wall time"}
SYSTEM = Target(SYSTEM_REPORTS, tuple(SYSTEM_REPORTS), _system_point,
                "a run setting (step, order, ...: cosim.engine.settings) or component.parameter",
                units={"energy_residual": "J", "real_time_factor": "-", "steps": "-", "step": "s"},
                what="an SSP system (.ssp, or an unpacked .ssd)")
