"""A scene's signal FMUs run alone, through the engine's one run path: the trajectory FMU (`play`,
the one evaluation of a scene's signals outside a run: its reference pose and load) and the
cueing FMU (`play_cueing`: a vehicle's motion through the washout, the platform left out)."""

from __future__ import annotations

import numpy as np

from ...engine import Algorithm, Component, Experiment, FixedStep, SystemStructure, fmu_path
from ...engine.run import Plan, run
from ..ports import POSE
from ..scene import Scene, SceneError
from ..scene.signals import scene_trajectory

TRAJECTORY_OUTPUTS = (*(f"pose_ref.{a}" for a in POSE), *(f"load.force.{a}" for a in "xyz"))
CUEING_OUTPUTS = (*(f"pose_ref.{a}" for a in POSE), "tilt.roll", "tilt.pitch",
                  *(f"vehicle.{q}.{a}" for q in ("specific_force", "angular_rate") for a in "xyz"))


def alone(name: str, values: dict, duration: float, step: float, outputs: tuple[str, ...]) -> np.ndarray:
    """One of our FMUs with these start values run alone for `duration` at `step`: its results.
    Raises what the FMU refuses (a bad table: its file and line) as the engine's error, a run
    that stops part way as RunStopped."""
    system = SystemStructure(name, [Component(name, fmu_path(name), values)], [],
                             experiment=Experiment(0.0, duration, step))
    return run(Plan(system, Algorithm("jacobi", 0), FixedStep(step), duration, [(name, n) for n in outputs],
                    divergence=None))[0]


def _columns(result: np.ndarray, name: str, outputs: tuple[str, ...]) -> np.ndarray:
    return np.column_stack([result[f"{name}.{n}"] for n in outputs])


def play(trajectory_values: dict, duration: float, step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The trajectory FMU with these start values run alone for `duration` at `step`: times,
    reference poses (n x 6), base-frame load forces (n x 3)."""
    result = alone("trajectory", trajectory_values, duration, step, TRAJECTORY_OUTPUTS)
    return (result["time"], _columns(result, "trajectory", TRAJECTORY_OUTPUTS[:6]),
            _columns(result, "trajectory", TRAJECTORY_OUTPUTS[6:]))


def reference_motion(scene: Scene, samples: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The scene's reference pose and base-frame load force at `samples` evenly spaced times over
    its duration, from its trajectory FMU run alone (tables included): times, poses (n x 6),
    forces (n x 3)."""
    return play(scene_trajectory(scene), scene.duration, scene.duration / (samples - 1))


def play_cueing(cueing_values: dict, duration: float, step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                                             np.ndarray]:
    """The cueing FMU with these start values run alone for `duration` at `step` (a vehicle's
    motion through the classical washout, the platform's response left out): times, the pose
    reference (n x 6), the tilt (n x 2: roll, pitch) and the vehicle's motion it took (n x 6)."""
    result = alone("cueing", cueing_values, duration, step, CUEING_OUTPUTS)
    return (result["time"], *(_columns(result, "cueing", names)
                              for names in (CUEING_OUTPUTS[:6], CUEING_OUTPUTS[6:8], CUEING_OUTPUTS[8:])))


WORKSPACE_STEP = 0.01  # [s] the reference's samples a workspace check takes (at most its scene's step apart)
TILT_IMPOSSIBLE = np.pi / 2  # [rad] a leg turned past a right angle from its neutral direction: no joint allows it
WORKSPACE_SAMPLES = 1e6  # the most a workspace check plays


def table_row(path, t: float) -> tuple[list[str], int | None]:
    """A trajectory table's columns and the line (1-based) of its first row at or after t [s] (None:
    no such row, or the file unreadable); its comments and blank lines passed over."""
    columns: list[str] = []
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as file:
            for number, line in enumerate(file, 1):
                if not line.strip() or line.lstrip().startswith("#"):
                    continue
                if not columns:
                    columns = [c.strip() for c in line.split(",")]
                    continue
                try:
                    if float(line.split(",", 1)[0]) >= t - 1e-9:
                        return columns, number
                except ValueError:
                    continue
    except OSError:
        pass
    return columns, None


def workspace_problem(scene: Scene, mechanics_values: dict) -> tuple[str, str] | None:
    """What a scene's own reference asks that no platform of its kind can do, found before its run,
    as (the scene's key to blame, what): None for nothing; a leg of no length or turned past a right angle from its neutral direction at
    either joint (the joints would cross: the mechanics stops there), where and when; a hint where an
    angle of the reference is larger than half a turn (radians meant as degrees). Not for a cueing
    scene (its reference is the guarded cueing's)."""
    from ..core import Core
    step = max(scene.step, min(WORKSPACE_STEP, scene.duration / 2))
    if scene.vehicle is not None or scene.duration / step > WORKSPACE_SAMPLES:
        return None  # (a run that long is refused by what it would record)
    times, poses, _ = play(scene_trajectory(scene), scene.duration, step)
    core = Core(values=mechanics_values)
    kinematics = core.pose_kinematics(poses)
    tilt = np.maximum(kinematics["lower_angle"], kinematics["upper_angle"])
    bad = (kinematics["length"] <= 0.0) | ~(tilt < TILT_IMPOSSIBLE)
    if not bad.any():
        return None
    k = int(np.flatnonzero(bad.any(axis=1))[0])
    leg = int(np.flatnonzero(bad[k])[0]) + 1
    largest = np.abs(poses[:, 3:]).max(axis=0)  # each angle's largest over the reference
    wide = POSE[3 + int(np.argmax(largest))]
    hint = (f"; its {wide} reaches {largest.max():.3g} rad ({np.degrees(largest.max()):.0f} deg): a scene's angles "
            "are radians" if largest.max() > np.pi / 2 else "")
    how = "to no length" if kinematics["length"][k, leg - 1] <= 0 else "past a right angle from its neutral direction"
    # the DOF to blame: the wide angle of a hint, else the one the pose then needs (_blamed); at the
    # trajectory table where that gives it (its row there named), else at its own [trajectory.<dof>]
    dof = wide if hint else _blamed(core, poses[k])
    columns, line = table_row(scene.table, times[k]) if scene.table is not None else ([], None)
    if dof in columns:
        key, row = "trajectory.table", f"; the table's row there: {scene.table}:{line}" if line else ""
    else:
        key, row = f"trajectory.{dof}" if scene.document.line(f"trajectory.{dof}") else "trajectory", ""
    return (key,
            f"the reference takes leg {leg} {how} at t = {times[k]:.3f} s (the joints would cross){hint}{row}")


def _possible(core, poses: np.ndarray) -> np.ndarray:
    """Per pose (n x 6): every leg of some length and no joint turned a right angle from neutral."""
    kinematics = core.pose_kinematics(poses)
    tilt = np.maximum(kinematics["lower_angle"], kinematics["upper_angle"])
    return ((kinematics["length"] > 0.0) & (tilt < TILT_IMPOSSIBLE)).all(axis=1)


def _blamed(core, pose: np.ndarray) -> str:
    """The DOF an impossible pose is impossible by: of those whose return to neutral alone makes it
    possible, the farthest from neutral (translations against the legs' length there, angles in
    radians); where none alone does, the farthest."""
    neutral = core.neutral_pose
    away = np.abs(pose - neutral) / np.r_[[core.pose_kinematics(neutral[None])["length"].max()] * 3, [1.0] * 3]
    away = np.where(np.isfinite(away), away, np.inf)
    trials = np.repeat(pose[None], 6, axis=0)
    trials[np.arange(6), np.arange(6)] = neutral
    with np.errstate(all="ignore"):
        curing = _possible(core, trials)
    return POSE[int(np.argmax(np.where(curing, away, -1.0))) if curing.any() else int(np.argmax(away))]


def check_workspace(scene: Scene, mechanics_values: dict) -> None:
    """SceneError at the scene's key where its own reference asks what no platform of its kind can
    do (workspace_problem): before a run, or an export that another tool would run into the same."""
    problem = workspace_problem(scene, mechanics_values)
    if problem is not None:
        raise SceneError(f"{scene.document.where(problem[0])}: {problem[1]}")
