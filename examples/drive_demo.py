"""One leg's PMSM drive on its test bench (the rigid motor-side inertia of a leg at the neutral
pose), with each of the three inverter models: ideal, averaged and switching.

Writes to OUT: pmsm_drive_demo.png (position step with each inverter model; the switching model's
phase currents in their hysteresis band) and one CSV per run, in fmpy's result convention.

    python examples/drive_demo.py [--out out]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from cosim.engine.artifacts import fmu_path  # noqa: E402
from cosim.engine.fmi import FmuInstance  # noqa: E402
from drive_bench import RigidInertia, run_on_inertia  # noqa: E402

J_EQ = 0.0209  # motor-side inertia of one leg at the neutral pose [kg m^2] (params/meng2010.toml)
INVERTERS = {1: "ideal", 2: "averaged", 3: "switching"}
RECORD = ["torque", "current.q", "voltage.q", "speed_ref", "current.a", "current.b", "current.c",
          "current_error.max", "power.electrical", "power.mechanical"]


def save_csv(result: np.ndarray, path: Path) -> None:
    np.savetxt(path, result, delimiter=",", header=",".join(result.dtype.names), comments="")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("out"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    path = fmu_path("pmsm_drive")

    step_angle = 5.0  # rad of motor angle = 18 mm of leg travel (screw ratio 277.8 rad/m)
    results = {}
    for model, name in INVERTERS.items():
        drive = FmuInstance(path, f"leg1_{name}")
        drive.initialize({"inverter.model": model})
        start = time.perf_counter()
        results[name] = run_on_inertia(drive, RigidInertia(J_EQ), 0.4, 5e-5 if model == 3 else 1e-4,
                                       lambda t: {"angle_ref": step_angle if t >= 0.02 else 0.0}, RECORD)
        wall = time.perf_counter() - start
        drive.free()
        save_csv(results[name], args.out / f"pmsm_step_{name}.csv")
        angle = results[name]["load.angle"]
        print(f"{name:>9}: final angle {angle[-1]:.4f} rad (ref {step_angle}), overshoot "
              f"{100 * (angle.max() / step_angle - 1):.1f} %, peak |i_q| {np.abs(results[name]['current.q']).max():.1f} A, "
              f"wall {wall:.2f} s")

    fig, axes = plt.subplots(2, 2, figsize=(12, 8))
    for name, r in results.items():
        axes[0, 0].plot(r["time"], r["load.angle"], label=name)
        axes[0, 1].plot(r["time"], r["load.speed"], label=name)
        axes[1, 0].plot(r["time"], r["torque"], label=name, lw=0.8)
    axes[0, 0].axhline(step_angle, color="k", ls=":", lw=0.8)
    axes[0, 0].set(title="Motor angle after a 5 rad step", xlabel="time [s]", ylabel="angle [rad]")
    axes[0, 1].set(title="Motor speed", xlabel="time [s]", ylabel="speed [rad/s]")
    axes[1, 0].set(title="Electromagnetic torque", xlabel="time [s]", ylabel="torque [N m]")
    sw = results["switching"]
    window = (sw["time"] >= 0.02) & (sw["time"] <= 0.035)
    for phase in "abc":
        axes[1, 1].plot(sw["time"][window] * 1e3, sw[f"current.{phase}"][window], lw=0.8, label=f"i_{phase}")
    axes[1, 1].set(title="Switching inverter: phase currents during the acceleration", xlabel="time [ms]",
                   ylabel="current [A]")
    for ax in axes.flat:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("pmsm_drive on one leg's motor-side inertia (Meng et al. 2010, Tables 2-4)")
    fig.tight_layout()
    fig.savefig(args.out / "pmsm_drive_demo.png", dpi=110)
    print(f"wrote {args.out / 'pmsm_drive_demo.png'} and the CSV files beside it")


if __name__ == "__main__":
    main()
