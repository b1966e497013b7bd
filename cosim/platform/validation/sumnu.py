"""Sumnu (2015): the driving forces of Figs 4.3-4.6 with and without the lower leg's inertia (inverse
model), and the PID case studies of Section 5.2 (rigid force actuators: the linear-motor FMU with
its electrical dynamics switched off, an ideal force source) and Section 5.3 (linear motors), each
against the tracking-error bounds the thesis states.

The thesis does not publish its PID constants; every case runs with the linear-motor FMU's
default gains (a 10 Hz design for the heavy leg), not tuned to the thesis' bounds.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..report import plots
from ...engine.artifacts import ROOT
from ..scene.parameter_sets import mechanics_start_values
from ..core import Core
from ..run.runner import run_scene
from ..scene import Scene, Signal, Sine, load_scene, signals_document
from ..scene.signals import sine_motion
from ..ports import POSE
from ..report.rows import Row

W = 3.0  # rad/s, every trajectory of the thesis
F = W / (2 * np.pi)

TRAJECTORY_1 = {"x": Signal(-1.5, (Sine(0.2, F),)), "y": Signal(0.0, (Sine(0.2, F),)), "z": Signal(1.0, (Sine(0.2, F),))}
TRAJECTORY_2 = {"x": Signal(-1.5), "z": Signal(1.0), "yaw": Signal(0.0, (Sine(0.35, F),))}
FIGURES = [  # figure, trajectory, mass set
    ("4.4", TRAJECTORY_1, "light"), ("4.5", TRAJECTORY_1, "heavy"), ("4.6", TRAJECTORY_2, "heavy")]
WITHOUT_LOWER_PART = {"actuator.rotating_mass": 0.0, "actuator.rotating_inertia": 0.0}


def driving_forces(trajectory: dict[str, Signal], mass_set: str, lower_part: bool, n: int = 200):
    """Leg forces (n x 6) of the inverse model over 0 <= w t <= 2 pi."""
    values = mechanics_start_values("sumnu2015", mass_set)
    if not lower_part:
        values = {**values, **WITHOUT_LOWER_PART}
    core = Core().use_start_values(values)
    t = np.linspace(0.0, 2 * np.pi / W, n)
    pose, rate, acc = sine_motion(trajectory, t)
    return t, np.array([core.leg_forces(*m) for m in zip(pose, rate, acc)])


def figures_4(figures: Path | None = None) -> tuple[list[Row], dict]:
    rows, data = [], {}
    for figure, trajectory, mass_set in FIGURES:
        t, excluded = driving_forces(trajectory, mass_set, lower_part=False)
        _, included = driving_forces(trajectory, mass_set, lower_part=True)
        data[figure] = (t, excluded, included)
        rows.append(Row(f"Fig {figure} ({mass_set} set): peak leg force without / with the lower part's inertia",
                        "plots only", f"{np.abs(excluded).max():.1f} / {np.abs(included).max():.1f}", "N",
                        f"largest difference {np.abs(included - excluded).max():.2f} N"))
    if figures is not None:
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(3, 3, figsize=(13, 9), sharex=True)
        for row, (figure, (t, excluded, included)) in enumerate(data.items()):
            for col, (forces, title) in enumerate(((excluded, "excluded"), (included, "included"),
                                                   (included - excluded, "difference"))):
                axes[row, col].plot(W * t, forces, lw=1)
                axes[row, col].set_title(f"Fig {figure} ({'abc'[col]}): lower part inertia {title}", fontsize=9)
                axes[row, col].grid(True, alpha=0.3)
            axes[row, 0].set_ylabel("leg force [N]")
        for ax in axes[-1]:
            ax.set_xlabel("w t [rad]")
        plots.save_figure(fig, figures / "sumnu_fig4_forces.png")
    return rows, data


# ---- Section 5.2 and 5.3: PID case studies -------------------------------------------------------

CASES_5_2 = {  # start pose, mass set, trajectory, bounds (x, y, z [m]; roll, pitch, yaw [rad])
    "I": ([-1.5, 0, 1, 0, 0, 0], "light", TRAJECTORY_1, [1e-4, 1e-4, 1e-3, 2e-3, 2e-3, 1e-4]),
    "II": ([-1.5, 0, 1, 0, 0, 0], "heavy", TRAJECTORY_2, [1e-6, 1e-6, 1e-4, 1e-6, 1e-6, 1e-6]),
    "III": ([-1.3, 0.2, 1.2, 0, 0, 0], "heavy", TRAJECTORY_2, [1e-4, 1e-3, 1e-3, 1e-5, 1e-5, 1e-5]),
    # the thesis prints the yaw of IV as "1"; read as 0 (its other trajectories hold yaw at 0 or
    # move it about 0, and a 1 rad yaw would be far outside every other case)
    "IV": ([-1.3, 0.2, 1.2, 0, 0, 0], "heavy", {"x": Signal(-1.5, (Sine(0.1, F),)), "z": Signal(1.0),
                                                 "roll": Signal(0.0, (Sine(0.1, F),))}, [1e-4, 1e-5, 1e-3, 1e-3, 1e-3, 1e-3]),
}
BOUNDS_5_3 = {"I": [1e-4, 1e-4, 1e-3, 1e-3, 1e-4, 1e-4], "II": [1e-7, 1e-7, 1e-3, 1e-7, 1e-7, 1e-3],
              "III": [1e-5, 4e-4, 1e-3, 1e-3, 1e-3, 1e-3]}
SETTLED = 2.0  # s: errors are taken after the start transient
# Coupling step of the case studies. The linear motors' default gains are designed for the heavy
# leg; on the light set of case 5.2 I the loop is about twice as fast and diverges at 1 ms, without
# any limit tripping (issue 7's divergence detection is what should catch that). 0.2 ms is stable
# everywhere, and within 10 % of 0.1 ms.
STEP = 2e-4


def _errors(scene: Scene) -> np.ndarray:
    result, _ = run_scene(scene)
    late = result["time"] > SETTLED
    return np.array([np.abs(result[f"pose.{a}"] - result[f"pose_ref.{a}"])[late].max() for a in POSE])


def case_5_2(case: str, duration: float = 4.0) -> tuple[np.ndarray, list[float]]:
    start, mass_set, trajectory, bounds = CASES_5_2[case]
    scene = load_scene(ROOT / "scenes" / "sumnu_case_1.toml", {
        "scene.name": f"Sumnu 5.2 case {case}", "scene.duration": duration, "scene.step": STEP,
        "mechanics.mass_set": mass_set, "trajectory": signals_document(trajectory),
        "drive.parameters": {"effects.electrical": False},
        "mechanics.parameters": {f"initial.pose.{a}": v for a, v in zip(POSE, start)}})
    return _errors(scene), bounds


def case_5_3(case: str, duration: float = 4.0) -> tuple[np.ndarray, list[float]]:
    scene = load_scene(ROOT / "scenes" / f"sumnu_case_{['I', 'II', 'III'].index(case) + 1}.toml",
                       {"scene.duration": duration, "scene.step": STEP})
    return _errors(scene), BOUNDS_5_3[case]


def case_studies() -> tuple[list[Row], dict]:
    rows, data = [], {}
    for section, cases, run in (("5.2", CASES_5_2, case_5_2), ("5.3", BOUNDS_5_3, case_5_3)):
        for case in cases:
            errors, bounds = run(case)
            data[(section, case)] = (errors, np.array(bounds))
            ratio = errors / np.array(bounds)
            rows.append(Row(f"{section} case {case}: largest error after {SETTLED:g} s, x y z [m]; roll pitch yaw [rad]",
                            " ".join(f"{b:.0e}" for b in bounds), " ".join(f"{e:.1e}" for e in errors), "",
                            f"within the bound on {int((ratio <= 1).sum())} of 6 axes; worst {ratio.max():.2g}x the bound "
                            "(the thesis' PID constants are not published; ours are the FMU's 10 Hz defaults)"))
    return rows, data
