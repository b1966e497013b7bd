"""The configuration design map (cosim.platform.design, Halder et al. Section V): how fast.

The shipped study's whole grid (studies/halder_section5.toml: r_b 0.8-1.5 m x z_p0 0.6-1.8 m in
0.01 m steps, six basic motions) is mapped in one run: the kinematic map alone and with the
dynamic map (two inverse-dynamics models per design), in one process, then on a LocalCluster of
one and of two worker processes. Reported: grid points per second, what one point costs against
its arithmetic (poses through the dynamics core), and the parallel efficiency T(1 worker) /
(2 T(2 workers)), with the cluster's start-up apart; and the co-simulated confirmations of the
study's [confirm] design (every basic motion through the co-simulation) per minute, in one process
and on two Dask workers; then studies/meng_eq35_platform.toml (a scene's motion as the specification) and
its confirmation through the PMSM drives.

    python benchmarks/design.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import publish  # noqa: E402
from cosim.engine.artifacts import ROOT  # noqa: E402
from cosim.platform.design import design_map, load_study, parallel_map, platform_values  # noqa: E402
from cosim.platform.design.search.confirm import confirm  # noqa: E402
from cosim.platform.design.spec.motion import basic_motions  # noqa: E402
from cosim.platform.core import Core  # noqa: E402


def main() -> None:
    study = load_study(ROOT / "studies" / "halder_section5.toml")
    kinematic = design_map(study, dynamic=False)
    dynamic = design_map(study, dynamic=True)
    timings = {}
    for workers in (1, 2):
        start = time.perf_counter()
        parallel_map(study, workers=workers)
        timings[workers] = time.perf_counter() - start
    one = timings[1]
    poses = study.samples * len(kinematic.motions)
    core = Core(actuators=False, motors=False, friction=False)
    core.use_start_values(platform_values(study, {"base_radius": 1.1, "disc_height": 1.4}))
    every = basic_motions(study, core.neutral_pose)
    import numpy as np
    stacked = np.concatenate([m[0] for m in every.values()])
    start = time.perf_counter()
    for _ in range(200):
        core.pose_kinematics(stacked, jacobian=True)
    per_pose = (time.perf_counter() - start) / 200 / len(stacked)
    lines = [f"| map ({kinematic.points} designs x {len(kinematic.motions)} motions) | wall [s] | designs per second |",
             "|---|---|---|",
             f"| kinematic, one process | {kinematic.seconds:.1f} | {kinematic.points / kinematic.seconds:.0f} |",
             f"| kinematic and dynamic, one process | {dynamic.seconds:.1f} | {dynamic.points / dynamic.seconds:.0f} |",
             f"| the same on 1 Dask worker (start-up included) | {one:.1f} | {dynamic.points / one:.0f} |",
             f"| the same on 2 Dask workers (start-up included) | {timings[2]:.1f} | {dynamic.points / timings[2]:.0f} |",
             "",
             f"Parallel efficiency T(1 worker) / (2 T(2 workers)): {one / (2 * timings[2]):.2f} (the cluster's start-up, "
             f"about 2-3 s, included in both). The kinematic map costs {1e6 * kinematic.seconds / kinematic.points / poses:.2f}"
             f" us per pose all told ({poses} poses per design); the dynamics core's own kinematics and leg Jacobian take "
             f"{1e6 * per_pose:.2f} us of it; the rest is building each design's platform, the Jacobian's singular "
             "values (at every tenth pose) and the Python around them."]
    actuator = study.actuator(study.confirm.actuator)
    confirmations = {}
    for workers in (0, 2):
        start = time.perf_counter()
        runs = confirm(study, study.confirm.point, actuator, workers=workers)
        confirmations[workers] = (len(runs), time.perf_counter() - start)
    simulated = sum(r["steps"] for r in runs) * 1e-3
    lines += ["", f"Co-simulated confirmations ({confirmations[0][0]} basic motions, {simulated:.0f} s simulated in all): "
              f"{60 * confirmations[0][0] / confirmations[0][1]:.0f} per minute in one process, "
              f"{60 * confirmations[2][0] / confirmations[2][1]:.0f} per minute on 2 Dask workers (the cluster's "
              "start-up included: with six short runs it outweighs the second core)."]
    meng = load_study(ROOT / "studies" / "meng_eq35_platform.toml")
    scene_map = design_map(meng)
    start = time.perf_counter()
    (driven,) = confirm(meng, meng.confirm.point, meng.actuator(meng.confirm.actuator), drive=meng.confirm.drive)
    driven_wall = time.perf_counter() - start
    lines += ["", f"A scene's motion as the specification ({meng.path.name}: {scene_map.points} designs of Meng's layout, "
              f"Eq 35 at {len(meng.recorded.times)} poses each, kinematic and dynamic): {scene_map.seconds:.1f} s in one "
              f"process ({scene_map.points / scene_map.seconds:.0f} designs per second). Its confirmation through six "
              f"PMSM drives ({driven['steps']} macro steps): {driven_wall:.2f} s."]
    print("\n".join(lines))
    publish("design", "python benchmarks/design.py", lines)


if __name__ == "__main__":
    main()
