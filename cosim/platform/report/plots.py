"""Plots of a platform run like Figs 7 and 8 of Meng et al. (2010); the results themselves are
written by cosim.engine.results."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...engine.artifacts import fmu_path
from ...engine.checks import variables
from ...engine.files import write_figure
from ..ports import DRIVES, LEGS, POSE


def pyplot():
    """matplotlib's pyplot on the Agg backend, imported when a figure is drawn (a run without
    plots never loads it)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def units(drive: str) -> dict[str, str]:
    """The unit of every variable a platform run can record (the trajectory's, the mechanics' and
    the drive's; outputs first where two share a name), as the FMUs' modelDescriptions declare it,
    written for people (N.m -> N m), by variable name: a per-leg column `speed[3]` has the unit of
    the drive's `speed`."""
    found = [v for fmu in ("trajectory", "mechanics", DRIVES[drive].fmu) for v in variables(fmu_path(fmu)).values()]
    out: dict[str, str] = {}
    for v in sorted(found, key=lambda v: v.causality != "output"):
        if v.unit:
            out.setdefault(v.name, v.unit.replace(".", " "))
            if v.name.startswith("leg[1]."):  # a per-leg mechanics output, recorded as <name>[i]
                out.setdefault(v.name[len("leg[1]."):], v.unit.replace(".", " "))
    return out


DOF = ["x (surge) [m]", "y (sway) [m]", "z (heave) [m]", "roll [rad]", "pitch [rad]", "yaw [rad]"]


def save_figure(fig, path: Path, dpi: int = 100) -> Path:
    """Lays out, writes whole (creating the folder) and closes a figure."""
    try:
        fig.tight_layout()
        return write_figure(fig, path, dpi)
    finally:
        pyplot().close(fig)


DRIVE_QUANTITIES = {"torque": "motor torque", "speed": "motor speed", "current.q": "i_q", "force": "motor force",
                    "velocity": "leg velocity", "current": "current", "torque_applied": "applied motor torque",
                    "force_applied": "applied force"}


def _steady_limits(ax, t, values, start: float, margin: float = 0.15) -> None:
    """y limits from the part after `start` (the start-up transient would otherwise set the scale)."""
    late = np.asarray(values)[..., t >= start]
    if late.size and np.all(np.isfinite(late)):
        low, high = float(late.min()), float(late.max())
        pad = margin * (high - low or abs(high) or 1.0)
        ax.set_ylim(low - pad, high + pad)


def _mark(ax, windows) -> None:
    for start, end in windows:
        ax.axvspan(start, end, color="tab:orange", alpha=0.25, lw=0)


def plot_tracking(result: np.ndarray, path: Path, title: str, source: str = "", impacts=(), settle: float = 0.5) -> None:
    """Reference and actual pose per DOF, and the tracking error in mm or mrad, scaled to the steady
    error after `settle` seconds; an inset shows the whole error with the start-up. `source` names
    the paper's figure it corresponds to; `impacts` are (start, end) windows to mark."""
    t = result["time"]
    fig, axes = pyplot().subplots(6, 2, figsize=(12, 13), sharex=True)
    for k, (label, a) in enumerate(zip(DOF, POSE)):
        unit = "mm" if k < 3 else "mrad"
        error = 1e3 * (result[f"pose.{a}"] - result[f"pose_ref.{a}"])
        axes[k, 0].plot(t, result[f"pose_ref.{a}"], "k--", lw=1, label="reference")
        axes[k, 0].plot(t, result[f"pose.{a}"], lw=1, label="actual")
        axes[k, 0].set_ylabel(label)
        ax = axes[k, 1]
        ax.plot(t, error, lw=1, color="tab:red")
        ax.set_ylabel(f"{a} error [{unit}]")
        if t[-1] > 2 * settle:
            _steady_limits(ax, t, error, settle)
            inset = ax.inset_axes([0.78, 0.55, 0.2, 0.4])
            early = t <= 2 * settle
            inset.plot(t[early], error[early], lw=0.8, color="tab:red")
            inset.set_title("start-up", fontsize=6)
            inset.tick_params(labelsize=6)
        for panel in axes[k]:
            panel.grid(True, alpha=0.3)
            _mark(panel, impacts)
    axes[0, 0].legend(fontsize=8)
    axes[0, 0].set_title("Pose: reference and actual" + (f" ({source})" if source else ""))
    axes[0, 1].set_title(f"Tracking error (scaled to t > {settle:g} s; impact shaded)" if impacts else
                         f"Tracking error (scaled to t > {settle:g} s)")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.suptitle(title)
    save_figure(fig, path)


def plot_drives(result: np.ndarray, path: Path, title: str, effort: str, speed: str, units: dict[str, str],
                source: str = "", impacts=(), settle: float = 0.5) -> None:
    """Each drive's speed and effort (torque or force) with their units (by variable name, as
    cosim.platform.report.plots.units gives them), scaled to after the start-up, and, for each impact,
    the effort enlarged around it: the shock the drives take while the pose stays put is what
    Meng's Fig 8 shows."""
    t = result["time"]
    rows = 2 + (1 if impacts else 0)
    fig, axes = pyplot().subplots(rows, 1, figsize=(12, 4 * rows))
    (speed_name, speed_unit), (effort_name, effort_unit) = ((DRIVE_QUANTITIES[q], units[q]) for q in (speed, effort))
    for i in LEGS:
        axes[0].plot(t, result[f"{speed}[{i}]"], lw=1, label=f"leg {i}")
        axes[1].plot(t, result[f"{effort}[{i}]"], lw=1, label=f"leg {i}")
    for ax, name, unit, var in ((axes[0], speed_name, speed_unit, speed), (axes[1], effort_name, effort_unit, effort)):
        ax.set(ylabel=f"{name} [{unit}]", xlabel="time [s]")
        if t[-1] > 2 * settle:
            _steady_limits(ax, t, np.array([result[f"{var}[{i}]"] for i in LEGS]), settle)
        _mark(ax, impacts)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, ncol=6)
    axes[0].set_title(f"Drive {speed_name}" + (f" ({source})" if source else "") + f", scaled to t > {settle:g} s")
    axes[1].set_title(f"Drive {effort_name}" + (", impact shaded" if impacts else ""))
    if impacts:
        start, end = impacts[0]
        window = (t >= start - 0.05) & (t <= end + 0.15)
        for i in LEGS:
            axes[2].plot(t[window], result[f"{effort}[{i}]"][window], lw=1, label=f"leg {i}")
        _mark(axes[2], impacts)
        axes[2].set(title=f"{effort_name} around the impact at {start:g} s", ylabel=f"{effort_name} [{effort_unit}]",
                    xlabel="time [s]")
        axes[2].grid(True, alpha=0.3)
    fig.suptitle(title)
    save_figure(fig, path)


def plot_perception(perceived, path: Path, title: str) -> None:
    """Motion cueing judged by perception (cosim.platform.perception.Perceived): per channel the
    vehicle's motion, what the occupant would perceive of it, and what the occupant perceives of
    the platform's motion at the head."""
    from ..perception import CHANNELS, UNITS
    fig, axes = pyplot().subplots(3, 2, figsize=(12, 10), sharex=True)
    t = perceived.times
    for c, (channel, unit) in enumerate(zip(CHANNELS, UNITS)):
        ax = axes[c % 3, c // 3]
        ax.plot(t, perceived.vehicle[:, c], color="0.6", lw=1, label="vehicle")
        ax.plot(t, perceived.vehicle_perceived[:, c], "k--", lw=1.2, label="perceived in the vehicle")
        ax.plot(t, perceived.platform_perceived[:, c], color="tab:blue", lw=1.2, label="perceived on the platform")
        ax.set_ylabel(f"{channel}{' - g' if channel.endswith('force.z') else ''} [{unit}]")
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    axes[0, 0].set_title("specific force (otoliths)")
    axes[0, 1].set_title("angular velocity (semicircular canals)")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.suptitle(title)
    save_figure(fig, path)
