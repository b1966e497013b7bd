"""Beyond one grid: the design with the largest worst-case margin. Each constraint's margin over
every motion (stroke at both ends, joint angle, the paper's peak force), the smallest of them
maximised by scipy's differential evolution over the axes' ranges, its evaluations on Dask."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ...report.rows import Row
from .map import DesignMap, at
from ..spec.study import Actuator, Study, stubs, value
from ..spec.verdicts import SINGULAR


def margins(study: Study, point: dict[str, float], actuator: Actuator) -> dict[str, float]:
    """A design's margins (margins_of) at a point of the study's axes."""
    return margins_of(study, at(study, point), actuator)


def margins_of(study: Study, design: DesignMap, actuator: Actuator) -> dict[str, float]:
    """A one-design map's margins against each constraint over every motion, each as a fraction of
    what it is measured against (negative: violated): the stroke at both ends (of the stroke), the
    joint angle (of the limit), the peak force of the paper's model (of the allowed force), the
    full model's peak force (of the actuator's peak) and the legs' speed (of its speed) where it
    gives them (inf where not), and the conditioning (of the singular threshold)."""
    s = stubs(study)
    full, speed = design.force_full.max(), design.leg_speed.max()
    return {"max stroke": float((actuator.running_length_max - s - design.actuated_length_max.max()) / actuator.stroke),
            "min stroke": float((design.actuated_length_min.min() + s - actuator.running_length_min) / actuator.stroke),
            "joint angle": float(1 - max(design.top_angle.max() / study.joint_limits[0],
                                         design.bottom_angle.max() / study.joint_limits[1])),
            "force": float(1 - design.force_paper.max() / study.allowed_force(actuator)),
            "peak force": float(1 - full / actuator.peak_force) if actuator.peak_force is not None else math.inf,
            "speed": float(1 - speed / actuator.speed) if actuator.speed is not None else math.inf,
            "singular": float(1 - np.nanmax(design.condition) / SINGULAR)}


def _negative_margin(x: np.ndarray, study: Study, keys: tuple[str, ...], actuator: Actuator) -> float:
    return -min(margins(study, dict(zip(keys, map(float, x))), actuator).values())


@dataclass
class Optimum:
    point: dict[str, float]
    margins: dict[str, float]
    evaluations: int
    seconds: float


def optimise(study: Study, actuator: Actuator, workers: int | None = 0, scheduler: str | None = None,
             seed: int = 1, max_iterations: int = 60) -> Optimum:
    """The design (within the study's axes' ranges) whose smallest margin over every constraint and
    basic motion is largest: the most robust admissible design, found by scipy's differential
    evolution (one objective, the worst margin, for one actuator; pareto.py trades several
    objectives and the actuator's choice). Its evaluations run on Dask when workers/scheduler say
    so (each a design of the map), in this process otherwise; the same seed gives the same design."""
    from functools import partial
    keys = tuple(study.axes)
    bounds = [(float(v[0]), float(v[-1])) for v in study.axes.values()]
    start = time.perf_counter()
    objective = partial(_negative_margin, study=study, keys=keys, actuator=actuator)
    result = evolve(objective, bounds, workers, scheduler, seed, max_iterations)
    point = dict(zip(keys, map(float, result.x)))
    return Optimum(point, margins(study, point, actuator), int(result.nfev), time.perf_counter() - start)


def evolve(objective, bounds: list[tuple[float, float]], workers: int | None, scheduler: str | None, seed: int,
           max_iterations: int, population: int = 15, progress: str | None = None):
    """scipy's differential evolution of `objective` (a picklable function of a point) within
    `bounds`, each generation's points evaluated on Dask when workers/scheduler say so (in this
    process for workers = 0 and no scheduler); the same seed gives the same answer. `progress`: a
    label for the evaluations' progress (cosim.engine.observers.TaskProgress: a bar with the time
    left on a terminal, out of the most the search can take). Returns scipy's OptimizeResult."""
    from contextlib import nullcontext
    from scipy.optimize import differential_evolution
    from ....engine.observers import TaskProgress
    from ....engine.sweep.dask_run import dask_client
    shown = TaskProgress(progress, (max_iterations + 1) * population * len(bounds)) if progress else None
    with (dask_client(workers, scheduler) if workers != 0 or scheduler else nullcontext()) as client:

        def mapper(function, points):  # what differential_evolution evaluates its population through
            points = list(points)
            values = client.gather(client.map(function, points, pure=False)) if client else list(map(function, points))
            if shown is not None:
                shown.advance(f"best so far {min(values):.4g}", count=len(points))
            return values
        result = differential_evolution(objective, bounds, seed=seed, maxiter=max_iterations, popsize=population,
                                        tol=1e-6, polish=False, updating="deferred", workers=mapper)
        if shown is not None:
            shown.finish(f"best {result.fun:.4g}")
        return result


def study_optimum(study: Study, workers: int | None = 0, scheduler: str | None = None) -> Optimum | None:
    """The most robust design for the study's [optimise] actuator, or None if it names none."""
    spec = study.optimise
    if spec is None:
        return None
    return optimise(study, study.actuator(spec.actuator), workers, scheduler, spec.seed, spec.iterations)


def optimum_rows(study: Study, best: Optimum) -> list[Row]:
    """The optimum's design and margins as a row."""
    where = ", ".join(value(k, v, ".3f") for k, v in best.point.items())
    worst = min(best.margins, key=best.margins.get)
    return [Row(f"the most robust design for {study.optimise.actuator} (largest worst-case margin)", "", where, "",
                f"differential evolution, {best.evaluations} designs; margins: " + ", ".join(
                    f"{k} {v:.1%}" for k, v in best.margins.items() if k != "singular" and math.isfinite(v))
                + f" (the least: {worst})")]
