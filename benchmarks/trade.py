"""The speed-accuracy trade (issue 7), in one run: coupling algorithm x extrapolation order x macro
step (fixed and adaptive) x drive fidelity x mechanics effects x the interface-Jacobian coupling
(each drive's d effort / d flow applied in the mechanics), on the Meng scene and on a fast
small scene (Sumnu's case I, linear motors), next to libcosim stepping the same FMUs (fixed step,
and its ECCO algorithm with a power bond per drive).

For each point: the pose error against a converged reference, for our points the drive efforts'
error (torque or force as the legs feel them, at every step through the start-up, relative to the
peak, and in its worst window relative to the efforts' own change there and against the shipped
scenes' tolerances: cosim.platform.run.accuracy), the largest
energy residual of a bond in one step, macro steps, wall time and real-time factor. Our points
run as one sweep (cosim.engine.sweep) on every core. The reference is the scene under
Gauss-Seidel of order 1 at a sixteenth of its step; its convergence is shown as its difference to
the run at an eighth. Errors are taken at the same checkpoints (every 50 ms) for every run, ours and
libcosim's. Prints each scene's table and Pareto front, writes docs/trade.md and
docs/figures/trade_<scene>.png.

    .venv/bin/python benchmarks/trade.py [--probe 1.0]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import publish  # noqa: E402
from cosim.engine.artifacts import ROOT  # noqa: E402
from cosim.engine import EnergyControl  # noqa: E402
from cosim.platform.run.libcosim import run_in_libcosim  # noqa: E402
from cosim.platform.report.plots import save_figure  # noqa: E402
from cosim.engine.observers import TaskProgress  # noqa: E402
from cosim.engine.sweep import run_sweep  # noqa: E402
from cosim.platform.run.runner import run_scene  # noqa: E402
from cosim.platform.run.sweep import ScenePoint  # noqa: E402
from cosim.platform.scene import Scene, load_scene  # noqa: E402
from cosim.platform.ports import POSE  # noqa: E402


@dataclass
class Point:
    family: str          # "ours fixed", "ours doubling", "ours energy", "libcosim fixed", "libcosim ECCO"
    label: str
    error: float = float("nan")
    effort_error: float = float("nan")  # largest drive torque/force error / its peak (ours only)
    window_error: float = float("nan")  # the same in its worst window / the efforts' own change there (ours)
    tolerance_ratio: float = float("nan")  # its worst window against the shipped scenes' tolerances (<= 1: within)
    residual: float = float("nan")
    steps: int = 0
    wall: float = float("nan")
    diverged: bool = False


def _at(result: np.ndarray, checkpoints: np.ndarray) -> np.ndarray:
    return np.column_stack([np.interp(checkpoints, result["time"], result[f"pose.{a}"]) for a in POSE])


def _overrides(changes: dict) -> dict:
    """A point's changes to the scene as overrides at the scene file's keys."""
    keys = {"algorithm": "coupling.algorithm", "order": "coupling.order", "step": "scene.step",
            "step_control": "coupling.step_control", "rtol": "coupling.rtol", "atol": "coupling.atol",
            "startup_time": "coupling.startup_time", "startup_step": "coupling.startup_step",
            "interface_jacobian": "coupling.interface_jacobian"}
    out = {}
    for name, value in changes.items():
        if name in keys:
            out[keys[name]] = value
        else:  # drive or mechanics parameters
            table = {"drive": "drive.parameters", "mechanics": "mechanics.parameters"}[name]
            out.update({f'{table}."{k}"': v for k, v in value.items()})
    return out


def ours(scene: Scene, base: tuple, planned: list[tuple[str, str, dict]], reference: np.ndarray,
         checkpoints: np.ndarray) -> list[Point]:
    """Our engine's points, as one sweep on every core (cosim.engine.sweep): the pose error at the
    checkpoints (as libcosim's), the drive efforts' error at every step through the start-up."""
    evaluate = ScenePoint(str(scene.path), ("pose_error", "effort_error", "window_error", "tolerance_ratio",
                                            "energy_residual", "steps", "stepping_wall"),
                          base=base, reference=reference, checkpoints=tuple(checkpoints))
    with tempfile.TemporaryDirectory() as out:
        rows = run_sweep(f"trade {scene.path.stem}", [_overrides(changes) for _, _, changes in planned], evaluate,
                         evaluate.columns(), Path(out)).rows
    points = []
    for (label, family, _), row in zip(planned, rows):
        point = Point(family, label, wall=row.get("stepping_wall", float("nan")))
        if row["status"] != "ok":
            point.diverged = True
        else:
            point.error, point.effort_error = row["pose_error"], row["effort_error"]
            point.window_error, point.tolerance_ratio = row["window_error"], row["tolerance_ratio"]
            point.residual, point.steps = row["energy_residual"], int(row["steps"])
        points.append(point)
    return points


def pareto(points: list[Point]) -> list[Point]:
    good = sorted((p for p in points if not p.diverged and np.isfinite(p.error)), key=lambda p: p.wall)
    front, best = [], np.inf
    for p in good:
        if p.error < best:
            front.append(p)
            best = p.error
    return front


def study(scene: Scene, base: tuple, fidelities: dict[str, dict], effects: dict[str, dict]) -> tuple[list[Point], dict]:
    h = scene.step
    checkpoints = np.round(np.arange(0.05, scene.duration + 1e-9, 0.05), 9)
    reference_result, _ = run_scene(scene.changed({"scene.step": h / 16}))
    reference = _at(reference_result, checkpoints)
    eighth, _ = run_scene(scene.changed({"scene.step": h / 8}))
    convergence = float(np.abs(_at(eighth, checkpoints) - reference).max())
    planned = []
    for algorithm in ("gauss-seidel", "jacobi"):
        for order in (0, 1, 2):
            for factor in (0.25, 0.5, 1.0, 2.0):
                planned.append((f"{algorithm} {order}, {h * factor * 1e3:g} ms", "ours fixed",
                                dict(algorithm=algorithm, order=order, step=h * factor)))
    for tolerance in (1e-2, 1e-3, 1e-4):
        planned.append((f"doubling rtol=atol={tolerance:g}", "ours doubling",
                        dict(step_control="doubling", rtol=tolerance, atol=tolerance)))
        planned.append((f"energy rtol={tolerance:g}", "ours energy",
                        dict(step_control="energy", rtol=tolerance, atol=tolerance / 10)))
    for name, drive in fidelities.items():
        for factor in (0.5, 1.0):
            changes = dict(step=h * factor, drive=drive)
            if drive.get("solver.method") == 3 and scene.control.startup_time:  # one drive step per macro step
                changes["startup_step"] = h * factor / 16                  # needs the finer start finer
            planned.append((f"{name}, {h * factor * 1e3:g} ms", "ours fidelity", changes))
    for name, mechanics in effects.items():
        planned.append((f"{name}, {h * 1e3:g} ms", "ours effects", dict(mechanics=mechanics)))
    for algorithm, order in (("gauss-seidel", 1), ("gauss-seidel", 2), ("jacobi", 1)):  # the drives' slopes applied
        for factor in (0.5, 1.0, 2.0):
            planned.append((f"interface Jacobian, {algorithm} {order}, {h * factor * 1e3:g} ms", "ours interface Jacobian",
                            dict(algorithm=algorithm, order=order, step=h * factor, interface_jacobian=True)))
    planned.append((f"interface Jacobian, gauss-seidel 1, {2 * h * 1e3:g} ms, drives' RK4 at {h * 0.2e3:g} ms, "
                    f"mechanics' RK4 at {2 * h * 1e3:g} ms", "ours interface Jacobian",
                    dict(step=2 * h, interface_jacobian=True, drive={"solver.exponential": False, "solver.step": h * 0.2},
                         mechanics={"solver.method": 1, "solver.step": 2 * h})))
    if scene.control.startup_time:  # what the scene's finer start buys
        for factor in (0.5, 1.0):
            planned.append((f"gauss-seidel 1, {h * factor * 1e3:g} ms, no finer start", "ours fixed",
                            dict(step=h * factor, startup_time=0.0)))
    points = ours(scene, base, planned, reference_result, checkpoints)
    progress = TaskProgress(f"trade {scene.path.stem}: libcosim", 6)
    for factor in (0.25, 0.5, 1.0, 2.0):
        point = Point("libcosim fixed", f"libcosim fixed {h * factor * 1e3:g} ms")
        run = run_in_libcosim(scene.changed({"scene.step": h * factor}), checkpoints=checkpoints)
        point.error, point.wall = float(np.abs(run.poses - reference).max()), run.wall
        point.steps = int(round(scene.duration / (h * factor)))
        points.append(point)
        progress.advance(point.label)
    for tolerance in (1e-2, 1e-3):
        point = Point("libcosim ECCO", f"libcosim ECCO rtol=atol={tolerance:g}")
        run = run_in_libcosim(scene, checkpoints=checkpoints, ecco=EnergyControl(scene.step, rtol=tolerance, atol=tolerance,
                                                                                   h_min=1e-5))
        point.error, point.wall = float(np.abs(run.poses - reference).max()), run.wall
        points.append(point)
        progress.advance(point.label)
    return points, dict(convergence=convergence, duration=scene.duration)


def ratios(points: list[Point], duration: float) -> list[str]:
    lines = []
    usable = [p for p in points if not p.diverged and np.isfinite(p.error)]
    ours_points = [p for p in usable if p.family.startswith("ours")]
    for peer in (p for p in usable if p.family.startswith("libcosim")):
        match = [p for p in ours_points if p.error <= peer.error]
        if match:
            best = min(match, key=lambda p: p.wall)
            lines.append(f"- at libcosim's error {peer.error:.1e} ({peer.label}, {peer.wall:.2f} s): ours "
                         f"{best.wall:.3f} s ({best.label}), {peer.wall / best.wall:.1f}x less wall time")
    for adaptive in (p for p in usable if p.family == "ours doubling"):
        fixed = [p for p in usable if p.family == "ours fixed" and p.error <= adaptive.error]
        if fixed:
            best = min(fixed, key=lambda p: p.steps)
            lines.append(f"- {adaptive.label}: error {adaptive.error:.1e} in {adaptive.steps} macro steps; the best "
                         f"fixed step reaching it ({best.label}) takes {best.steps}: {best.steps / adaptive.steps:.1f}x")
    for target in (1e-4, 1e-5):
        match = [p for p in ours_points if p.error <= target]
        if match:
            best = min(match, key=lambda p: p.wall)
            lines.append(f"- cheapest run within {target:g} m/rad: {best.label}, real-time factor "
                         f"{duration / best.wall:.1f}; its drive efforts are off by {100 * best.effort_error:.1f} % "
                         "of their peak")
        else:
            lines.append(f"- no run of ours reaches {target:g} m/rad")
        windowed = [p for p in match if p.tolerance_ratio <= 1.0]
        if windowed:
            best = min(windowed, key=lambda p: p.wall)
            lines.append(f"- cheapest run within {target:g} m/rad and the shipped scenes' tolerances on the drive "
                         "efforts (2 % of their own change through the start-up, 1e-3 N m or 1e-3 of the static leg "
                         f"force in steady tracking): {best.label}, real-time factor {duration / best.wall:.1f}")
        both = [p for p in match if p.effort_error <= 0.01]
        if both:
            best = min(both, key=lambda p: p.wall)
            lines.append(f"- cheapest run within {target:g} m/rad and 1 % of the drive efforts' peak (through the "
                         f"start-up): {best.label}, real-time factor {duration / best.wall:.1f}")
        else:
            lines.append(f"- no run of ours reaches {target:g} m/rad with the drive efforts within 1 % of their peak "
                         "(the start-up shock's first milliseconds need finer steps)")
    return lines


def table(points: list[Point], duration: float) -> list[str]:
    front = set(id(p) for p in pareto(points))
    lines = ["| point | pose error [m, rad] | drive effort error [% of peak] | worst window [% of own change] | "
             "against the tolerances [<= 1: within] | largest bond residual [J] | macro steps | wall [s] | "
             "real-time factor | Pareto |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for p in sorted(points, key=lambda p: (p.diverged, p.wall)):
        error = "diverged" if p.diverged else f"{p.error:.2e}"
        effort = "" if p.diverged or not np.isfinite(p.effort_error) else f"{100 * p.effort_error:.2f}"
        residual = "" if p.diverged or not np.isfinite(p.residual) else f"{p.residual:.2e}"
        window = "" if p.diverged or not np.isfinite(p.window_error) else f"{100 * p.window_error:.2f}"
        ratio = "" if p.diverged or not np.isfinite(p.tolerance_ratio) else f"{p.tolerance_ratio:.2f}"
        lines.append(f"| {p.label} | {error} | {effort} | {window} | {ratio} | {residual} | {p.steps or ''} | {p.wall:.3f} | "
                     f"{duration / p.wall:.1f} | {'*' if id(p) in front else ''} |")
    return lines


def plot(points: list[Point], path: Path, title: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9, 6))
    for family, marker in (("ours fixed", "o"), ("ours doubling", "s"), ("ours energy", "D"), ("ours fidelity", "^"),
                           ("ours effects", "v"), ("ours interface Jacobian", "*"), ("libcosim fixed", "x"),
                           ("libcosim ECCO", "+")):
        chosen = [p for p in points if p.family == family and not p.diverged]
        if chosen:
            ax.loglog([p.wall for p in chosen], [p.error for p in chosen], marker, ls="", label=family, ms=6)
    front = pareto(points)
    ax.loglog([p.wall for p in front], [p.error for p in front], "k-", lw=0.8, label="Pareto front")
    ax.set(xlabel="wall time [s]", ylabel="largest pose error [m, rad]", title=title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    save_figure(fig, path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--probe", type=float, default=1.0, help="simulated seconds per point")
    args = parser.parse_args()
    meng = load_scene(ROOT / "scenes" / "meng_eq35.toml", {"scene.duration": args.probe, "load.pulses": []})
    sumnu = load_scene(ROOT / "scenes" / "sumnu_case_1.toml", {"scene.duration": args.probe})
    studies = [  # name, scene, the same as overrides of its file (for the sweep), fidelities, effects
        ("meng", meng, (("scene.duration", args.probe), ("load.pulses", [])), {"ideal inverter": {"inverter.model": 1}, "averaged inverter": {"inverter.model": 2},
                        "switching inverter": {"inverter.model": 3},
                        "averaged inverter, L-stable drives (ROS34PW2, one step per macro step; start at a sixteenth)":
                            {"inverter.model": 2, "solver.exponential": False, "solver.method": 3,
                             "solver.step": meng.step}},
         {"friction off": {"effects.friction": False}, "actuator inertia off": {"effects.actuator_inertia": False},
          "motor systems off": {"effects.motor_inertia": False}}),
        ("sumnu_case_1", sumnu, (("scene.duration", args.probe),), {"ideal force source": {"effects.electrical": False},
                                 "electrical dynamics": {"effects.electrical": True}},
         {"actuator inertia off": {"effects.actuator_inertia": False}}),
    ]
    doc = ["# The speed-accuracy trade", "",
           f"Rebuilt by `.venv/bin/python benchmarks/trade.py` (probes of {args.probe:g} s, this project's 2-core "
           "machine); see the script's docstring for the method. Wall times are of the stepping alone; our points run as one "
           "sweep on both cores, two at a time (which costs each about 5 %, benchmarks/sweep.py), libcosim's one at a "
           "time. The drive effort error is the largest torque (or force) difference to the reference at any step, "
           "through the start-up, relative to the reference's peak.", ""]
    summary = []
    for name, scene, base, fidelities, effects in studies:
        points, info = study(scene, base, fidelities, effects)
        summary += [f"{scene.name} ({args.probe:g} s probes; reference converged to {info['convergence']:.1e}):", "",
                    *ratios(points, info["duration"]), ""]
        lines = [f"## {scene.name}", "",
                 f"Reference converged to {info['convergence']:.1e} m/rad (its difference to half its step's run).",
                 "", *ratios(points, info["duration"]), "", *table(points, info["duration"]), "",
                 f"![trade](figures/trade_{name}.png)", ""]
        print("\n".join(lines))
        doc += lines
        plot(points, ROOT / "docs" / "figures" / f"trade_{name}.png", scene.name)
    (ROOT / "docs" / "trade.md").write_text("\n".join(doc))
    if args.probe == 1.0:  # the documented command
        publish("trade", "python benchmarks/trade.py", [*summary, "Every point's table and plot: "
                                                        "`docs/trade.md`."])


if __name__ == "__main__":
    main()
