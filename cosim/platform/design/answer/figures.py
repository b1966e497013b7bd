"""The design map's figures in the plane of the study's two axes: per actuator the kinematic limits
of every motion (Halder's Figs 2 and 3), and the force and speed limits (Fig 4), the admissible
zone shaded, named designs marked."""

from __future__ import annotations

import math
from pathlib import Path

from ...report.plots import save_figure
from ..search.map import Actuator, DesignMap
from ..spec.study import unit


def _plane(design: DesignMap):
    """A figure in the plane of the study's two axes (labelled), and the axes' names and values."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    (row_key, rows), (column_key, columns) = list(design.study.axes.items())
    fig, ax = plt.subplots(figsize=(8, 6))
    ax.set_xlabel(row_key.replace("_", " ") + (f" [{unit(row_key)}]" if unit(row_key) else ""))
    ax.set_ylabel(column_key.replace("_", " ") + (f" [{unit(column_key)}]" if unit(column_key) else ""))
    return plt, fig, ax, (row_key, rows), (column_key, columns)


LINES = {"max stroke": "-", "min stroke": "--", "joint angle": "-.", "force": "-", "force, full model": ":"}
COLOURS = {"surge": "tab:blue", "sway": "tab:orange", "heave": "tab:green", "roll": "tab:red", "pitch": "tab:purple",
           "yaw": "tab:brown"}


def plot_kinematic(design: DesignMap, actuator: Actuator, path: Path, marks: dict[str, tuple[float, float]]) -> Path:
    """Halder's Figs 2 and 3: per basic motion and constraint, the limiting curve (solid: max stroke,
    dashed: min stroke, dash-dot: joint angle) in the base radius - disc height plane, the zone
    where every constraint of every motion holds shaded, and the named points marked."""
    plt, fig, ax, (row_key, rows), (column_key, columns) = _plane(design)
    ok = design.admissible(actuator)
    if ok.any():
        ax.contourf(rows, columns, ok.T.astype(float), levels=[0.5, 1.5], colors=["0.85"])
    for constraint, admissible in design.kinematic_admissible(actuator).items():
        for m, motion in enumerate(design.motions):
            grid = admissible[:, :, m].T.astype(float)
            if 0 < grid.mean() < 1:
                ax.contour(rows, columns, grid, levels=[0.5], colors=[COLOURS.get(motion, "tab:blue")], linestyles=LINES[constraint])
    for label, (x, y) in marks.items():
        ax.plot(x, y, "k.", markersize=7)
        ax.annotate(label, (x, y), textcoords="offset points", xytext=(5, 3))
    handles = [plt.Line2D([], [], color=COLOURS.get(m, "tab:blue"), label=m) for m in design.motions] + \
        [plt.Line2D([], [], color="k", linestyle=LINES[c], label=c) for c in ("max stroke", "min stroke", "joint angle")]
    ax.legend(handles=handles, fontsize=8, ncol=3, loc="upper right")
    ax.set_title(f"{actuator.name}: running length {actuator.running_length_min:g}-{actuator.running_length_max:g} m, "
                 "joint angle < " + ("{:g}".format(*map(math.degrees, design.study.joint_limits))
                                     if len(set(design.study.joint_limits)) == 1 else
                                     "{:g} (top), {:g} (bottom)".format(*map(math.degrees, design.study.joint_limits)))
                 + " deg (admissible: shaded)", fontsize=9)
    return save_figure(fig, path, dpi=110)


def plot_dynamic(design: DesignMap, actuator: Actuator, path: Path, marks: dict[str, tuple[float, float]]) -> Path:
    """Halder's Fig 4: the peak force limit (the paper's payload-only model, solid; our full model,
    dotted), where the actuator gives them its peak force (full model, dashed) and speed (grey), and
    the stroke limits of the heave motion (or of the one recorded motion); the zone where all of
    them and every other kinematic constraint hold shaded."""
    plt, fig, ax, (row_key, rows), (column_key, columns) = _plane(design)
    ok = design.admissible(actuator, dynamic=True)
    if ok.any():
        ax.contourf(rows, columns, ok.T.astype(float), levels=[0.5, 1.5], colors=["0.85"])
    allowed = design.study.allowed_force(actuator)
    lines = [(design.force_paper <= allowed, "k", "-", f"peak force = {allowed:.0f} N (payload only)"),
             (design.force_full <= allowed, "k", ":", "the same, legs' inertia and friction included")]
    if actuator.peak_force is not None:
        lines.append((design.force_full <= actuator.peak_force, "k", "--",
                      f"peak force = {actuator.peak_force:.0f} N (the actuator's peak, full model)"))
    if actuator.speed is not None:
        lines.append((design.leg_speed <= actuator.speed, "0.5", "-", f"leg speed = {actuator.speed:g} m/s"))
    motion = "heave" if "heave" in design.motions else design.motions[0] if len(design.motions) == 1 else None
    if motion is not None:
        kinematic = design.kinematic_admissible(actuator)
        for constraint, style in (("min stroke", "--"), ("max stroke", "-.")):
            lines.append((kinematic[constraint][:, :, [design.motions.index(motion)]], COLOURS.get(motion, "tab:blue"),
                          style, f"{motion}: {constraint}"))
    handles = []
    for holds, colour, style, label in lines:
        grid = holds.all(axis=2).T.astype(float)
        handles.append(plt.Line2D([], [], color=colour, linestyle=style, label=label))
        if 0 < grid.mean() < 1:
            ax.contour(rows, columns, grid, levels=[0.5], colors=[colour], linestyles=style)
    for label, (x, y) in marks.items():
        ax.plot(x, y, "k.", markersize=7)
        ax.annotate(label, (x, y), textcoords="offset points", xytext=(5, 3))
    ax.legend(handles=handles, fontsize=8, loc="upper right")
    friction, other = design.study.force_margins
    ax.set_title(f"{actuator.name}: {actuator.continuous_force:g} N continuous less {friction:.0%} and {other:.0%} "
                 f"margins read as '{design.study.force_margins_mode}' (admissible: shaded)", fontsize=9)
    return save_figure(fig, path, dpi=110)


def plot_front(study, front, path: Path) -> Path:
    """The Pareto front in every pair of its objectives: one colour per actuator of the catalogue,
    the knee a star, each objective's best a diamond."""
    import itertools
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    pairs = list(itertools.combinations(range(len(front.objectives)), 2))
    columns = min(3, len(pairs))
    rows = -(-len(pairs) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(4.2 * columns, 3.6 * rows), squeeze=False)
    names = list(study.pareto.actuators)
    colours = {name: f"C{k}" for k, name in enumerate(names)}
    for ax, (i, j) in zip(axes.flat, pairs):
        for name in names:
            mine = [n for n, a in enumerate(front.actuators) if a.name == name]
            if mine:
                ax.scatter(front.values[mine, i], front.values[mine, j], s=14, color=colours[name], label=name)
        ax.scatter(*front.values[front.knee, [i, j]], marker="*", s=160, color="k", label="knee", zorder=3)
        for objective, index in front.best.items():
            ax.scatter(*front.values[index, [i, j]], marker="D", s=40, facecolors="none", edgecolors="k", zorder=3)
            ax.annotate(f"best {objective}", front.values[index, [i, j]], fontsize=6, textcoords="offset points",
                        xytext=(4, 3))
        ax.set_xlabel(front.objectives[i].replace("_", " "), fontsize=8)
        ax.set_ylabel(front.objectives[j].replace("_", " "), fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(pairs):]:
        ax.set_visible(False)
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.suptitle(f"{study.name}: {len(front)} designs no other beats in every objective (NSGA-II)", fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.95 - 0.02 * (rows < 3)))
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.975), ncol=min(4, len(labels)), fontsize=7)
    return save_figure(fig, path, dpi=110)
