"""Halder et al.: the 6-SBU platform with ball-screw legs under feedforward plus PD control
(params/halder2013.toml), its 15 deg roll and 10 deg pitch demands, and the coupled translations
the five control strategies of its Fig 6 leave.

The legs are force actuators (the linear-motor FMU as an ideal force source, effects.electrical =
false) with a PD on the running length, limited to 830 N, plus a constant feedforward force per leg:
the paper's inverse model (Eq 16) at the target pose, which neglects the legs' weight and inertia
(the mechanics' static inverse dynamics with the leg masses switched off). The mechanics carries
the legs (upper part, lower part, motor) with their inertia, their spin with the payload, the
ball-screw's and the joints' viscous friction; as in the paper's forward model (Eq 23, which has no
gravity term for the legs), the legs carry no weight: gravity is the payload's weight, applied as
an external force at its centre of mass.

With the paper's gains (k_p = 500 N/m, k_d = 120 N s/m) our model of the platform is statically
unstable: the payload's centre of mass stands 0.285 m above the upper joints, an inverted pendulum
whose weight tips it faster than 500 N/m per leg can right it (a 1 deg roll step diverges; it holds
from k_p between 2000 and 3000 N/m). stability_threshold() measures that; the cases run at
GAIN_SCALE times the paper's gains, k_d scaled alike to keep the paper's k_d / k_p.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..report import plots
from ..scene.parameter_sets import read_parameter_set, mechanics_start_values
from ..core import Core
from ..scene import Pulse, Ramp, Signal, Step
from ..scene.signals import trajectory_parameters
from ...engine import FixedStep
from ...engine.outcome import RunStopped
from ...engine.run import Plan, run
from ..ports import POSE
from ..ports import platform_algorithm
from ..run.system import columns, platform_structure
from ..report.rows import Row

STEP = 1e-3
DURATION = 6.0
GAIN_SCALE = 10.0


@dataclass(frozen=True)
class Demand:
    name: str
    axis: str              # roll or pitch
    angle: float           # rad
    coupled: tuple[str, str]  # the translation it couples into, and heave
    compensation: tuple[float, float]  # Case 2's compensating demands [m]
    ramp_time: float       # s, of the 10 deg/s ramp (Cases 3-5)
    compensation_rate: tuple[float, float]  # Case 5's compensating rates [m/s]
    paper_per_degree: tuple[float, float]   # the paper's coupled errors [mm/deg]


ROLL = Demand("15 deg roll", "roll", np.radians(15.0), ("y", "z"), (0.0517, 0.0071), 1.5, (0.0345, 0.0047), (-3.5, -0.5))
PITCH = Demand("10 deg pitch", "pitch", np.radians(10.0), ("x", "z"), (-0.0346, 0.0030), 1.0, (-0.0345, 0.0030), (3.5, -0.3))
CASES = {1: "step", 2: "step with step compensation", 3: "10 deg/s ramp", 4: "ramp with step compensation",
         5: "ramp with compensation as rates"}


def _trajectory(demand: Demand, case: int, neutral: np.ndarray, angle: float | None = None) -> dict[str, Signal]:
    """The demand's basic motion (a step or a ramp to `angle`, default the demand's) from the
    neutral pose, with the strategy's compensation of the coupled DOFs."""
    angle = demand.angle if angle is None else angle
    steps: dict[str, list] = {dof: [] for dof in POSE}
    ramps: dict[str, list] = {dof: [] for dof in POSE}
    if case in (1, 2):
        steps[demand.axis].append(Step(0.0, angle))
    else:
        ramps[demand.axis].append(Ramp(0.0, demand.ramp_time, angle / demand.ramp_time))
    for dof, size, rate in zip(demand.coupled, demand.compensation, demand.compensation_rate):
        if case in (2, 4):
            steps[dof].append(Step(0.0, size))
        elif case == 5:
            ramps[dof].append(Ramp(0.0, demand.ramp_time, rate))
    return {dof: Signal(float(neutral[k]), steps=tuple(steps[dof]), ramps=tuple(ramps[dof]))
            for k, dof in enumerate(POSE)}


def feedforward(target: np.ndarray) -> np.ndarray:
    """The paper's constant feedforward: leg forces holding the payload at the target pose by its
    inverse model, which neglects the legs' weight, inertia and friction."""
    values = mechanics_start_values("halder2013")
    core = Core(actuators=False, motors=False, friction=False).use_start_values(values)
    return core.leg_forces(target, np.zeros(6), np.zeros(6))


def run_case(demand: Demand, case: int, duration: float = DURATION, gain_scale: float = GAIN_SCALE,
             angle: float | None = None, step: float = STEP) -> np.ndarray:
    """Results (time, pose_ref.*, pose.*) for one demand and strategy (angle: another basic angle,
    for the stability search). Raises RunStopped if the platform leaves its workspace."""
    c = read_parameter_set("halder2013")
    values = mechanics_start_values("halder2013")
    neutral = np.array([values[f"geometry.neutral.{a}"] for a in POSE])
    trajectory = _trajectory(demand, case, neutral, angle)
    target = np.array([trajectory[a].offset + sum(s.height for s in trajectory[a].steps)
                       + sum(r.slope * (r.end - r.start) for r in trajectory[a].ramps) for a in POSE])
    weight = values["platform.mass"] * values["environment.gravity_z"]
    values["environment.gravity_z"] = 0.0  # legs without weight, as in the paper's Eq 23
    drive = {"effects.electrical": False, "control.position_kp": gain_scale * c["control"]["kp"],
             "control.position_ki": 0.0, "control.position_kd": gain_scale * c["control"]["kd"],
             "limit.force": c["control"]["force_limit"], "limit.current": 1e6}
    legs = [{"force_ff": float(f)} for f in feedforward(target)]
    signals = trajectory_parameters(trajectory, [Pulse("force.z", weight, 0.0, 1e9)])
    structure = platform_structure("linear", values, drive, signals, leg_values=legs)
    return run(Plan(structure, platform_algorithm("linear"), FixedStep(step), duration, *columns("linear"),
                    clock="mechanics"))[0]


def stability_threshold(gain_scales=(1.0, 2.0, 4.0, 6.0, 8.0)) -> float:
    """The smallest of gain_scales at which a 1 deg roll step settles (roll error after 4 s below a
    tenth of the step and shrinking), or nan."""
    for scale in gain_scales:
        try:
            rows = run_case(ROLL, 1, duration=4.0, gain_scale=scale, angle=np.radians(1.0))
        except RunStopped:
            continue
        error, t = np.abs(rows["pose.roll"] - rows["pose_ref.roll"]), rows["time"]
        late, later = error[(t > 3.0) & (t <= 3.5)].max(), error[t > 3.5].max()
        if later < 0.1 * np.radians(1.0) and later <= late:
            return scale
    return float("nan")


def stiffness_balance(delta: float = 1e-5) -> dict:
    """The platform's static stiffness at the neutral, from its quasi-static potential
    V(q) = m g z + sum 1/2 k_p dl_i^2 - sum F_i dl_i (q the pose, F_i the legs' holding forces):
    K = s k_p J'J - sum F_i d2 l_i / dq2, the PD legs' stiffness against the loaded legs' geometric
    stiffness (a strut carrying F swings sideways with -F/L); the frame's origin is the payload's
    centre of mass, so gravity adds none of its own. Returns per DOF the PD and strut stiffness [N/m,
    N m/rad] and the gain scale each needs, and the scale s at which K turns positive definite."""
    values = mechanics_start_values("halder2013")
    core = Core().use_start_values(values)
    q0 = np.array([values[f"geometry.neutral.{a}"] for a in POSE])
    forces = feedforward(q0)
    lengths = core.leg_lengths
    e = np.eye(6) * delta
    J = np.column_stack([(lengths(q0 + e[a]) - lengths(q0 - e[a])) / (2 * delta) for a in range(6)])
    H = np.zeros((6, 6, 6))
    for a in range(6):
        for b in range(6):
            H[:, a, b] = (lengths(q0 + e[a] + e[b]) - lengths(q0 + e[a] - e[b]) - lengths(q0 - e[a] + e[b])
                          + lengths(q0 - e[a] - e[b])) / (4 * delta * delta)
    pd = read_parameter_set("halder2013")["control"]["kp"] * J.T @ J
    struts = -np.einsum("i,iab->ab", forces, H)
    return {"leg_force": float(np.mean(forces)), "leg_length": float(np.mean(lengths(q0))),
            "pd": np.diag(pd), "struts": np.diag(struts), "per_dof": -np.diag(struts) / np.diag(pd),
            "threshold": float(np.linalg.eigvals(np.linalg.solve(pd, -struts)).real.max())}


def per_millimetre_settling(band: float = 0.02) -> float:
    """The paper's k_p = 500 and k_d read as per millimetre (1000 x the per-metre reading): the time
    the 15 deg roll step of Case 1 takes to stay within `band` of itself [s]. These stiff legs need
    a 0.2 ms coupling step (1 ms diverges)."""
    rows = run_case(ROLL, 1, duration=3.0, gain_scale=1000.0, step=2e-4)
    error, t = np.abs(rows["pose.roll"] - rows["pose_ref.roll"]), rows["time"]
    outside = np.nonzero(error > band * abs(rows["pose_ref.roll"][-1]))[0]
    return float(t[outside[-1]]) if len(outside) else 0.0


def coupled_errors(rows: np.ndarray, demand: Demand, neutral_z: float) -> tuple[float, float, float]:
    """Steady state (mean of the last 0.5 s): the basic angle reached [deg], and the unwanted
    translation and heave: the payload's displacement from the neutral along them [mm], whatever
    the compensating demands asked."""
    late = rows["time"] >= rows["time"][-1] - 0.5
    pose = {a: rows[f"pose.{a}"][late].mean() for a in POSE}
    return (float(np.degrees(pose[demand.axis])), 1e3 * float(pose[demand.coupled[0]]),
            1e3 * float(pose["z"] - neutral_z))


def study(figures: Path | None = None) -> tuple[list[Row], dict]:
    neutral_z = mechanics_start_values("halder2013")["geometry.neutral.z"]
    threshold = stability_threshold()
    kp = read_parameter_set("halder2013")["control"]["kp"]
    balance = stiffness_balance()
    rows = [Row("smallest PD gain holding a 1 deg roll step", f"k_p = {kp:g} N/m works", threshold * kp, "N/m",
                "tried 1, 2, 4, 6, 8 x the paper's gains; below it the payload tips over (see text)"),
            Row("gain scale at which the static stiffness turns positive (linearised)", "1 x works",
                balance["threshold"], "x", "the legs' geometric stiffness against the PD (see text)")]
    rows += [Row(f"{a}: PD / loaded-strut stiffness at the paper's gains", "",
                 f"{balance['pd'][k]:.0f} / {balance['struts'][k]:.0f}", "N/m" if k < 3 else "N m/rad",
                 f"needs {balance['per_dof'][k]:.2f} x") for k, a in enumerate(POSE)]
    per_mm = per_millimetre_settling()
    rows.append(Row("15 deg roll step with the gains read per millimetre (1000 x, 0.2 ms coupling step)",
                    "settles in about 1 s", per_mm, "s", "into 2 % of the step; the paper's settling matches this "
                    "reading of its gains, not the per-metre one"))
    data = {"threshold": threshold, "per_millimetre_settling": per_mm, "balance": balance}
    for demand in (ROLL, PITCH):
        for case in CASES:
            result = run_case(demand, case)
            data[(demand.name, case)] = (result, coupled_errors(result, demand, neutral_z))
        angle, translation, heave = data[(demand.name, 1)][1]
        degrees = np.degrees(demand.angle)
        rows.append(Row(f"{demand.name}, Case 1: coupled {'sway' if demand.coupled[0] == 'y' else 'surge'} per degree",
                        f"{demand.paper_per_degree[0]:+.1f}", translation / degrees, "mm/deg",
                        f"basic angle reached {angle:.2f} deg"))
        rows.append(Row(f"{demand.name}, Case 1: coupled heave per degree", f"{demand.paper_per_degree[1]:+.1f}",
                        heave / degrees, "mm/deg", ""))
        for case in (2, 3, 4, 5):
            _, t, h = data[(demand.name, case)][1]
            paper = {2: "negligible", 3: "about Case 1's", 4: "negligible", 5: "negligible"}[case]
            rows.append(Row(f"{demand.name}, Case {case} ({CASES[case]}): steady coupled translation / heave "
                            "from the neutral",
                            paper, f"{t:+.1f} / {h:+.1f}", "mm", ""))
        # Case 5's largest transient heave, which the paper quotes (1.5 mm roll, 0.75 mm pitch)
        result = data[(demand.name, 5)][0]
        transient = 1e3 * np.abs(result["pose.z"] - neutral_z).max()
        rows.append(Row(f"{demand.name}, Case 5: largest transient coupled heave",
                        "about 1.5" if demand is ROLL else "about 0.75", transient, "mm", ""))
    if figures is not None:
        _plot(data, figures)
    return rows, data


def _plot(data: dict, figures: Path) -> None:
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(2, 3, figsize=(14, 7), sharex=True)
    for row, demand in enumerate((ROLL, PITCH)):
        j = POSE.index(demand.coupled[0])
        for case in CASES:
            rows = data[(demand.name, case)][0]
            t = rows["time"]
            axes[row, 0].plot(t, np.degrees(rows[f"pose.{demand.axis}"]), lw=1, label=f"{case}: {CASES[case]}")
            axes[row, 1].plot(t, 1e3 * rows[f"pose.{demand.coupled[0]}"], lw=1)
            axes[row, 2].plot(t, 1e3 * (rows["pose.z"] - rows["pose.z"][0]), lw=1)
        axes[row, 0].set_ylabel(f"{demand.axis} [deg]")
        axes[row, 1].set_ylabel(f"coupled {'sway' if j == 1 else 'surge'} [mm]")
        axes[row, 2].set_ylabel("coupled heave [mm]")
        axes[row, 0].set_title(f"{demand.name} (as Halder Fig 6)", fontsize=9)
    axes[0, 0].legend(fontsize=7)
    for ax in axes.ravel():
        ax.grid(True, alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    plots.save_figure(fig, figures / "halder_fig6.png")
