"""Geometry and actuator chosen together: the Pareto front of a study's [pareto] objectives.

A candidate is a design of the study's two axes (anywhere in their ranges), an actuator of the
catalogue and, for one given by its motor, the screw's lead (the motor's torque and speed become
leg force and speed through it, its rotor's inertia is reflected onto the leg by it). It is
admissible as a design of the map is (optimise.margins_of: the stroke at both ends, the joint
angles, the forces and speed, not singular), with its own actuator's legs on the platform. Among
the admissible, NSGA-II (pymoo) keeps the candidates no other beats in every objective at once;
its evaluations run on Dask like the optimiser's. The knee is the front's design nearest the ideal
point once each objective is scaled to [0, 1] over the front; it and each objective's best design
are confirmed by co-simulation, each with its actuator's drive (confirm.confirm)."""

from __future__ import annotations

import time
from contextlib import nullcontext
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from ...report.rows import Row
from .map import at
from .optimise import margins_of
from ..spec.study import MAXIMISED, OBJECTIVES, Actuator, Study, point_text
from .workspace import position_volume


CONSTRAINTS = 7  # optimise.margins_of: max and min stroke, joint angle, force, peak force, speed, singular


@dataclass
class Front:
    """The non-dominated admissible designs: per design its point, actuator (at its lead) and
    objective values (in their own sense: a margin as a fraction, a volume in m^3); the knee and
    each objective's best (indices into `designs`), and their co-simulated confirmations."""
    objectives: tuple[str, ...]
    points: list[dict[str, float]]
    actuators: list[Actuator]
    values: np.ndarray               # [designs, objectives]
    evaluations: int
    seconds: float
    knee: int = -1
    best: dict[str, int] = field(default_factory=dict)
    confirmations: dict[int, list[dict[str, Any]]] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.points)


def variables(study: Study) -> tuple[np.ndarray, np.ndarray]:
    """The decision variables' bounds: the two axes' ranges, the catalogue's index (a real in
    [0, n), floored) and, where [pareto] gives a lead range, the screw's lead [m]."""
    spec = study.pareto
    low = [float(v[0]) for v in study.axes.values()] + [0.0]
    high = [float(v[-1]) for v in study.axes.values()] + [len(spec.actuators) - 1e-9]
    if spec.lead is not None:
        low.append(spec.lead[0])
        high.append(spec.lead[1])
    return np.array(low), np.array(high)


def candidate(study: Study, x: np.ndarray) -> tuple[dict[str, float], Actuator]:
    """The design and actuator a decision vector stands for."""
    spec = study.pareto
    point = {key: float(v) for key, v in zip(study.axes, x)}
    actuator = study.actuator(spec.actuators[min(int(x[2]), len(spec.actuators) - 1)])
    if actuator.motor is not None and spec.lead is not None:
        actuator = actuator.with_lead(float(x[3]))
    return point, actuator


def measure(study: Study, point: dict[str, float], actuator: Actuator) -> tuple[dict[str, float], dict[str, float]]:
    """A candidate's objective values (each in its own sense) and its margins (negative: violated),
    on the platform with the actuator's legs."""
    own = study.with_actuator(actuator)
    one = at(own, point)
    values = {"stroke": float(one.actuated_length_max.max() - one.actuated_length_min.min()),
              "force_margin": float(1 - one.force_full.max() / own.allowed_force(actuator)),
              "conditioning": float(one.condition.max()),
              "actuator_force": actuator.continuous_force}
    if "workspace" in study.pareto.objectives:
        values["workspace"] = position_volume(own, point, actuator, study.pareto.workspace_spacing)
    return {k: values[k] for k in study.pareto.objectives}, margins_of(own, one, actuator)


def evaluate(x: np.ndarray, study: Study) -> tuple[np.ndarray, np.ndarray]:
    """One candidate for NSGA-II: the objectives to minimise (a larger-is-better one negated) and
    the constraints (<= 0 where they hold)."""
    values, margins = measure(study, *candidate(study, x))
    objectives = np.array([-values[k] if k in MAXIMISED else values[k] for k in study.pareto.objectives])
    constraints = -np.array(list(margins.values()))
    return np.nan_to_num(objectives, nan=1e300, posinf=1e300), np.nan_to_num(constraints, nan=1e300, posinf=1e300)


def pareto_front(study: Study, workers: int | None = 0, scheduler: str | None = None) -> Front:
    """NSGA-II over the study's [pareto] variables and objectives, its evaluations on Dask when
    workers/scheduler say so (each a candidate), in this process otherwise; the same seed gives the
    same front. The knee and each objective's best marked (not yet confirmed)."""
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.problem import Problem
    from pymoo.optimize import minimize
    from ....engine.sweep.dask_run import dask_client
    spec = study.pareto
    low, high = variables(study)
    start = time.perf_counter()
    with (dask_client(workers, scheduler) if workers != 0 or scheduler else nullcontext()) as client:
        one = partial(evaluate, study=study)

        class Candidates(Problem):
            def _evaluate(self, x, out, *args, **kwargs):
                rows = list(x)
                done = client.gather(client.map(one, rows, pure=False)) if client else [one(r) for r in rows]
                out["F"] = np.array([f for f, _ in done])
                out["G"] = np.array([g for _, g in done])

        problem = Candidates(n_var=len(low), n_obj=len(spec.objectives), n_ieq_constr=CONSTRAINTS, xl=low, xu=high)
        result = minimize(problem, NSGA2(pop_size=spec.population), ("n_gen", spec.generations), seed=spec.seed,
                          verbose=False)
    seconds = time.perf_counter() - start
    evaluations = spec.population * spec.generations
    if result.X is None:  # no admissible candidate
        return Front(spec.objectives, [], [], np.empty((0, len(spec.objectives))), evaluations, seconds)
    _, once = np.unique(np.atleast_2d(result.X), axis=0, return_index=True)  # a design found twice, once
    x, f = np.atleast_2d(result.X)[once], np.atleast_2d(result.F)[once]
    chosen = [candidate(study, row) for row in x]
    order = np.lexsort(f.T[::-1])  # a stable order: by the first objective, then the next
    values = f[order] * np.array([-1.0 if k in MAXIMISED else 1.0 for k in spec.objectives])
    front = Front(spec.objectives, [chosen[i][0] for i in order], [chosen[i][1] for i in order], values, evaluations,
                  seconds)
    front.knee, front.best = knee(front), {k: int(np.argmax(values[:, n]) if k in MAXIMISED else np.argmin(values[:, n]))
                                           for n, k in enumerate(spec.objectives)}
    return front


def knee(front: Front) -> int:
    """The design nearest the ideal point (each objective's best over the front) once each objective
    is scaled to [0, 1] over the front, larger-is-better ones turned: the balanced compromise."""
    cost = front.values * np.array([-1.0 if k in MAXIMISED else 1.0 for k in front.objectives])
    span = np.ptp(cost, axis=0)
    scaled = (cost - cost.min(axis=0)) / np.where(span > 0, span, 1.0)
    return int(np.argmin(np.linalg.norm(scaled, axis=1)))


def confirm_front(study: Study, front: Front, workers: int | None = 0, scheduler: str | None = None) -> None:
    """The knee and each objective's best through the co-simulation (every motion), each with its
    actuator's legs and drive; stored in front.confirmations by design index."""
    from .confirm import confirm
    for index in dict.fromkeys([front.knee, *front.best.values()]):
        actuator = front.actuators[index]
        front.confirmations[index] = confirm(study.with_actuator(actuator), front.points[index], actuator, workers,
                                             scheduler, drive=actuator.drive)


def study_front(study: Study, workers: int | None = 0, scheduler: str | None = None) -> Front | None:
    """The study's [pareto] front, confirmed where it says so; None if it has no [pareto]."""
    if study.pareto is None:
        return None
    front = pareto_front(study, workers, scheduler)
    if study.pareto.confirm and len(front):
        confirm_front(study, front, workers, scheduler)
    return front


def describe(study: Study, front: Front, index: int) -> str:
    """A front design: its point, actuator (and lead) and objective values."""
    actuator = front.actuators[index]
    lead = f" at a {1e3 * actuator.lead:.1f} mm lead" if actuator.motor is not None and actuator.lead else ""
    return (f"{point_text(study, {k: round(v, 3) for k, v in front.points[index].items()})}, {actuator.name}{lead}: "
            + ", ".join(f"{k} {_shown(k, v)}" for k, v in zip(front.objectives, front.values[index])))


def _shown(objective: str, value: float) -> str:
    return {"stroke": f"{value:.3f} m", "force_margin": f"{value:.1%}", "workspace": f"{value:.3f} m^3",
            "conditioning": f"{value:.2f}", "actuator_force": f"{value:.0f} N"}[objective]


def pareto_rows(study: Study, front: Front) -> list[Row]:
    """The front's size and make-up, the knee and each objective's best, and their confirmations."""
    from .confirm import confirmation_rows
    spec = study.pareto
    if not len(front):
        return [Row("Pareto front", "", "none", "", f"no admissible candidate in {front.evaluations} evaluations "
                    "(NSGA-II): widen the axes, the catalogue or the lead range")]
    share = ", ".join(f"{name} {sum(a.name == name for a in front.actuators)}" for name in spec.actuators)
    out = [Row(f"Pareto front over {', '.join(spec.objectives)}", "", f"{len(front)} designs", "",
               f"NSGA-II, {spec.population} x {spec.generations} evaluations in {front.seconds:.0f} s, seed {spec.seed}; "
               f"by actuator: {share}"),
           Row("knee (nearest the ideal point, each objective scaled over the front)", "", describe(study, front, front.knee),
               "", "")]
    for objective, index in front.best.items():
        out.append(Row(f"best {objective}", "", describe(study, front, index), "", OBJECTIVES[objective]))
    for index, runs in front.confirmations.items():
        label = "knee" if index == front.knee else "best " + next(k for k, i in front.best.items() if i == index)
        actuator = front.actuators[index]
        out += confirmation_rows(runs, f"{label}: {point_text(study, {k: round(v, 3) for k, v in front.points[index].items()})}, "
                                 f"{actuator.name}")
    return out


def write_front(study: Study, front: Front, out: Path) -> list[Path]:
    """The front as a table (Parquet and CSV: the design, the actuator, its lead, the objectives,
    the knee and the bests marked) and its figure (every pair of objectives)."""
    import pyarrow as pa
    import pyarrow.csv
    import pyarrow.parquet as pq
    from ....engine.files import replacing
    from ..answer.figures import plot_front
    stem = study.path.stem
    columns: dict[str, Any] = {k: [p[k] for p in front.points] for k in study.axes}
    columns["actuator"] = [a.name for a in front.actuators]
    columns["screw_lead"] = [a.lead if a.motor is not None else None for a in front.actuators]
    columns["continuous_force"] = [a.continuous_force for a in front.actuators]
    for n, objective in enumerate(front.objectives):
        columns[objective] = front.values[:, n]
    columns["role"] = [", ".join((["knee"] if i == front.knee else []) + [f"best {k}" for k, j in front.best.items()
                                                                          if j == i]) for i in range(len(front))]
    arrow = pa.table(columns)
    written = []
    with replacing(out / f"{stem}_pareto.parquet", "the Pareto front", arrow.nbytes + 4096) as temporary:
        pq.write_table(arrow, temporary)
    written.append(out / f"{stem}_pareto.parquet")
    with replacing(out / f"{stem}_pareto.csv", "the Pareto front", 3 * arrow.nbytes + 4096) as temporary:
        pa.csv.write_csv(arrow, temporary)
    written.append(out / f"{stem}_pareto.csv")
    if len(front):
        written.append(plot_front(study, front, out / f"{stem}_pareto.png"))
    return written
