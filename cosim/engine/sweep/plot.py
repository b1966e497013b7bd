"""A sweep's plot: one report against one axis (a line) or two (a heat map on a grid, coloured
points otherwise), failed and diverged points marked."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np

from ..files import write_figure
from .points import column_name


def label(column: str, units: Mapping[str, str]) -> str:
    """An axis label: the column and its unit where the target knows it (a per-leg column
    `name[k]` by its name)."""
    unit = units.get(column) or units.get(column.split("[")[0])
    return f"{column} [{unit}]" if unit else column


def _outline():
    from matplotlib import patheffects
    return patheffects.withStroke(linewidth=2, foreground="black")


def plot_sweep(rows: list[dict], spec: dict, path: Path, title: str, units: Mapping[str, str] | None = None) -> Path:
    """The chosen report against one axis (a line, failed points marked at the bottom) or two
    (a heat map on a grid, coloured points otherwise); units by column (the sweep's target's)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    units = units or {}
    report, x_name, y_name = (column_name(str(spec[k])) if k in spec else None for k in ("report", "x", "y"))
    ok = [r for r in rows if r["status"] == "ok" and np.isfinite(r.get(report, np.nan))]
    bad = [r for r in rows if r not in ok]
    fig, ax = plt.subplots(figsize=(8, 5))
    if y_name is None:
        ok.sort(key=lambda r: r[x_name])
        ax.plot([r[x_name] for r in ok], [r[report] for r in ok], "o-", ms=4, label="ran")
        if bad:
            bottom = min((r[report] for r in ok), default=1.0)
            ax.plot([r[x_name] for r in bad], [bottom] * len(bad), "rx", ms=8,
                    label=f"diverged or failed ({len(bad)})")
        ax.set(xlabel=label(x_name, units), ylabel=label(report, units))
        if spec.get("log_y"):
            ax.set_yscale("log")
        ax.legend()
    else:
        xs, ys = sorted({r[x_name] for r in rows}), sorted({r[y_name] for r in rows})
        if len(xs) * len(ys) == len(rows):  # a grid: a heat map, failed cells blank
            z = np.full((len(ys), len(xs)), np.nan)
            for r in ok:
                z[ys.index(r[y_name]), xs.index(r[x_name])] = r[report]
            from matplotlib.colors import LogNorm
            norm = LogNorm() if spec.get("log_color") and np.nanmin(z, initial=np.inf) > 0 else None
            image = ax.pcolormesh(np.arange(len(xs) + 1), np.arange(len(ys) + 1), z, shading="flat", norm=norm)
            ax.set_xticks(np.arange(len(xs)) + 0.5, [f"{v:g}" if isinstance(v, float) else str(v) for v in xs])
            ax.set_yticks(np.arange(len(ys)) + 0.5, [f"{v:g}" if isinstance(v, float) else str(v) for v in ys])
            for r in ok:
                ax.text(xs.index(r[x_name]) + 0.5, ys.index(r[y_name]) + 0.5, f"{r[report]:.3g}", ha="center",
                        va="center", fontsize=8, color="white", path_effects=[_outline()])
            for r in bad:
                ax.text(xs.index(r[x_name]) + 0.5, ys.index(r[y_name]) + 0.5, r["status"], ha="center", va="center",
                        fontsize=7, color="red")
        else:
            image = ax.scatter([r[x_name] for r in ok], [r[y_name] for r in ok], c=[r[report] for r in ok], s=30)
            if bad:
                ax.plot([r[x_name] for r in bad], [r[y_name] for r in bad], "rx", label="diverged or failed")
                ax.legend()
        fig.colorbar(image, ax=ax, label=label(report, units))
        ax.set(xlabel=label(x_name, units), ylabel=label(y_name, units))
    if spec.get("log_x") and y_name is None:
        ax.set_xscale("log")
    ax.set_title(title)
    if y_name is None:
        ax.grid(True, alpha=0.3)
    else:
        ax.grid(False)
    fig.tight_layout()
    try:
        return write_figure(fig, path, 100, "the sweep's plot")
    finally:
        plt.close(fig)
