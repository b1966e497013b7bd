"""Plots of a platform run like Figs 7 and 8 of Meng et al. (2010); the results themselves are
written by cosim.engine.results."""

from __future__ import annotations

from pathlib import Path
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

DOF = ["x (surge) [m]", "y (sway) [m]", "z (heave) [m]", "roll [rad]", "pitch [rad]", "yaw [rad]"]


def save_figure(fig, path: Path) -> None:
    """Lays out, writes (creating the folder) and closes a figure."""
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def plot_tracking(result: np.ndarray, path: Path, title: str) -> None:
    t = result["time"]
    axes_names = ("x", "y", "z", "roll", "pitch", "yaw")
    fig, axes = plt.subplots(6, 2, figsize=(12, 13), sharex=True)
    for k, (label, a) in enumerate(zip(DOF, axes_names)):
        axes[k, 0].plot(t, result[f"pose_ref.{a}"], "k--", lw=1, label="desired")
        axes[k, 0].plot(t, result[f"pose.{a}"], lw=1, label="actual")
        axes[k, 0].set_ylabel(label)
        axes[k, 1].plot(t, result[f"pose.{a}"] - result[f"pose_ref.{a}"], lw=1, color="tab:red")
        axes[k, 1].set_ylabel("error")
        for ax in axes[k]:
            ax.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    axes[0, 0].set_title("Pose tracking (as Meng Fig 7)")
    axes[0, 1].set_title("Tracking error")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.suptitle(title)
    save_figure(fig, path)


def plot_drives(result: np.ndarray, path: Path, title: str, effort: str, speed: str) -> None:
    t = result["time"]
    fig, axes = plt.subplots(2, 1, figsize=(12, 8), sharex=True)
    for i in range(1, 7):
        axes[0].plot(t, result[f"{speed}[{i}]"], lw=1, label=f"leg {i}")
        axes[1].plot(t, result[f"{effort}[{i}]"], lw=1, label=f"leg {i}")
    axes[0].set(title=f"Drive {speed} (as Meng Fig 8a)", ylabel=speed)
    axes[1].set(title=f"Drive {effort} (as Meng Fig 8b)", ylabel=effort, xlabel="time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, ncol=6)
    fig.suptitle(title)
    save_figure(fig, path)
