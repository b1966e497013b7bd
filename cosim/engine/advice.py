"""Advice that has been tried: when a fixed-step run diverges, shorter steps are probed on the
same system up to a little past the divergence, and only a step that held is recommended."""

from __future__ import annotations

from .execution import Execution, RunFailed
from .observers import DivergenceMonitor
from .settings import Algorithm, FixedStep
from .structure import SystemStructure

FRACTIONS = (4, 16)  # probe a quarter, then a sixteenth of the step


def stable_step(structure: SystemStructure, algorithm: Algorithm, step: float, diverged_at: float,
                stop_time: float, ratio: float = 0.05, margin: float = 0.5) -> tuple[float | None, float, list[float]]:
    """(the first probed step that ran without diverging or failing, or None; the time probed to;
    the steps tried). Each probe runs from the start to diverged_at + margin (at most stop_time)."""
    until = min(stop_time, diverged_at + margin)
    tried = []
    for fraction in FRACTIONS:
        h = step / fraction
        tried.append(h)
        with Execution(structure, algorithm, FixedStep(h)) as execution:
            try:
                execution.run(until, [DivergenceMonitor(ratio=ratio)])
                return h, until, tried
            except RunFailed:  # diverged or an FMU failed: not a step to recommend
                continue
    return None, until, tried


def advice_text(structure: SystemStructure, algorithm: Algorithm, step: float, diverged_at: float,
                stop_time: float, ratio: float = 0.05) -> str:
    h, until, tried = stable_step(structure, algorithm, step, diverged_at, stop_time, ratio)
    if h is not None:
        return f"a probe at {h * 1e3:g} ms ran stable to t = {until:g} s: try a step of {h * 1e3:g} ms"
    return (f"probes at {', '.join(f'{t * 1e3:g}' for t in tried)} ms diverged too before t = {until:g} s: "
            f"no stable fixed step found; step doubling is worth a try but was not probed")
