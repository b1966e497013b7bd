"""CPU time per simulated second of one pmsm_drive instance, per inverter model, at the default
internal solver settings (Dormand-Prince 5(4), rtol = atol = 1e-6; switching: steps <= 5 us).

Duty: position loop following a 2 Hz, 10 rad sine (22 A peak) of the angle reference on the rigid motor-side
inertia of one leg (J_eq = 0.0209 kg m^2), coupled by cosim.bench. Only the time inside fmi2DoStep
is counted (time.process_time around each call), so the Python test bench is not in the figure;
the communication step is 1 ms (the platform's macro step) and 10 ms (fewer calls, showing the
per-call overhead). Ratios in the last columns come from the same run.

    python benchmarks/pmsm_drive.py [--seconds 2]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from cosim.fmu_instance import FmuInstance
from cosim.fmus import fmu_path
from cosim.loads import RigidInertia

MODELS = {1: "ideal", 2: "averaged", 3: "switching"}


def cpu_per_simulated_second(model: int, step: float, seconds: float) -> tuple[float, float]:
    drive = FmuInstance(fmu_path("pmsm_drive"), f"bench{model}")
    drive.initialize({"inverter.model": model})
    load = RigidInertia(0.0209)
    inputs = drive.real_group(["angle_ref", "angle", "speed"])
    torque = drive.real_group(["torque"])
    cpu = 0.0
    for k in range(int(round(seconds / step))):
        t = k * step
        inputs.write([10.0 * np.sin(2 * np.pi * 2 * t), load.angle, load.speed])
        start = time.process_time()
        drive.do_step(step)
        cpu += time.process_time() - start
        load.step(torque.read()[0], step)
    tracking = abs(load.angle - 10.0 * np.sin(2 * np.pi * 2 * seconds))
    switchings = drive.get("inverter.switchings")
    drive.free()
    return cpu / seconds, tracking if model != 3 else switchings / seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=2.0, help="simulated seconds per point")
    args = parser.parse_args()
    goals = {1: 2e-3, 2: 2e-3, 3: 0.5}
    print(f"{'inverter':<10} {'comm step':>9} {'CPU ms / sim s':>15} {'real-time factor':>17} {'vs goal':>8}  note")
    results = {}
    for model, name in MODELS.items():
        for step in (1e-3, 1e-2):
            if model == 3 and step == 1e-2:
                continue
            cpu, extra = cpu_per_simulated_second(model, step, args.seconds if model != 3 else min(args.seconds, 1.0))
            results[(model, step)] = cpu
            note = f"{extra:.0f} commutations/s" if model == 3 else f"end tracking error {extra:.2e} rad"
            print(f"{name:<10} {step*1e3:>7.0f}ms {cpu*1e3:>15.3f} {1/cpu:>17.0f} {cpu/goals[model]:>8.2f}  {note}")
    print(f"\nswitching / averaged CPU ratio at 1 ms: {results[(3, 1e-3)] / results[(2, 1e-3)]:.0f}")
    print(f"averaged, 1 ms / 10 ms communication step: {results[(2, 1e-3)] / results[(2, 1e-2)]:.2f}")


if __name__ == "__main__":
    main()
