"""How far a run is from a reference run of the same scene, judged where people look (issue 24):
per window of time, the start-up, each load pulse with the time after it, and the steady tracking
between, each against its own scale (the reference's own change of the quantity there), beside the
largest difference over the whole run."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ..ports import DRIVES, LEGS, POSE, per_leg

if TYPE_CHECKING:
    from ..scene import Scene

START_UP = 0.2  # [s] the drives' start-up shock and its settling
AFTER = 0.2     # [s] judged with each load pulse after its end

# The tolerances every shipped scene holds at its defaults (issue 24; tests/platform/
# test_scene_accuracy.py), against the same scene at a 64th of its step:
POSE_TOLERANCE = 1e-5    # [m, rad] the pose, after its first POSE_FROM
POSE_FROM = 0.01         # [s]
WINDOW_TOLERANCE = 0.02  # the drive efforts through the start-up and each load pulse, of their own change there
STEADY_TOLERANCE = 1e-3  # in steady tracking: N m for a rotary drive, a fraction of the legs' largest static
                         # force for a linear one (steady_bound)


@dataclass(frozen=True)
class Window:
    name: str
    spans: tuple[tuple[float, float], ...]  # the time spans it covers, each [start, end)

    def mask(self, t: np.ndarray) -> np.ndarray:
        return np.any([(t >= a) & (t < b) for a, b in self.spans], axis=0)


def windows(duration: float, pulses: Sequence = ()) -> list[Window]:
    """The start-up, each load pulse (from its start to AFTER past its end) and the steady
    tracking: the rest after the start-up. Spans are half open; the last one takes the run's end."""
    end = duration + 1e-9 * max(1.0, duration)
    out = [Window("start-up", ((0.0, min(START_UP, end)),))]
    edges = sorted({(p.start, min(end, p.end + AFTER)) for p in pulses if p.start < duration})
    out += [Window(f"load pulse at {a:g} s", ((a, b),)) for a, b in edges]
    steady, t = [], START_UP
    for a, b in edges:
        if a > t:
            steady.append((t, a))
        t = max(t, b)
    if t < end:
        steady.append((t, end))
    if steady:
        out.append(Window("steady tracking", tuple(steady)))
    return out


def efforts(run: np.ndarray, effort: str) -> np.ndarray:
    """A run's time and per-leg drive efforts as the legs feel them: `<effort>_applied[i]` where the
    interface Jacobian corrects them, `<effort>[i]` otherwise, under the names `<effort>[i]`."""
    names = [f"{effort}_applied[{i}]" if f"{effort}_applied[{i}]" in run.dtype.names else f"{effort}[{i}]" for i in LEGS]
    out = np.zeros(len(run), dtype=[("time", float), *[(n, float) for n in per_leg(effort)]])
    out["time"] = run["time"]
    for target, source in zip(per_leg(effort), names):
        out[target] = run[source]
    return out


def difference(result: np.ndarray, reference: np.ndarray, names: Sequence[str], with_time: bool = False):
    """Largest |result - reference| over `names` at the result's own times, the (finer) reference
    interpolated there (and when, with_time); inf when the result stops before the reference does."""
    if not len(result) or result["time"][-1] < reference["time"][-1] - 1e-9:
        return (float("inf"), float("nan")) if with_time else float("inf")
    t = result["time"]
    gap = np.max([np.abs(result[n] - np.interp(t, reference["time"], reference[n])) for n in names], axis=0)
    k = int(np.argmax(gap))
    return (float(gap[k]), float(t[k])) if with_time else float(gap[k])


@dataclass(frozen=True)
class WindowError:
    window: str
    error: float  # largest |result - reference| in the window, the quantity's unit
    scale: float  # the reference's own change there: the largest (max - min) over `names`

    @property
    def relative(self) -> float:
        return self.error / self.scale if self.scale > 0 else float("inf")


def steady_bound(drive: str, static_forces: Sequence[float]) -> float:
    """The steady-tracking tolerance of a drive's effort in its unit: STEADY_TOLERANCE N m for a
    rotary drive, STEADY_TOLERANCE of the legs' largest static force [N] for a linear one."""
    return STEADY_TOLERANCE if drive == "pmsm" else STEADY_TOLERANCE * max(abs(f) for f in static_forces)


def tolerance_ratio(errors: Sequence[WindowError], steady: float) -> tuple[float, str]:
    """The worst window's error as a fraction of its tolerance (at most 1: within the tolerances)
    and its name: the start-up and each load pulse against WINDOW_TOLERANCE of their own change,
    the steady tracking against `steady` (steady_bound) in the effort's unit."""
    ratios = [(e.error / steady if e.window == "steady tracking" else e.relative / WINDOW_TOLERANCE, e.window)
              for e in errors]
    return max(ratios, default=(float("nan"), ""))


def window_errors(result: np.ndarray, reference: np.ndarray, names: Sequence[str],
                  spans: Sequence[Window]) -> list[WindowError]:
    """Per window, the largest difference of `names` (at the result's times, the reference
    interpolated) against the reference's own change in that window."""
    t = result["time"]
    out = []
    for window in spans:
        here, there = window.mask(t), window.mask(reference["time"])
        if not here.any() or not there.any():
            continue
        error = max(float(np.max(np.abs(result[n][here] - np.interp(t[here], reference["time"], reference[n]))))
                    for n in names)
        scale = max(float(np.ptp(reference[n][there])) for n in names)
        out.append(WindowError(window.name, error, scale))
    return out


def converged_twin(scene: "Scene") -> "Scene":
    """The scene's converged twin: the scene at a 16th of its step throughout (no finer start, no
    edge windows), on the FMI 2.0 FMUs: the same models as the FMI 3.0 ones
    (tests/models/test_fmi3.py), which take the coupling's input derivatives (at a 16th of its own
    step a run on FMI 3.0 FMUs, which extrapolate their inputs themselves, is not converged)."""
    from ...engine.tools import CONVERGED
    on_fmi2 = scene.changed({"scene.fmi": 2})
    return on_fmi2.changed({"scene.step": on_fmi2.step / CONVERGED, "coupling.startup_time": 0.0,
                            "coupling.edge_time": 0.0, "coupling.step_control": "fixed"})


def probe_duration(scene: "Scene") -> float:
    """How long a probe of a scene runs: 2 s, and past its first load pulse and the AFTER after it
    (where the efforts are judged against their own change), at most the scene's duration."""
    first = min((pulse.end + AFTER for pulse in scene.pulses if pulse.start < scene.duration), default=0.0)
    return min(scene.duration, max(2.0, first))


@dataclass(frozen=True)
class Judgement:
    """A run against its scene's converged run, by the shipped scenes' tolerances."""
    pose_error: float  # [m, rad] the largest after POSE_FROM
    ratio: float       # the efforts' worst window against its tolerance (tolerance_ratio)
    window: str        # which window that is

    @property
    def within(self) -> bool:
        return self.pose_error <= POSE_TOLERANCE and self.ratio <= 1.0


def judge(scene: "Scene", result: np.ndarray, reference: np.ndarray) -> Judgement:
    """`result` of `scene` against `reference` (its converged run over the same time): the pose
    after POSE_FROM and the drive efforts as the legs feel them, per window; a run that stops early
    is infinitely far."""
    if not len(result) or result["time"][-1] < reference["time"][-1] - 1e-9:
        return Judgement(float("inf"), float("inf"), "the run stopped early")
    from .compile import scene_values
    from .tuning import leg_plants
    late = result[result["time"] >= POSE_FROM]
    pose = difference(late, reference, [f"pose.{a}" for a in POSE])
    effort = DRIVES[scene.drive].effort[0]
    found = window_errors(efforts(result, effort), efforts(reference, effort), per_leg(effort),
                          windows(float(reference["time"][-1]), scene.pulses))
    bound = steady_bound(scene.drive, [p.static_force for p in leg_plants(scene_values(scene)[0])])
    ratio, window = tolerance_ratio(found, bound)
    return Judgement(pose, ratio, window)


@dataclass(frozen=True)
class Compared:
    """One column of a run against the reference run, in one window (or over the whole run)."""
    run: str
    column: str
    window: str
    difference: float  # largest |run - reference| there, at the run's times (the reference interpolated)
    at: float          # [s] where
    change: float      # the reference's own change there (max - min)

    @property
    def relative(self) -> float:
        return self.difference / self.change if self.change > 0 else (0.0 if self.difference == 0 else float("inf"))


def compare(reference: np.ndarray, runs: dict[str, np.ndarray], columns: Sequence[str],
            spans: Sequence[Window]) -> list[Compared]:
    """Each run's columns against the reference's, over the whole run and per window (where both
    have samples), within the time both cover: `cosim compare`."""
    out = []
    for label, run in runs.items():
        t = run["time"]
        common = (t >= reference["time"][0] - 1e-12) & (t <= reference["time"][-1] + 1e-12)
        for column in columns:
            gap = np.abs(run[column] - np.interp(t, reference["time"], reference[column]))
            for window in (Window("whole run", ((-np.inf, np.inf),)), *spans):
                here, there = window.mask(t) & common, window.mask(reference["time"])
                if here.any() and there.any():
                    k = int(np.argmax(np.where(here, gap, -1.0)))
                    out.append(Compared(label, column, window.name, float(gap[k]), float(t[k]),
                                        float(np.ptp(reference[column][there]))))
    return out
