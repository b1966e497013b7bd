"""A design's reachable workspace and its distance to a singular pose (left open by the papers):
the positions it reaches at the neutral orientation, the orientations at the neutral position,
within the actuator's running lengths and the joint limits (Eq 21 at each pose), the leg
Jacobian's conditioning over them, and along each DOF the nearest pose where it turns singular."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...core import Core
from ...report.rows import Row
from ..spec.study import DOFS, ROTATIONS, Actuator, Study, platform_values, point_text, stubs
from ..spec.verdicts import conditioning, near_text

REACH, ANGULAR_REACH = 1.0, math.pi  # [m], [rad] how far along each DOF a singular pose is sought
SEARCH = {False: f"{REACH:g} m", True: f"{math.degrees(ANGULAR_REACH):g} deg"}


@dataclass
class Workspace:
    """A design's reachable workspace under an actuator's running lengths and the joint limit: the
    positions reachable at the neutral orientation (a grid of `spacing`), the orientations
    reachable at the neutral position (a grid of `angle_step`), the leg Jacobian's conditioning
    over the reachable positions, and along each DOF from the neutral the distance to the nearest
    singular pose (inf where none lies within `reach`)."""
    positions: np.ndarray        # reachable positions (n x 3) [m]
    spacing: float
    orientations: np.ndarray     # reachable (roll, pitch, yaw) (n x 3) [rad]
    angle_step: float
    smallest_singular: float     # over the reachable positions
    condition: float
    singular_distance: dict[str, float]  # per DOF [m or rad]

    @property
    def volume(self) -> float:
        """[m^3] the reachable positions' cells."""
        return len(self.positions) * self.spacing ** 3

    def reach(self) -> dict[str, tuple[float, float]]:
        """Per DOF the smallest and largest reachable displacement on its own axis (m, rad)."""
        out = {}
        for k, dof in enumerate(DOFS):
            points = self.positions if k < 3 else self.orientations
            others = np.delete(np.arange(3), k % 3)
            on_axis = points[np.all(np.abs(points[:, others]) < 1e-12, axis=1), k % 3]
            out[dof] = (float(on_axis.min()), float(on_axis.max())) if len(on_axis) else (0.0, 0.0)
        return out


def reachable(core: Core, poses: np.ndarray, actuator: Actuator, joint_limit: float | tuple[float, float],
              stub_length: float) -> np.ndarray:
    """Which poses keep every leg's running length within the actuator's and both joint angles
    within the limit (Eq 21 at one pose); joint_limit: both joints', or (top, bottom)."""
    top_limit, bottom_limit = joint_limit if isinstance(joint_limit, tuple) else (joint_limit, joint_limit)
    k = core.pose_kinematics(poses)
    running = k["length"] + stub_length
    return (np.all(running <= actuator.running_length_max, axis=1) & np.all(running >= actuator.running_length_min, axis=1)
            & np.all(k["upper_angle"] <= top_limit, axis=1) & np.all(k["lower_angle"] <= bottom_limit, axis=1))


def singular_distance(core: Core, reach: float = REACH, angular_reach: float = ANGULAR_REACH,
                      samples: int = 2001) -> dict:
    """Along each DOF alone from the neutral pose, the smallest displacement (either sign) at which
    the leg Jacobian turns singular: where its determinant changes sign between two samples,
    refined by bisection; inf if it does not within +-reach (m) or +-angular_reach (rad)."""
    neutral = core.neutral_pose
    out = {}

    def det(poses: np.ndarray) -> np.ndarray:
        return np.linalg.det(core.pose_kinematics(poses, jacobian=True)["jacobian"])

    for k, dof in enumerate(DOFS):
        limit = angular_reach if dof in ROTATIONS else reach
        best = math.inf
        for sign in (1.0, -1.0):
            steps = sign * np.linspace(0.0, limit, samples)
            poses = np.tile(neutral, (samples, 1))
            poses[:, k] += steps
            d = det(poses)
            change = np.nonzero(np.sign(d[1:]) != np.sign(d[:-1]))[0]
            if not len(change):
                continue
            low, high = steps[change[0]], steps[change[0] + 1]
            for _ in range(60):  # bisection on the sign of det J
                middle = 0.5 * (low + high)
                pose = neutral.copy()
                pose[k] += middle
                if np.sign(det(pose[None])[0]) == np.sign(d[change[0]]):
                    low = middle
                else:
                    high = middle
            best = min(best, abs(0.5 * (low + high)))
        out[dof] = best
    return out


def cube(neutral: np.ndarray, first: int, half: float, step: float) -> np.ndarray:
    """Poses about the neutral on a grid (of `step`, within +-half) over three coordinates from
    `first` on: the positions (0) or the orientations (3)."""
    axis = np.arange(-half, half + step / 2, step)
    grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    poses = np.tile(neutral, (len(grid), 1))
    poses[:, first:first + 3] += grid
    return poses


def position_volume(study: Study, point: dict[str, float], actuator: Actuator, spacing: float,
                    extent: float = 0.8) -> float:
    """[m^3] the positions of a design reachable at the neutral orientation (Workspace.volume alone,
    on a grid of `spacing` within +-extent)."""
    core = Core(actuators=False, motors=False, friction=False).use_start_values(platform_values(study, point))
    poses = cube(core.neutral_pose, 0, extent, spacing)
    return float(reachable(core, poses, actuator, study.joint_limits, stubs(study)).sum() * spacing ** 3)


def workspace(study: Study, point: dict[str, float], actuator: Actuator, spacing: float = 0.02,
              angle_step: float = math.radians(1.0), extent: float = 0.8, angular_extent: float = math.radians(45.0)) -> Workspace:
    """The workspace of the design at `point` (see Workspace): positions within +-extent of the
    neutral on each axis, orientations within +-angular_extent."""
    core = Core(actuators=False, motors=False, friction=False).use_start_values(platform_values(study, point))
    neutral = core.neutral_pose
    s = stubs(study)
    poses = cube(neutral, 0, extent, spacing)
    ok = reachable(core, poses, actuator, study.joint_limits, s)
    positions = poses[ok, :3] - neutral[:3]
    turned = cube(neutral, 3, angular_extent, angle_step)
    orientations = turned[reachable(core, turned, actuator, study.joint_limits, s), 3:] - neutral[3:]
    sample = poses[ok][:: max(1, ok.sum() // 5000)]
    singular = np.linalg.svd(core.pose_kinematics(sample, jacobian=True)["jacobian"], compute_uv=False) \
        if len(sample) else np.full((1, 6), np.nan)
    return Workspace(np.round(positions, 12), spacing, np.round(orientations, 12), angle_step,
                     float(singular[:, -1].min()), float((singular[:, 0] / singular[:, -1]).max()),
                     singular_distance(core))


def study_workspace(study: Study) -> Workspace | None:
    """The workspace of the study's [workspace] design, or None if it names none."""
    spec = study.workspace
    if spec is None:
        return None
    return workspace(study, spec.point, study.actuator(spec.actuator), spec.spacing, spec.angle_step)


def workspace_rows(study: Study, space: Workspace) -> list[Row]:
    """The [workspace] design's reach, volume, conditioning and singular distances as rows, each
    verdict against the study's thresholds."""
    where = point_text(study, study.workspace.point)
    reach = space.reach()
    found = {d: v for d, v in space.singular_distance.items() if math.isfinite(v)}
    return [Row(f"reachable positions at the neutral orientation ({where}, {study.workspace.actuator})", "",
                space.volume, "m^3", f"a {1e3 * space.spacing:g} mm grid; on the axes: " + ", ".join(
                    f"{d} {reach[d][0]:+.2f}/{reach[d][1]:+.2f} m" for d in ("surge", "sway", "heave"))),
            Row("reachable orientations at the neutral position, each alone", "",
                ", ".join(f"{d} {math.degrees(reach[d][0]):+.0f}/{math.degrees(reach[d][1]):+.0f}" for d in ROTATIONS),
                "deg", f"{len(space.orientations)} of the {math.degrees(space.angle_step):g} deg grid's orientations "
                "reachable"),
            Row("leg Jacobian over the reachable positions", "",
                f"smallest singular value {space.smallest_singular:.3f}, condition number {space.condition:.1f}", "",
                conditioning(study, space.condition)),
            Row("nearest singular pose along each DOF from the neutral", "(left open by the papers)",
                ", ".join(f"{d} {math.degrees(v):.1f} deg" if d in ROTATIONS else f"{d} {v:.3f} m"
                          for d, v in found.items()) or "none", "",
                "; ".join([near_text(study, space.singular_distance)] + [
                    f"none within +-{SEARCH[rotation]} along {', '.join(missing)}" for rotation in (False, True)
                    if (missing := [d for d in DOFS if d not in found and (d in ROTATIONS) == rotation])]))]
