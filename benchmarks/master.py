"""The Meng scene (scenes/meng_eq35.toml, 10 s with Eq 36's impact) in one run: each configuration
of our master with its errors against a converged reference, and libcosim (libcosimpy, the Open
Simulation Platform's engine) stepping the same eight FMUs with the same connections at the scene's
step.

Configurations: the paper's scene (Gauss-Seidel order 1 at 1 ms, the drives' exponential integrator
at 1 ms, the mechanics' Heun at 1 ms, the first 75 ms and the 5 ms after each edge of the impact at
a sixteenth: the cheapest numerics measured to hold the shipped scenes' tolerances); the same at its
numerics before (the drives' RK4 at the FMU's 0.1 ms, the first 0.1 s and 20 ms after each edge at a
sixteenth, the mechanics' RK4); with the mechanics' RK4 at 1 ms; with the drives' RK4 at 0.2 ms;
with the drives on the L-stable ROS34PW2 at the macro step; scenes/meng_eq35_fast.toml, the paper's
scene with the drives on two threads; and the interface-Jacobian coupling (each drive's d torque / d
speed applied in the mechanics) at 2 ms, the start and the 20 ms after each edge of the impact at a
sixteenth, the drives' RK4 at 0.2 ms and the mechanics' RK4 at 2 ms (on Heun's method, whose
stability interval is shorter, the slopes' damping makes it diverge as the finer start ends). For
each: the largest pose error [m, rad] and drive torque error [% of the torques' peak] at its own
steps, through the start-up and the impact, against the scene at 31.25 us throughout (its own
convergence is printed: its difference to the run at 62.5 us), the wall time (the best of five,
taken in rounds over the configurations so that a busy spell of the machine hits them alike), the
real-time factor and the master's share of the wall time. libcosim's fixed-step algorithm holds
inputs constant over a step (our order-0 Jacobi): its pose differs from ours by its coupling error
(trade.py measures it against the same kind of reference on 1 s probes).

The torques' error is also given per window (cosim.platform.run.accuracy): the start-up, the impact
with the 0.2 s after it, the steady tracking, each against the reference's own change there, so
that an error that passes as a fraction of the start-up shock's peak shows at its size through the
impact; for a configuration with the interface Jacobian, the torques the legs felt (what the run
records and plots as torque_applied).

End to end: `python -m cosim run scenes/meng_eq35.toml --no-plots` in a new process (imports, the
scene, the FMUs' instantiation, the run, the CSV, .mat and log), best of five (the machine's busy
spells only ever add), next to the stepping's own wall in it.

Every shipped scene at its defaults: its errors per window against the same scene at a 64th of its
step throughout (the pose after the first 10 ms; the drive efforts, the applied ones under the
interface Jacobian, through the start-up, each load pulse and the steady tracking, against the
reference's own change there), its wall time (best of three), real-time factor and master share;
and its floor: the CPU time per simulated second of its FMUs stepped alone from C
(benchmarks/fmu_step_bench.c) with the scene's parameter values at the scene's macro step and, for
the time the scene takes at the finer step, at that step (inputs held at zero and the platform
weightless, so that nothing leaves the workspace: fixed-step solvers cost the same whatever the
state), with the run's wall time over it.

    python benchmarks/master.py [--duration 10]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import publish, run_stepping  # noqa: E402
from cosim.engine.artifacts import ROOT  # noqa: E402
from cosim.engine.results import write_csv, write_mat  # noqa: E402
from cosim.platform.run.libcosim import run_in_libcosim  # noqa: E402
from cosim.engine.settings import FixedStep  # noqa: E402
from cosim.platform.run.compile import scene_structure  # noqa: E402
from cosim.platform.run.runner import run_scene  # noqa: E402
from cosim.platform.scene import load_scene, shipped_scenes  # noqa: E402
from cosim.platform.run.accuracy import AFTER, START_UP, difference, window_errors, windows  # noqa: E402
from cosim.platform.ports import DRIVES, POSE, per_leg  # noqa: E402

SCENE = ROOT / "scenes" / "meng_eq35.toml"
TORQUES = per_leg("torque")
POSES = [f"pose.{a}" for a in POSE]
FAST = ROOT / "scenes" / "meng_eq35_fast.toml"  # the same scene, faster drive numerics, two threads
ROUNDS = 5  # wall times: the best of this many, taken in rounds over the configurations
INTERFACE_JACOBIAN_2MS = {"scene.step": 2e-3, "coupling.interface_jacobian": True, "coupling.startup_time": 0.1,
                          "coupling.startup_step": 1.25e-4, "coupling.edge_time": 0.02,
                          'drive.parameters."solver.exponential"': False, 'drive.parameters."solver.step"': 2e-4,
                          'mechanics.parameters."solver.step"': 2e-3, 'mechanics.parameters."solver.method"': 1}
CONFIGURATIONS = [  # label, short label, scene file, overrides
    ("scenes/meng_eq35.toml, the paper's scene (Gauss-Seidel order 1, 1 ms, the drives' exponential integrator "
     "at 1 ms, the mechanics' Heun at 1 ms)", "the paper's scene", SCENE, {}),
    ("the paper's scene at its numerics before (the drives' RK4 at 0.1 ms, a 0.1 s start, 20 ms edges, the "
     "mechanics' RK4)", "its numerics before", SCENE,
     {'drive.parameters."solver.exponential"': False, 'drive.parameters."solver.step"': 1e-4,
      "coupling.startup_time": 0.1, "coupling.edge_time": 0.02, 'mechanics.parameters."solver.method"': 1}),
    ("the paper's scene, the mechanics' RK4 at 1 ms", "RK4 mechanics", SCENE, {'mechanics.parameters."solver.method"': 1}),
    ("the paper's scene, the drives' RK4 at 0.2 ms", "RK4 drives at 0.2 ms", SCENE,
     {'drive.parameters."solver.exponential"': False, 'drive.parameters."solver.step"': 2e-4}),
    ("the paper's scene, the drives on ROS34PW2 at the macro step", "ROS34PW2 drives", SCENE,
     {'drive.parameters."solver.exponential"': False, 'drive.parameters."solver.method"': 3,
      'drive.parameters."solver.step"': 1e-3}),
    ("scenes/meng_eq35_fast.toml: the paper's scene with the drives on two threads", "the fast scene", FAST, {}),
    ("interface Jacobian at 2 ms, start and impact edges at 1/16, drives' RK4 at 0.2 ms, mechanics' RK4 at 2 ms",
     "interface Jacobian, 2 ms (its applied torques)", SCENE, INTERFACE_JACOBIAN_2MS),
]
FLOOR_SECONDS = 5.0  # simulated seconds each FMU is stepped alone for its floor


def _renamed(result: np.ndarray, names: list[str], under: list[str] = TORQUES) -> np.ndarray:
    """The result with columns `names` under the columns `under` (the torques: to compare them alike)."""
    out = result.copy()
    for target, name in zip(under, names):
        out[target] = result[name]
    return out


def fine_time(scene) -> tuple[float, float]:
    """The scene's finer step and the simulated time it is taken at (its start and its windows)."""
    control = scene.control
    if not isinstance(control, FixedStep) or control.startup_time == 0.0:
        return scene.step, 0.0
    return control.startup_step, control.startup_time + sum(end - start for start, end in control.windows)


def floor(scene) -> dict[str, float]:
    """Per FMU of the scene (the six drives as one), CPU seconds per simulated second stepped alone
    from C at the scene's steps with its parameter values (strings such as a table's file left out,
    the platform weightless, the inputs at zero)."""
    fine_step, fine = fine_time(scene)
    out: dict[str, float] = {}
    for component in scene_structure(scene).components:
        name = Path(component.fmu).stem
        values = {k: v for k, v in component.parameters.items() if isinstance(v, (bool, int, float))}
        if name == "mechanics":
            values.update({"environment.gravity_x": 0.0, "environment.gravity_y": 0.0, "environment.gravity_z": 0.0})
        cost = run_stepping(name, scene.step, FLOOR_SECONDS, values, repeats=5) * (scene.duration - fine)
        if fine:
            cost += run_stepping(name, fine_step, min(FLOOR_SECONDS, fine), values, repeats=5) * fine
        key = "drives" if component.name not in ("mechanics", "trajectory") else component.name
        out[key] = out.get(key, 0.0) + cost / scene.duration
    return out


def shipped_table() -> tuple[list[str], dict[str, float]]:
    """Every shipped scene at its defaults: errors per window against its converged run, speed,
    floor (markdown lines), and per scene its floor [CPU s per simulated s], its wall time over the
    floor and its master share."""
    stats, where = {}, ""
    lines = ["| scene | pose [m, rad] | start-up | load pulses | steady tracking | macro steps | wall | real-time "
             "factor | master share | floor [ms/s]: mechanics + drives + trajectory | wall / floor |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for name in shipped_scenes():
        scene = load_scene(name)
        reference, _ = run_scene(load_scene(name, {"scene.step": scene.step / 64, "coupling.startup_time": 0.0,
                                                   "coupling.edge_time": 0.0}))
        runs = [run_scene(scene) for _ in range(3)]
        result, report = min(runs, key=lambda run: run[1].wall)
        late = result["time"] >= 0.01
        pose = max(float(np.abs(result[n] - np.interp(result["time"], reference["time"], reference[n]))[late].max())
                   for n in POSES)
        effort = DRIVES[scene.drive].effort[0]
        recorded = per_leg(effort + ("_applied" if scene.interface_jacobian else ""))
        errors = window_errors(_renamed(result, recorded, per_leg(effort)), reference, per_leg(effort),
                               windows(scene.duration, scene.pulses))
        unit = "N m" if scene.drive == "pmsm" else "N"

        def cell(kind: str) -> str:
            found = [e for e in errors if e.window == kind or (kind == "load pulse" and e.window.startswith(kind))]
            worst = max(found, key=lambda e: e.relative, default=None)
            return "-" if worst is None else f"{worst.error:.1e} {unit} ({100 * worst.relative:.2f} %)"
        parts = floor(scene)
        total = sum(parts.values())
        stats[name] = (total, report.wall / scene.duration / total, report.master_share, parts)
        if name == SCENE.stem:  # where the wall time over the floor goes, per FMU
            inside = {key: sum(v for k, v in report.fmi_seconds_by_instance.items()
                               if (k if k in ("mechanics", "trajectory") else "drives") == key) / scene.duration
                      for key in parts}
            where = (f"Where {name}'s wall time over its floor goes, per simulated second: inside the FMUs' calls "
                     "in the run (their inputs, outputs and output derivatives included) against the same FMUs "
                     "stepped alone, " + ", ".join(f"{key} {1e3 * inside[key]:.2f} ms against {1e3 * parts[key]:.2f}"
                                                   for key in ("mechanics", "drives", "trajectory"))
                     + f"; the master outside them {1e3 * (report.wall - report.fmi_seconds) / scene.duration:.2f} ms.")
        lines.append(f"| {name} | {pose:.1e} | {cell('start-up')} | {cell('load pulse')} | {cell('steady tracking')} | "
                     f"{report.macro_steps} | {report.wall:.3f} s | {report.real_time_factor:.0f} | "
                     f"{100 * report.master_share:.0f} % | {1e3 * total:.1f}: {1e3 * parts['mechanics']:.1f} + "
                     f"{1e3 * parts['drives']:.1f} + {1e3 * parts['trajectory']:.2f} | "
                     f"{report.wall / scene.duration / total:.2f} |")
    return [*lines, "", where], stats


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--duration", type=float, default=10.0)
    args = parser.parse_args()
    fine = {"scene.duration": args.duration, "coupling.startup_time": 0.0, "coupling.edge_time": 0.0}
    reference, _ = run_scene(load_scene(SCENE, {**fine, "scene.step": 3.125e-5}))
    coarser, _ = run_scene(load_scene(SCENE, {**fine, "scene.step": 6.25e-5}))
    peak = max(np.abs(reference[n]).max() for n in TORQUES)
    lines = [f"Meng scene, {args.duration:g} s with the impact, 8 FMUs (trajectory, mechanics, six drives); errors "
             f"against the scene at 31.25 us throughout (converged to {difference(coarser, reference, POSES):.1e} in pose "
             f"and {100 * difference(coarser, reference, TORQUES) / peak:.2f} % in torque: its difference to the run at "
             "62.5 us):", "",
             "| configuration | pose error [m, rad] | torque error [% of peak] | macro steps | wall | real-time factor "
             "| master share of wall |", "|---|---|---|---|---|---|---|"]
    best: dict[str, tuple] = {}
    for _ in range(ROUNDS):  # every configuration once per round, so a busy spell of the machine hits all
        for label, _, path, overrides in CONFIGURATIONS:
            run = run_scene(load_scene(path, {"scene.duration": args.duration, **overrides}))
            if label not in best or run[1].wall < best[label][1].wall:
                best[label] = run
    reports, by_window = {}, []
    spans = windows(args.duration, load_scene(SCENE).pulses)
    for label, short, _, _ in CONFIGURATIONS:
        result, report = best[label]
        reports[label] = report
        lines.append(f"| {label} | {difference(result, reference, POSES):.1e} | "
                     f"{100 * difference(result, reference, TORQUES) / peak:.2f} | {report.macro_steps} | "
                     f"{report.wall:.3f} s | {report.real_time_factor:.0f} | {100 * report.master_share:.0f} % |")
        # what the run plots as the drives' torque: the applied one under the interface Jacobian
        plotted = per_leg("torque_applied") if "torque_applied[1]" in result.dtype.names else TORQUES
        errors = [dataclasses.replace(e, error=a.error) for e, a in
                  zip(window_errors(result, reference, TORQUES, spans), window_errors(
                      _renamed(result, plotted), reference, TORQUES, spans))]
        by_window.append(f"| {short} | " + " | ".join(
            f"{e.error:.1e} ({100 * e.relative:.1f} %)" for e in errors) + " |")
    scene = load_scene(SCENE, {"scene.duration": args.duration})
    peer = run_in_libcosim(scene)
    lines.append(f"| libcosim (fixed step, inputs held), {scene.step * 1e3:g} ms | | | {round(args.duration / scene.step)} | "
                 f"{peer.wall:.3f} s | {args.duration / peer.wall:.0f} | |")
    shipped, before, rk4_mechanics, fast, jacobian = (reports[CONFIGURATIONS[k][0]] for k in (0, 1, 2, 5, 6))
    end_to_end, imports, libraries = [], [], []
    # the modules' bytecode cached, as an installed package has it (an environment that forbids
    # writing it, PYTHONDONTWRITEBYTECODE, compiles every module on every run: about 0.1 s more)
    environment = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    with tempfile.TemporaryDirectory() as out:
        for _ in range(5):
            began = time.perf_counter()
            subprocess.run([sys.executable, "-m", "cosim", "run", str(SCENE), "--no-plots", "--out", out,
                            "--duration", repr(args.duration)], check=True, capture_output=True, env=environment)
            end_to_end.append(time.perf_counter() - began)
            began = time.perf_counter()
            subprocess.run([sys.executable, "-c", "import cosim.cli, cosim.platform.run.runner"], check=True,
                           env=environment)
            imports.append(time.perf_counter() - began)
            began = time.perf_counter()
            subprocess.run([sys.executable, "-c", "import numpy, fmpy.fmi2, fmpy.model_description"], check=True,
                           env=environment)
            libraries.append(time.perf_counter() - began)
        ours = run_scene(load_scene(SCENE, {"scene.duration": args.duration}))[0]
        began = time.perf_counter()
        write_csv(ours, Path(out) / "timing.csv")
        write_mat(ours, Path(out) / "timing.mat")
        writing = time.perf_counter() - began
    final = np.array([ours[f"pose.{a}"][-1] for a in POSE])
    lines += ["", "The drive torques' error per window (cosim.platform.run.accuracy: the start-up's first "
              f"{START_UP:g} s, each load pulse and the {AFTER:g} s after it, the steady tracking between), in N m and "
              "relative to the reference torques' own change in that window:", "",
              "| configuration | " + " | ".join(w.name for w in spans) + " |",
              "|---|" + "---|" * len(spans), *by_window]
    table, stats = shipped_table()
    paper_floor, parts = stats[SCENE.stem][0], stats[SCENE.stem][3]
    one_core_each = parts["mechanics"] + parts["trajectory"] + parts["drives"] / 6
    near = [name for name, (_, ratio, _, _) in stats.items() if ratio <= 1.3]
    jacobian_floor = sum(floor(load_scene(SCENE, {"scene.duration": args.duration, **INTERFACE_JACOBIAN_2MS})).values())
    lines += ["", f"Ratios in this run: libcosim's wall / the paper's scene's {peer.wall / shipped.wall:.1f}, / the fast "
              f"scene's {peer.wall / fast.wall:.1f} (libcosim at 1 ms is {np.abs(final - peer.pose).max():.1e} "
              "from our final pose: its coupling error; benchmarks/trade.py compares the engines at equal error); the "
              f"paper's scene / its numerics before {shipped.wall / before.wall:.2f}, / the same with the mechanics' RK4 "
              f"{shipped.wall / rk4_mechanics.wall:.2f}, and the fast scene / "
              f"the paper's scene {fast.wall / shipped.wall:.2f} in wall time. End to end, `python -m "
              f"cosim run scenes/meng_eq35.toml --no-plots` takes {min(end_to_end):.2f} s [goal < 0.5 s]: "
              f"{min(imports):.2f} s starting Python and importing ({min(libraries):.2f} s of it Python with numpy and "
              f"fmpy alone, which no change of ours moves), {shipped.wall:.2f} s stepping, {writing:.2f} s "
              "writing the CSV and .mat (17 digits a value), the rest loading the scene and instantiating the FMUs.",
              "", f"The real-time factor's goal of 200 on the Meng scene: the paper's scene runs at "
              f"{shipped.real_time_factor:.0f}, {shipped.wall / args.duration / paper_floor:.2f}x its floor of "
              f"{1e3 * paper_floor:.1f} ms per simulated second (the FMUs' own arithmetic at its steps: at most "
              f"{1 / paper_floor:.0f} with a master that cost nothing: the FMUs' arithmetic at 1 ms alone is over a "
              "200th). A 2 ms step needs the interface Jacobian to stay stable (floor "
              f"{1e3 * jacobian_floor:.1f} ms/s, at most {1 / jacobian_floor:.0f}; it runs at "
              f"{jacobian.real_time_factor:.0f}), and there the slopes' correction leaves a systematic torque error "
              "that misses the steady-tracking and impact tolerances (the rows above; taking the slopes out gives it "
              "back, exact output derivatives of the motor speed do not: docs/guide/scenes.md). The paper's scene runs at the cheapest numerics measured "
              "within them, which its linear twin shares; the fast scene adds a second core. What would move "
              f"it: the floor is mechanics {1e3 * parts['mechanics']:.1f} + drives {1e3 * parts['drives']:.1f} + "
              f"trajectory {1e3 * parts['trajectory']:.1f} ms/s, the six drives {100 * parts['drives'] / paper_floor:.0f} "
              "% of it; with a core for each drive (the fast scene's threads, six of them) it would be the mechanics, "
              f"the trajectory and one drive, {1e3 * one_core_each:.1f} ms/s (at most {1 / one_core_each:.0f}); on "
              "one core, 200 needs the FMUs' arithmetic and every call between them within 5 ms/s, under the "
              "floor's arithmetic alone by half. "
              f"Within 1.3x of the floor [goal]: {len(near)} of the {len(stats)} shipped scenes ({', '.join(near) or 'none'}); the "
              f"master's share at most {100 * max(share for _, _, share, _ in stats.values()):.0f} % [goal 10 %]."]
    lines += ["", "Every shipped scene at its defaults (the efforts' errors per window in their unit and relative to "
              "the reference's own change there; the tolerances: pose 1e-5, 2 % through the start-up and each pulse, "
              "1e-3 N m or 1e-3 of the static leg force in steady tracking; tests/platform/test_scene_accuracy.py):", "",
              *table]
    print("\n".join(lines))
    if args.duration == 10.0:
        publish("master", "python benchmarks/master.py", lines)


if __name__ == "__main__":
    main()
