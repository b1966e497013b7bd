"""`python -m cosim advise SCENE --tolerance TOL`: which effects, drive fidelity and macro step does
a scene really need? Short probes of the scene against a converged reference; the cheapest
candidate whose pose error stays under the tolerance is recommended, every candidate listed with
its measured error and cost.

The reference is the scene with every effect on, its own drive fidelity, at a quarter of its step
(its convergence is shown: the difference to half the step must be well under the tolerance).
Candidates: macro steps of 1/2, 1, 2 and 4 times the scene's; each subset of the mechanics' effect
switches (motor systems, actuator inertia, friction); the drive's fidelity (PMSM: ideal or averaged
inverter; linear motor: with or without its electrical dynamics). A candidate the divergence
monitor stops is listed as diverged, never recommended. Meng's Table 5 asks one instance of this
question: what leaving out the motor systems costs.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..engine.observers import TaskProgress
from .runner import SceneFailed, run_scene
from .scene import Scene
from .ports import POSE

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
    wall: float = float("nan")      # [s] stepping the probe (the faster of two runs if it passed)
    macro_steps: int = 0
    diverged: str | None = None

    @property
    def label(self) -> str:
        off = ", ".join(e.split(".")[1] for e in self.effects_off) or "-"
        return f"{self.step * 1e3:g} ms | off: {off} | {self.fidelity}"


def _variant(scene: Scene, step: float, effects_off, fidelity: str, duration: float) -> Scene:
    drive = {**scene.drive_parameters, **FIDELITY[scene.drive][fidelity]}
    mechanics = {**scene.mechanics_parameters, **{e: False for e in effects_off}}
    return dataclasses.replace(scene, step=step, duration=duration, mechanics_parameters=mechanics,
                               drive_parameters=drive, step_control="fixed")


def _pose_difference(result: np.ndarray, reference: np.ndarray) -> float:
    return max(float(np.abs(np.interp(reference["time"], result["time"], result[f"pose.{a}"])
                            - reference[f"pose.{a}"]).max()) for a in POSE)


def advise(scene: Scene, tolerance: float, probe: float = 2.0) -> tuple[list[Candidate], dict]:
    duration = min(scene.duration, probe)
    own = next(name for name, values in FIDELITY[scene.drive].items()
               if all(scene.drive_parameters.get(k, v if name.startswith(("averaged", "electrical")) else None) == v
                      for k, v in values.items()))
    reference, _ = run_scene(_variant(scene, scene.step / 4, (), own, duration))
    half, _ = run_scene(_variant(scene, scene.step / 2, (), own, duration))
    convergence = _pose_difference(half, reference)
    candidates = []
    subsets = [c for r in range(len(EFFECTS) + 1) for c in itertools.combinations(EFFECTS, r)]
    plan = list(itertools.product((0.5, 1, 2, 4), subsets, FIDELITY[scene.drive]))
    progress = TaskProgress("advise", len(plan))
    for factor, off, fidelity in plan:
        candidate = Candidate(scene.step * factor, off, fidelity)
        variant = _variant(scene, candidate.step, off, fidelity, duration)
        try:
            result, report = run_scene(variant)
            candidate.error = _pose_difference(result, reference)
            candidate.macro_steps = report.macro_steps
            candidate.wall = report.wall
            if candidate.error <= tolerance:  # timing decides among these: measure again, keep the faster
                candidate.wall = min(candidate.wall, run_scene(variant)[1].wall)
        except SceneFailed as failed:
            candidate.diverged = failed.report.failure
            candidate.wall = failed.report.wall
        candidates.append(candidate)
        progress.advance(candidate.label)
    return candidates, dict(convergence=convergence, duration=duration, own_fidelity=own)


def recommend(candidates: list[Candidate], tolerance: float) -> Candidate | None:
    good = [c for c in candidates if c.diverged is None and c.error <= tolerance]
    return min(good, key=lambda c: c.wall) if good else None


def write_csv(candidates: list[Candidate], path: Path) -> Path:
    """Every candidate: step, effects off, fidelity, pose error, wall time, macro steps, divergence."""
    import csv
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["step_ms", "effects_off", "fidelity", "pose_error", "wall_s", "macro_steps", "diverged"])
        for c in candidates:
            writer.writerow([f"{c.step * 1e3:g}", " ".join(c.effects_off), c.fidelity, repr(c.error), repr(c.wall),
                             c.macro_steps, c.diverged or ""])
    return path


def text(scene: Scene, tolerance: float, candidates: list[Candidate], info: dict) -> str:
    """The candidates within the tolerance (cheapest first) as a table, the rest in a line each."""
    lines = [f"{scene.name}: probes of {info['duration']:g} s against a reference at {scene.step / 4 * 1e3:g} ms "
             f"(every effect on, {info['own_fidelity']}); the reference's own convergence (half its step "
             f"against it): {info['convergence']:.1e}"]
    good = sorted((c for c in candidates if not c.diverged and c.error <= tolerance), key=lambda c: c.wall)
    missed = sorted((c for c in candidates if not c.diverged and not c.error <= tolerance), key=lambda c: c.error)
    diverged = [c for c in candidates if c.diverged]
    if good:
        lines.append(f"within pose error {tolerance:g} ({len(good)} of {len(candidates)}, cheapest first):")
        lines.append(f"  {'candidate':<62} {'pose error':>11} {'wall [s]':>9} {'steps':>7}")
        lines += [f"  {c.label:<62} {c.error:>11.2e} {c.wall:>9.3f} {c.macro_steps:>7}" for c in good]
    if missed:
        lines.append(f"{len(missed)} ran but missed the tolerance (closest: {missed[0].label}, {missed[0].error:.1e})")
    if diverged:
        lines.append(f"{len(diverged)} diverged (stopped by the divergence monitor, never recommended)")
    best = recommend(candidates, tolerance)
    if info["convergence"] > 0.1 * tolerance:
        lines.append(f"warning: the tolerance {tolerance:g} is within ten times the reference's own error; "
                     "the ranking below it is not reliable")
    lines.append(f"recommended for pose error <= {tolerance:g}: {best.label} ({best.error:.1e}, {best.wall:.3f} s)"
                 if best else f"no candidate keeps the pose error under {tolerance:g}: keep the full model at a smaller step")
    return "\n".join(lines)
