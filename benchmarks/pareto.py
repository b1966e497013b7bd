"""The Pareto front over geometry and actuators (cosim.platform.design.search.pareto): how long, and what.

The shipped study studies/halder_pareto.toml (Halder's Section V motions; r_b, z_p0, an actuator of
a three-entry catalogue and a motor's screw lead; five objectives; NSGA-II, 40 x 25 evaluations)
searched in one process and on a LocalCluster of two worker processes in one run (the same front
both ways, checked), then its knee and each objective's best confirmed by co-simulation on the two
workers. Reported: the walls and their ratio, evaluations per second, the front's make-up and its
knee; the front's figure is written to docs/figures/halder_pareto.png for the user guide.

    python benchmarks/pareto.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import publish  # noqa: E402
from cosim.engine.artifacts import ROOT  # noqa: E402
from cosim.platform.design import load_study  # noqa: E402
from cosim.platform.design.answer.figures import plot_front  # noqa: E402
from cosim.platform.design.search.pareto import confirm_front, describe, pareto_front  # noqa: E402


def main() -> None:
    study = load_study(ROOT / "studies" / "halder_pareto.toml")
    spec = study.pareto
    here = pareto_front(study, workers=0)
    start = time.perf_counter()
    there = pareto_front(study, workers=2)
    on_dask = time.perf_counter() - start
    assert np.array_equal(here.values, there.values) and here.points == there.points, "Dask changed the front"
    start = time.perf_counter()
    confirm_front(study, there, workers=2)
    confirming = time.perf_counter() - start
    runs = [r for motions in there.confirmations.values() for r in motions]
    currents = [r for r in runs if "peak_current" in r]
    plot_front(study, there, ROOT / "docs" / "figures" / "halder_pareto.png")
    evaluations = spec.population * spec.generations
    share = ", ".join(f"{name} {sum(a.name == name for a in there.actuators)}" for name in spec.actuators)
    lines = ["| studies/halder_pareto.toml | wall [s] | evaluations per second |", "|---|---|---|",
             f"| NSGA-II, {spec.population} x {spec.generations} evaluations, one process | {here.seconds:.1f} | "
             f"{evaluations / here.seconds:.0f} |",
             f"| the same on 2 Dask workers (start-up included) | {on_dask:.1f} | {evaluations / on_dask:.0f} |",
             f"| knee and each objective's best co-simulated, {len(runs)} motions on 2 Dask workers | {confirming:.1f} "
             "| |", "",
             f"One process against two workers: {here.seconds / on_dask:.2f}x (the same front, bit for bit). "
             f"{len(there)} designs on the front ({share}); the knee: {describe(study, there, there.knee)}. "
             f"Its confirmations and the bests': peak leg force within "
             f"{max(abs(r['peak_force'] / r['predicted_peak'] - 1) for r in runs):.1%} of the full inverse dynamics; "
             + (f"the PMSM drives' peak current at most {max(r['peak_current'] for r in currents):.1f} A against their "
                f"{currents[0]['current_limit']:g} A limit." if currents else "no design of the front drives a motor.")]
    print("\n".join(lines))
    publish("pareto", "python benchmarks/pareto.py", lines)


if __name__ == "__main__":
    main()
