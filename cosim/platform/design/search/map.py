"""The design map (Halder's Figs 2-4 for any study): at every grid point and for every motion, the
limits over the motion (the legs' longest and shortest, both joints' largest angles, the leg
Jacobian's conditioning; and the peak leg force, payload only and full model, and the legs'
speed), from the mechanics FMU's own dynamics core, one call per grid point for all its poses;
on Dask when it is large (`parallel_map`, bit for bit the in-process map).

Which designs an actuator admits follows from the map (Eq 21, Fig 4): `kinematic_admissible`,
`dynamic_admissible`, `admissible`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ...core import Core
from ..spec.motion import basic_motions
from ..spec.study import Actuator, Study, platform_values, stubs
from ..spec.verdicts import SINGULAR


@dataclass
class DesignMap:
    """Per grid point (rows: the first axis, columns: the second) and basic motion, the limits
    over the motion; `seconds` the time the map took."""
    study: Study
    motions: list[str]
    actuated_length_max: np.ndarray    # [rows, columns, motions]: the largest actuated length [m]
    actuated_length_min: np.ndarray
    neutral_length: np.ndarray  # [rows, columns]: the longest actuated length at the neutral
    top_angle: np.ndarray     # the largest top (universal) joint angle [rad]
    bottom_angle: np.ndarray  # the largest bottom (spherical) joint angle [rad]
    smallest_singular: np.ndarray  # the leg Jacobian's smallest singular value over the motion
    condition: np.ndarray     # its largest condition number
    seconds: float = 0.0
    force_paper: np.ndarray | None = None  # [rows, columns, motions] peak |leg force|, payload only [N]
    force_full: np.ndarray | None = None   # the same with the legs' inertia and friction
    leg_speed: np.ndarray | None = None    # [rows, columns, motions] the largest |extension rate| [m/s]

    @property
    def points(self) -> int:
        return self.actuated_length_max.shape[0] * self.actuated_length_max.shape[1]

    def kinematic_admissible(self, actuator: Actuator) -> dict[str, np.ndarray]:
        """Per constraint, [rows, columns, motions] booleans (Eq 21): max stroke, min stroke, joint angle."""
        s = stubs(self.study)
        return {"max stroke": s + self.actuated_length_max < actuator.running_length_max,
                "min stroke": s + self.actuated_length_min > actuator.running_length_min,
                "joint angle": self.study.joints_within(self.top_angle, self.bottom_angle)}

    def dynamic_admissible(self, actuator: Actuator) -> dict[str, np.ndarray]:
        """Per limit, [rows, columns, motions] booleans: the paper's peak force (payload only) within
        the continuous force less the margins (Fig 4); where the actuator gives them, the full
        model's peak force within its peak force and the legs' speed within its speed."""
        if self.force_paper is None:
            return {}
        out = {"force": self.force_paper <= self.study.allowed_force(actuator)}
        if actuator.peak_force is not None:
            out["peak force"] = self.force_full <= actuator.peak_force
        if actuator.speed is not None:
            out["speed"] = self.leg_speed <= actuator.speed
        return out

    def admissible(self, actuator: Actuator, dynamic: bool = False) -> np.ndarray:
        """[rows, columns]: every constraint of every basic motion holds (and the forces and
        speed, with dynamic), on a platform that is not singular anywhere along them."""
        ok = np.all([c.all(axis=2) for c in self.kinematic_admissible(actuator).values()], axis=0)
        ok &= self.condition.max(axis=2) <= SINGULAR
        if dynamic:
            for limit in self.dynamic_admissible(actuator).values():
                ok &= limit.all(axis=2)
        return ok


def design_map(study: Study, dynamic: bool = True) -> DesignMap:
    """The kinematic (and dynamic) map of the study's grid: one call of the dynamics core per grid
    point for all its poses."""
    start = time.perf_counter()
    (row_key, rows), (column_key, columns) = list(study.axes.items())
    shape = (len(rows), len(columns))
    paper, full = Core(actuators=False, motors=False, friction=False), Core()
    out: dict[str, np.ndarray] = {}
    motions: list[str] = []

    def store(name: str, r: int, c: int, values: np.ndarray, ends: np.ndarray, reduce) -> None:
        """Per motion (`ends`: where one motion's rows end and the next's begin), the reduced value."""
        out.setdefault(name, np.empty((*shape, len(motions))))[r, c] = [reduce(part) for part in np.split(values, ends)]

    for r, row in enumerate(rows):
        for c, column in enumerate(columns):
            point = {row_key: float(row), column_key: float(column)}
            paper.use_start_values(platform_values(study, point))
            neutral = paper.neutral_pose
            paths = basic_motions(study, neutral)
            motions = list(paths)
            poses = np.concatenate([p for p, _, _ in paths.values()])
            k = paper.pose_kinematics(poses, jacobian=True)
            path_ends = np.cumsum([len(p) for p, _, _ in paths.values()])[:-1]
            # the Jacobian's singular values at every tenth pose of each path (and its ends): the
            # conditioning varies slowly along a path, and the SVDs would cost more than the rest
            sampled = np.r_[0:len(poses):10, len(poses) - 1]
            singular = np.full((len(poses), 6), np.nan)
            singular[sampled] = np.linalg.svd(k["jacobian"][sampled], compute_uv=False)
            with np.errstate(divide="ignore"):  # a singular pose: an infinite condition number
                condition = singular[:, :1] / singular[:, -1:]
            for name, values, reduce in (("actuated_length_max", k["length"], np.max), ("actuated_length_min", k["length"], np.min),
                                         ("top_angle", k["upper_angle"], np.max),
                                         ("bottom_angle", k["lower_angle"], np.max),
                                         ("smallest_singular", singular[:, -1:], np.nanmin),
                                         ("condition", condition, np.nanmax)):
                store(name, r, c, values, path_ends, reduce)
            out.setdefault("neutral_length", np.empty(shape))[r, c] = paper.leg_lengths(neutral).max()
            if dynamic:
                timed = basic_motions(study, neutral, timed=True)
                arrays = [np.concatenate([m[i] for m in timed.values()]) for i in range(3)]
                timed_ends = np.cumsum([len(m[0]) for m in timed.values()])[:-1]
                full.use_start_values(platform_values(study, point, effects=True))
                store("force_paper", r, c, np.abs(paper.leg_forces_many(*arrays)), timed_ends, np.max)
                store("force_full", r, c, np.abs(full.leg_forces_many(*arrays)), timed_ends, np.max)
                store("leg_speed", r, c, np.abs(paper.leg_velocities_many(arrays[0], arrays[1])), timed_ends, np.max)
    return DesignMap(study, motions, seconds=time.perf_counter() - start, **out)


def at(study: Study, point: dict[str, float], dynamic: bool = True) -> DesignMap:
    """The map of one design at exactly its values (whatever the study's grid holds)."""
    return design_map(study.with_axes({key: np.array([float(point[key])]) for key in study.axes}), dynamic)


def along(study: Study, row: float, dynamic: bool = False) -> DesignMap:
    """The map of one row at exactly `row` of the first axis, over the grid's columns."""
    (row_key, _), (column_key, columns) = list(study.axes.items())
    return design_map(study.with_axes({row_key: np.array([float(row)]), column_key: columns}), dynamic)


def limit_along(line: DesignMap, actuator: Actuator, constraint: str, motion: str) -> float | None:
    """Halder's points a, b, c on a map of one row (`along`): scanning the column variable (z)
    upward, the last admissible value before the constraint fails (max stroke: the largest
    admissible z) or the first admissible one (min stroke, joint angle: the smallest); None where
    it holds nowhere. On the grid: within one column step of the crossing."""
    columns = list(line.study.axes.values())[1]
    ok = line.kinematic_admissible(actuator)[constraint][0, :, line.motions.index(motion)]
    if not ok.any():
        return None
    return float(columns[ok][-1] if constraint == "max stroke" else columns[ok][0])


def _rows(study: Study, rows: list[int], dynamic: bool) -> DesignMap:
    """The map of some rows of the study's grid (a task of a parallel map)."""
    (row_key, values), (column_key, columns) = list(study.axes.items())
    return design_map(study.with_axes({row_key: values[rows], column_key: columns}), dynamic)


def parallel_map(study: Study, dynamic: bool = True, workers: int | None = None,
                 scheduler: str | None = None) -> DesignMap:
    """design_map with its rows on Dask (a LocalCluster of `workers` processes, default one per
    core, or a running scheduler); workers = 0: in this process. Bit for bit the in-process map."""
    if workers == 0 and scheduler is None:
        return design_map(study, dynamic)
    from ....engine.sweep.dask_run import dask_client
    start = time.perf_counter()
    with dask_client(workers, scheduler) as client:
        n = max(len(client.scheduler_info()["workers"]), 1)
        rows = np.array_split(np.arange(len(next(iter(study.axes.values())))), 4 * n)
        parts = client.gather(client.map(_rows, [study] * len(rows), [list(r) for r in rows if len(r)],
                                         [dynamic] * len(rows), pure=False))
    merged = {name: np.concatenate([getattr(p, name) for p in parts]) for name in
              ("actuated_length_max", "actuated_length_min", "neutral_length", "top_angle", "bottom_angle", "smallest_singular",
               "condition", *(("force_paper", "force_full", "leg_speed") if dynamic else ()))}
    return DesignMap(study, parts[0].motions, seconds=time.perf_counter() - start, **merged)
