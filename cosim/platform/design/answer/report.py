"""A study's answer: per actuator the admissible designs and their extent, the smallest stroke
that carries every motion, beside the paper's numbers where the study is Halder's Section V, and
the rows of the designs it looks at more closely (workspace, optimum, confirmation); as a
summary, figures and the map as a table (Parquet, CSV)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ....engine.files import replacing, write_text
from ...report.rows import Row, table
from ..search.confirm import confirmation_rows, study_confirmation
from .figures import plot_dynamic, plot_kinematic
from .halder import is_section5, longest, marks, paper_rows, shortest
from ..search.map import DesignMap
from ..search.optimise import optimum_rows, study_optimum
from ..search.pareto import Front, pareto_rows, write_front
from .assumptions import assumption_rows
from ..spec.study import point_text, span, stubs
from ..spec.verdicts import SINGULAR
from ..search.workspace import study_workspace, workspace_rows


def map_rows(design: DesignMap) -> list[Row]:
    """Any study's answer: per actuator the admissible designs (kinematic, then with its forces and
    speed) and their extent along each axis; the smallest stroke that carries every motion within
    the joint limit, where, and the running lengths it needs there."""
    study = design.study
    (row_key, rows), (column_key, columns) = list(study.axes.items())
    out = []
    for actuator in study.actuators:
        kinematic, both = design.admissible(actuator), design.admissible(actuator, dynamic=True)
        failing = {name: float(np.mean(~holds.all(axis=2))) for name, holds in
                   {**design.kinematic_admissible(actuator), **design.dynamic_admissible(actuator)}.items()}
        r, c = np.nonzero(both)
        extent = (f"{span(row_key, rows[r], study.decimals(row_key))}, "
                  f"{span(column_key, columns[c], study.decimals(column_key))}") if both.any() else "none"
        out.append(Row(f"admissible designs, {actuator.name}", "", f"{kinematic.sum()} / {both.sum()} of {design.points}",
                       "points", f"kinematic / with forces and speed; {extent}; each limit fails at: " + ", ".join(
                           f"{name} {share:.0%}" for name, share in failing.items())))
    joints = study.joints_within(design.top_angle, design.bottom_angle).all(axis=2)
    needed = np.where(joints, design.actuated_length_max.max(axis=2) - design.actuated_length_min.min(axis=2), np.inf)
    if np.isfinite(needed).any():
        r, c = np.unravel_index(np.argmin(needed), needed.shape)
        s = stubs(study)
        out.append(Row("the smallest stroke that carries every motion, over the grid (joint limit held)", "",
                       float(needed[r, c]), "m",
                       f"at {point_text(study, {row_key: rows[r], column_key: columns[c]}, grid=True)}: running length "
                       f"{design.actuated_length_min[r, c].min() + s:.3f} to {design.actuated_length_max[r, c].max() + s:.3f} m"
                       + ("; on the grid's edge: a wider grid may need less" if r in (0, len(rows) - 1)
                          or c in (0, len(columns) - 1) else "")))
    else:
        out.append(Row("the smallest stroke that carries every motion", "", "none", "",
                       "the joint limit fails at every design of the grid"))
    condition = design.condition.max(axis=2)
    limit = study.thresholds.condition_number
    singular = int((~(condition <= SINGULAR)).sum())
    out.append(Row("well-conditioned designs of the grid", "", f"{int((condition <= limit).sum())} of {design.points}",
                   "points", f"the leg Jacobian's condition number within the study's {limit:g} over every motion; "
                   f"over the grid {np.nanmin(condition):.1f} to {np.nanmax(condition):.3g}"
                   + (f"; {singular} singular (above {SINGULAR:.0e}: not admissible)" if singular else "")))
    return out


def report_rows(design: DesignMap, workers: int | None = 0, scheduler: str | None = None,
                front: Front | None = None) -> list[Row]:
    """The study's assumptions and what each changes at its chosen design; the map's rows (beside
    the paper's numbers for Halder's Section V plane), then the [workspace] design's, the
    [optimise] optimum's, the [confirm] design's co-simulation and the [pareto] front's (`front`,
    pareto.study_front), where the study names them (the optimiser's designs and the
    confirmations on Dask as workers/scheduler say)."""
    study = design.study
    space, best = study_workspace(study), study_optimum(study, workers, scheduler)
    runs = study_confirmation(study, workers, scheduler)
    rows = assumption_rows(study) + (paper_rows(design) if is_section5(study) else []) + map_rows(design)
    if space:
        rows += workspace_rows(study, space)
    if best:
        rows += optimum_rows(study, best)
    if runs:
        rows += confirmation_rows(runs, f"{point_text(study, study.confirm.point)}, {study.confirm.actuator}")
    if front is not None:
        rows += pareto_rows(study, front)
    return rows


def summary(design: DesignMap, rows: list | None = None) -> list[str]:
    """Markdown lines: the grid, the rows (report_rows unless given: the assumptions first), the
    map's speed."""
    study = design.study
    grid = " x ".join(f"{span(key, values, study.decimals(key))} in steps of {study.step(key):g}"
                      for key, values in study.axes.items())
    motion = (f"the motion of {study.recorded.name} ({len(study.recorded.times)} samples)" if study.recorded else
              f"{len(design.motions)} basic motions ({', '.join(design.motions)})")
    return [f"Grid: {grid}, {design.points} points, {motion}.", "",
            table(rows if rows is not None else report_rows(design)), "",
            f"The map took {design.seconds:.1f} s ({design.points / max(design.seconds, 1e-9):.0f} grid points per "
            "second, each " + ("over the motion)." if study.recorded else "over every basic motion).")]


def write(design: DesignMap, out: Path, rows: list | None = None, front: Front | None = None) -> list[Path]:
    """The figures (Halder's Figs 2 and 3 per actuator, Fig 4 for the longest stroke), the summary
    and the map as a table (one row per grid point and basic motion) into `out`; the Pareto front's
    table and figure where there is one."""
    import pyarrow as pa
    import pyarrow.csv
    import pyarrow.parquet as pq
    stem = design.study.path.stem
    (row_key, radii), (column_key, columns) = list(design.study.axes.items())
    written = []
    points, chosen = marks(design)
    for k, actuator in enumerate(design.study.actuators):
        own = points if actuator is shortest(design.study) else chosen
        written.append(plot_kinematic(design, actuator, out / f"{stem}_kinematic_{k + 1}.png", own))
    if design.force_paper is not None:
        written.append(plot_dynamic(design, longest(design.study), out / f"{stem}_dynamic.png", chosen))
    r, c, m = np.meshgrid(np.arange(len(radii)), np.arange(len(columns)), np.arange(len(design.motions)), indexing="ij")
    s = stubs(design.study)
    values = {row_key: radii[r].ravel(), column_key: columns[c].ravel(), "motion": np.array(design.motions)[m].ravel(),
              "actuated_length_min": design.actuated_length_min.ravel(), "actuated_length_max": design.actuated_length_max.ravel(),
              "running_length_min": design.actuated_length_min.ravel() + s, "running_length_max": design.actuated_length_max.ravel() + s,
              "top_angle": design.top_angle.ravel(), "bottom_angle": design.bottom_angle.ravel(),
              "smallest_singular": design.smallest_singular.ravel(), "condition": design.condition.ravel()}
    if design.force_paper is not None:
        values.update(force_paper=design.force_paper.ravel(), force_full=design.force_full.ravel(),
                      leg_speed=design.leg_speed.ravel())
    arrow = pa.table(values)
    with replacing(out / f"{stem}.parquet", "the design map", arrow.nbytes) as temporary:
        pq.write_table(arrow, temporary)
    with replacing(out / f"{stem}.csv", "the design map", 3 * arrow.nbytes) as temporary:
        pa.csv.write_csv(arrow, temporary)
    summary_file = write_text(out / f"{stem}.md", "\n".join([f"# {design.study.name}", "", *summary(design, rows), ""]),
                              "the design summary")
    if front is not None:
        written += write_front(design.study, front, out)
    return [*written, out / f"{stem}.parquet", out / f"{stem}.csv", summary_file]
