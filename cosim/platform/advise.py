"""`python -m cosim advise SCENE --tolerance TOL`: which effects, drive fidelity and macro step does
a scene really need? Short probes of the scene against a converged reference; the cheapest
candidate whose pose error stays under the tolerance and whose drive efforts (torques or forces,
through the start-up and any impact) stay within `effort_tolerance` of their peak is recommended,
every candidate listed with its measured errors and cost. The probes are points of one sweep
(cosim.engine.sweep), so they run on every core.

The reference is the scene with every effect on, its own drive fidelity, at a quarter of its step
(its convergence is shown: the difference to half the step must be well under the tolerance).
Candidates: macro steps of 1/2, 1, 2 and 4 times the scene's; each subset of the mechanics' effect
switches (motor systems, actuator inertia, friction); the drive's fidelity (PMSM: ideal or averaged
inverter; linear motor: with or without its electrical dynamics); and, for the full model at 1, 2
and 4 times the step, the interface-Jacobian coupling (where the scene extrapolates and does not
use it already). A candidate the divergence
monitor stops is listed as diverged, never recommended. Meng's Table 5 asks one instance of this
question: what leaving out the motor systems costs.
"""

from __future__ import annotations

import itertools
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..engine.files import write_text
from ..engine.sweep import run_sweep
from .ports import POSE
from .run.runner import run_scene
from .scene import Scene
from .run.sweep import ScenePoint

EFFECTS = ("effects.motor_inertia", "effects.actuator_inertia", "effects.friction")
FIDELITY = {"pmsm": {"averaged inverter": {"inverter.model": 2}, "ideal inverter": {"inverter.model": 1}},
            "linear": {"electrical dynamics": {"effects.electrical": True},
                       "ideal force source": {"effects.electrical": False}}}


@dataclass
class Candidate:
    step: float
    effects_off: tuple[str, ...]
    fidelity: str
    error: float = float("nan")     # largest pose difference to the reference [m, rad]
    effort_error: float = float("nan")  # largest drive effort difference to the reference / its peak
    effort_error_time: float = float("nan")  # [s] when it occurs
    window_error: float = float("nan")  # the efforts' worst window (start-up, a load pulse, steady), relative to
    window_error_at: str = ""           # their own change there, and which window
    wall: float = float("nan")      # [s] stepping the probe (the faster of two runs if it passed)
    macro_steps: int = 0
    diverged: str | None = None
    gains: str = "scene's"  # or "designed": the drives' loops designed for this candidate's reduced plant
    interface_jacobian: bool = False  # the drives' slopes applied in the mechanics

    @property
    def label(self) -> str:
        off = ", ".join(e.split(".")[1] for e in self.effects_off) or "-"
        coupling = " | interface Jacobian" if self.interface_jacobian else ""
        return f"{self.step * 1e3:g} ms | off: {off} | {self.fidelity} | {self.gains} gains{coupling}"


def fidelities(scene: Scene) -> dict[str, dict]:
    """The drive models a candidate may choose: our drive's, or the user's drive FMU as it is."""
    return {f"{scene.drive_fmu.name} as it is": {}} if scene.drive_fmu else FIDELITY[scene.drive]


def _variant(scene: Scene, step: float, fidelity: str, duration: float) -> Scene:
    """The scene at a fixed `step` for `duration`, its drives at `fidelity` (the reference runs)."""
    return scene.changed({"scene.step": step, "scene.duration": duration, "coupling.step_control": "fixed",
                          **{f'drive.parameters."{k}"': v for k, v in fidelities(scene)[fidelity].items()}})


def _point(scene: Scene, factor: float, effects_off, fidelity: str, interface_jacobian: bool, redesign: bool) -> dict:
    """A candidate as a sweep point: overrides at the scene's keys; with `redesign`, a reduced
    model's drives get loops designed for its plant (tuning "auto")."""
    redesign = redesign and scene.drive_fmu is None  # a user's drive keeps its own gains
    point = {"scene.step": scene.step * factor, "drive.tuning": "auto" if redesign and effects_off else scene.tuning,
             "coupling.interface_jacobian": interface_jacobian or scene.interface_jacobian}
    for effect in EFFECTS:
        point[f'mechanics.parameters."{effect}"'] = False if effect in effects_off else \
            scene.mechanics_parameters.get(effect, True)
    point.update({f'drive.parameters."{k}"': v for k, v in fidelities(scene)[fidelity].items()})
    if interface_jacobian and not scene.interface_jacobian:
        # the slopes put the drives' damping into the mechanics: RK4's stability interval (2.8) holds
        # it at twice the step where Heun's (2), which a shipped scene's mechanics may run, does not
        point['mechanics.parameters."solver.method"'] = 1
    return point


def _pose_difference(result: np.ndarray, reference: np.ndarray) -> float:
    return max(float(np.abs(np.interp(reference["time"], result["time"], result[f"pose.{a}"])
                            - reference[f"pose.{a}"]).max()) for a in POSE)


def advise(scene: Scene, tolerance: float, probe: float | None = None, effort_tolerance: float = 0.01,
           workers: int | None = None, redesign: bool = True) -> tuple[list[Candidate], dict]:
    """Every candidate's errors against the reference and its cost; workers as in
    cosim.engine.sweep.run_sweep (None: every core). redesign: a candidate that leaves effects out
    runs its drives with loops designed for its reduced plant (cosim.platform.run.tuning), as a
    designer would; the full-model candidates keep the scene's own gains."""
    # by default the probe lasts 2 s and reaches past the first load pulse and the 0.2 s after it,
    # where the efforts are judged against their own change
    from .run.accuracy import probe_duration
    duration = min(scene.duration, probe) if probe is not None else probe_duration(scene)
    own = next(name for name, values in fidelities(scene).items()
               if all(scene.drive_parameters.get(k, v if name.startswith(("averaged", "electrical")) else None) == v
                      for k, v in values.items()))
    reference, _ = run_scene(_variant(scene, scene.step / 4, own, duration))
    half, _ = run_scene(_variant(scene, scene.step / 2, own, duration))
    convergence = _pose_difference(half, reference)
    subsets = [c for r in range(len(EFFECTS) + 1) for c in itertools.combinations(EFFECTS, r)]
    plan = list(itertools.product((0.5, 1, 2, 4), subsets, fidelities(scene), (False,)))
    if scene.algorithm.order > 0 and not scene.interface_jacobian:
        plan += list(itertools.product((1, 2, 4), [()], fidelities(scene), (True,)))
    evaluate = ScenePoint(str(scene.path), ("pose_error", "effort_error", "window_error", "steps", "stepping_wall"),
                          base=(*scene.overrides.items(), ("scene.duration", duration),
                                ("coupling.step_control", "fixed")),
                          reference=reference)
    points = [_point(scene, *candidate, redesign) for candidate in plan]

    def sweep(chosen: list[dict], name: str) -> list[dict]:
        with tempfile.TemporaryDirectory() as out:
            return run_sweep(name, chosen, evaluate, evaluate.columns(), Path(out), workers=workers).rows

    rows = sweep(points, "advise")
    candidates = []
    for (factor, off, fidelity, slopes), row in zip(plan, rows):
        candidate = Candidate(scene.step * factor, off, fidelity,
                              gains="designed" if points[len(candidates)]["drive.tuning"] == "auto" else "scene's",
                              interface_jacobian=slopes or scene.interface_jacobian)
        if row["status"] == "ok":
            candidate.error, candidate.effort_error = row["pose_error"], row["effort_error"]
            candidate.effort_error_time = row["effort_error_time"]
            candidate.window_error, candidate.window_error_at = row["window_error"], row["window_error_at"]
            candidate.macro_steps, candidate.wall = int(row["steps"]), row["stepping_wall"]
        else:
            candidate.diverged = row["message"]
            candidate.wall = row.get("stepping_wall", float("nan"))
        candidates.append(candidate)
    passed = [k for k, c in enumerate(candidates) if within(c, tolerance, effort_tolerance)]
    if passed:  # timing decides among these: measure again, keep the faster
        for k, row in zip(passed, sweep([points[k] for k in passed], "advise (timing)")):
            if row["status"] == "ok":
                candidates[k].wall = min(candidates[k].wall, row["stepping_wall"])
    return candidates, dict(convergence=convergence, duration=duration, own_fidelity=own,
                            effort_tolerance=effort_tolerance)


def within(candidate: Candidate, tolerance: float, effort_tolerance: float = 0.01) -> bool:
    """The pose within `tolerance`, the drive efforts within `effort_tolerance` of their peak and, in
    every window (the start-up, each load pulse with the 0.2 s after it, steady tracking), of their
    own change there: an error that hides in the peak's shadow does not pass."""
    return candidate.diverged is None and candidate.error <= tolerance and \
        candidate.effort_error <= effort_tolerance and candidate.window_error <= effort_tolerance


def recommend(candidates: list[Candidate], tolerance: float, effort_tolerance: float = 0.01) -> Candidate | None:
    good = [c for c in candidates if within(c, tolerance, effort_tolerance)]
    return min(good, key=lambda c: c.wall) if good else None


def write_candidates(candidates: list[Candidate], path: Path) -> Path:
    """Every candidate: step, effects off, fidelity, pose error, wall time, macro steps, divergence."""
    import csv
    import io
    text = io.StringIO(newline="")
    writer = csv.writer(text)
    writer.writerow(["step_ms", "effects_off", "fidelity", "gains", "interface_jacobian", "pose_error",
                     "effort_error", "window_error", "window_error_at", "wall_s", "macro_steps", "diverged"])
    for c in candidates:
        writer.writerow([f"{c.step * 1e3:g}", " ".join(c.effects_off), c.fidelity, c.gains,
                         str(c.interface_jacobian).lower(), repr(c.error),
                         repr(c.effort_error), repr(c.window_error), c.window_error_at, repr(c.wall),
                         c.macro_steps, c.diverged or ""])
    return write_text(path, text.getvalue(), "the candidates")


def text(scene: Scene, tolerance: float, candidates: list[Candidate], info: dict) -> str:
    """The candidates within the tolerances (cheapest first) as a table, the rest in a line each."""
    effort_tolerance = info.get("effort_tolerance", 0.01)
    lines = [f"{scene.name}: probes of {info['duration']:g} s against a reference at {scene.step / 4 * 1e3:g} ms "
             f"(every effect on, {info['own_fidelity']}); the reference's own convergence (half its step "
             f"against it): {info['convergence']:.1e}"]
    good = sorted((c for c in candidates if within(c, tolerance, effort_tolerance)), key=lambda c: c.wall)
    missed = sorted((c for c in candidates if not c.diverged and not within(c, tolerance, effort_tolerance)),
                    key=lambda c: c.error)
    diverged = [c for c in candidates if c.diverged]
    criteria = (f"pose error {tolerance:g} and drive effort error {100 * effort_tolerance:g} % of its peak and of its "
                "own change in each window")
    if good:
        lines.append(f"within {criteria} ({len(good)} of {len(candidates)}, cheapest first):")
        lines.append(f"  {'candidate':<98} {'pose error':>11} {'effort err':>10} {'window':>8} {'wall [s]':>9} "
                     f"{'steps':>7}")
        lines += [f"  {c.label:<98} {c.error:>11.2e} {100 * c.effort_error:>9.2f}% {100 * c.window_error:>7.2f}% "
                  f"{c.wall:>9.3f} {c.macro_steps:>7}" for c in good]
    if missed:
        efforts = sorted((c for c in missed if c.error <= tolerance), key=lambda c: max(c.effort_error, c.window_error))
        lines.append(f"{len(missed)} ran but missed a tolerance (closest in pose: {missed[0].label}, "
                     f"{missed[0].error:.1e})")
        if efforts:
            c = efforts[0]
            lines.append(f"{len(efforts)} of them keep the pose but not the drive efforts (closest: {c.label}, "
                         f"{100 * c.effort_error:.1f} % of the peak at t = {c.effort_error_time:.4f} s, "
                         f"{100 * c.window_error:.1f} % of their change in the {c.window_error_at or 'worst'} window)")
    if diverged:
        lines.append(f"{len(diverged)} diverged (stopped by the divergence monitor, never recommended)")
    best = recommend(candidates, tolerance, effort_tolerance)
    if info["convergence"] > 0.1 * tolerance:
        lines.append(f"warning: the tolerance {tolerance:g} is within ten times the reference's own error; "
                     "the ranking below it is not reliable")
    lines.append(f"recommended for {criteria}: {best.label} ({best.error:.1e}, {100 * best.effort_error:.2f} %, "
                 f"{100 * best.window_error:.2f} % in its worst window, {best.wall:.3f} s)" if best else
                 f"no candidate keeps {criteria}: keep the full model at a smaller step")
    return "\n".join(lines)
