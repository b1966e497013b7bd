"""The paper's scene (Meng et al. 2010, Section 5): the PMSM-driven platform follows the 6-DOF
motion of Eq 35, with the 500 N impact of Eq 36 at 2.5 s; plots like Figs 7 and 8.

Runs the mechanics FMU with six pmsm_drive FMUs through cosim.system at a 1 ms step, and writes
to OUT: meng_eq35.csv (time, reference and actual pose, leg 1 length, motor torques, speeds and
q currents), meng_fig7_tracking.png and meng_fig8_motors.png. Until the master of issue 5 exists,
this fixed-step loop is the scene's runner.

    python -m cosim.meng_scene [--out out] [--stop-time 10] [--step 1e-3]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .parameter_sets import load  # noqa: E402
from .system import POSE, PlatformSystem  # noqa: E402

NEUTRAL_HEIGHT = 1.689527733348906  # z0 of the Meng layout [m] (mechanics FMU's neutral pose)
DOF = ["surge x [m]", "sway y [m]", "heave z [m]", "roll [rad]", "pitch [rad]", "yaw [rad]"]


def eq_35(t: float) -> np.ndarray:
    """Eq 35 about the neutral pose: surge 0.1, sway 0.2, heave 0.3 m at 0.2 Hz; roll 5, pitch 10,
    yaw 15 deg at 0.3 Hz."""
    a, b = np.sin(2 * np.pi * 0.2 * t), np.sin(2 * np.pi * 0.3 * t)
    return np.array([0.1 * a, 0.2 * a, NEUTRAL_HEIGHT + 0.3 * a,
                     np.radians(5) * b, np.radians(10) * b, np.radians(15) * b])


def eq_36(impact: dict):
    """The impact of Eq 36 from the [load] table of params/meng2010.toml: 500 N along the platform's
    z axis for 2.5 s <= t <= 2.52 s. We apply it along the base z axis; at the tilt of that instant
    (about 10 deg) the two differ by under 2 % of the force."""
    force, start, end = impact["impact_force_z"], impact["impact_start"], impact["impact_end"]

    def wrench(t: float) -> np.ndarray:
        return np.array([0.0, 0.0, force if start <= t <= end else 0.0, 0.0, 0.0, 0.0])

    return wrench


def run(stop_time: float = 10.0, step: float = 1e-3, impact: bool = True) -> tuple[np.ndarray, list[str], PlatformSystem]:
    meng = load("meng2010")
    # The drives start holding the platform's weight at the neutral pose (8.26 N m each, from the
    # mechanics' inverse model: the six legs share 950 kg plus their own parts' weight).
    hold_current = 8.264 / meng["motor"]["torque_constant"]
    system = PlatformSystem("pmsm", {}, {"initial.current_q": hold_current})
    system.record(["leg[1].length"], ["torque", "speed", "current.q"])
    result = system.run(stop_time, step, eq_35, eq_36(meng["load"]) if impact else None)
    names = ["time", *[f"pose_ref.{a}" for a in POSE], *[f"pose.{a}" for a in POSE], *system.record_names]
    return result, names, system


def plot(result: np.ndarray, names: list[str], out: Path) -> None:
    t = result[:, 0]
    fig, axes = plt.subplots(6, 2, figsize=(12, 13), sharex=True)
    for k, label in enumerate(DOF):
        axes[k, 0].plot(t, result[:, 1 + k], "k--", lw=1, label="desired")
        axes[k, 0].plot(t, result[:, 7 + k], lw=1, label="actual")
        axes[k, 0].set_ylabel(label)
        axes[k, 1].plot(t, result[:, 7 + k] - result[:, 1 + k], lw=1, color="tab:red")
        axes[k, 1].set_ylabel("error")
        for ax in axes[k]:
            ax.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    axes[0, 0].set_title("Pose tracking (Fig 7)")
    axes[0, 1].set_title("Tracking error; impact of Eq 36 at 2.5 s")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(out / "meng_fig7_tracking.png", dpi=100)
    plt.close(fig)

    fig, axes = plt.subplots(2, 1, figsize=(12, 8), sharex=True)
    column = {name: i for i, name in enumerate(names)}
    for i in range(1, 7):
        axes[0].plot(t, result[:, column[f"speed[{i}]"]], lw=1, label=f"W_m{i}")
        axes[1].plot(t, result[:, column[f"torque[{i}]"]], lw=1, label=f"T_a{i}")
    axes[0].set(title="Motor speeds (Fig 8a)", ylabel="speed [rad/s]")
    axes[1].set(title="Electromagnetic torques (Fig 8b)", ylabel="torque [N m]", xlabel="time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, ncol=6)
    fig.tight_layout()
    fig.savefig(out / "meng_fig8_motors.png", dpi=100)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("out"))
    parser.add_argument("--stop-time", type=float, default=10.0)
    parser.add_argument("--step", type=float, default=1e-3)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    result, names, system = run(args.stop_time, args.step)
    wall = time.perf_counter() - start
    np.savetxt(args.out / "meng_eq35.csv", result, delimiter=",", header=",".join(names), comments="")
    plot(result, names, args.out)
    error = np.abs(result[:, 7:13] - result[:, 1:7])
    print(f"Meng Eq 35 + Eq 36: {args.stop_time:g} s simulated in {wall:.2f} s wall "
          f"(real-time factor {args.stop_time / wall:.1f}), 7 FMUs at {args.step * 1e3:g} ms")
    print("largest tracking error after 0.5 s: " + ", ".join(
        f"{dof.split()[0]} {e:.2e}" for dof, e in zip(DOF, error[result[:, 0] > 0.5].max(axis=0))))
    warnings = [m.text for m in system.mechanics.messages if m.status == "warning"]
    if warnings:
        print(f"{len(warnings)} limit warnings from the mechanics, e.g. {warnings[0]}")
    print(f"wrote {args.out}/meng_fig7_tracking.png, meng_fig8_motors.png and meng_eq35.csv")
    system.free()


if __name__ == "__main__":
    main()
