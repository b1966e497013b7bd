"""Meng et al. (2010): Figs 6-8 and Table 5 from the Meng scenes (scenes/meng_*.toml).

- tracking(): Eq 35 with the impact of Eq 36 (Figs 7, 8): per-DOF tracking errors, how long the
  start's torque shocks take to settle, and what the impact changes (a run without it is the
  reference).
- bandwidths(): Fig 6, closed-loop frequency response of each DOF from simulated sine responses.
- table_5(): the eight rows of Table 5 by Eq 40, in both readings of its A (peak value, as its text
  defines; peak-to-peak, as its name says), from the inverse model and from the closed loop.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ..report import plots
from ...engine.artifacts import ROOT
from ..core import Core
from ..run.runner import FIGURES, run_scene
from ..scene import Scene, Signal, Sine, load_scene, signals_document
from ..scene.signals import sine_motion
from ..report.plots import units
from ..ports import POSE, per_leg
from ..report.rows import Row

SCENES = ROOT / "scenes"
NEUTRAL_Z = 1.689527733348906
DOF_NAMES = {"x": "surge", "y": "sway", "z": "heave", "roll": "roll", "pitch": "pitch", "yaw": "yaw"}


def meng_scene(name: str = "meng_eq35", changes: dict | None = None) -> Scene:
    """A shipped Meng scene with values at dotted keys of its file (`changes`)."""
    return load_scene(SCENES / f"{name}.toml", changes)


def inverse_torques(scene: Scene, t: np.ndarray, core: Core | None = None) -> np.ndarray:
    """Motor torques (n x 6) the inverse model needs along the scene's reference (no load)."""
    core = core or Core()
    pose, rate, acc = sine_motion(scene.trajectory, t)
    return np.array([core.inverse_dynamics(p, r, a) for p, r, a in zip(pose, rate, acc)])


def _settling_time(t: np.ndarray, deviation: np.ndarray, band: float, start: float, end: float) -> float:
    """Time from `start` until `deviation` stays within `band` up to `end`."""
    window = (t >= start) & (t <= end)
    outside = np.nonzero(window & (deviation > band))[0]
    return float(t[outside[-1]] - start) if len(outside) else 0.0


def tracking(figures: Path | None = None) -> tuple[list[Row], dict]:
    """Figs 7 and 8: Eq 35 with the impact of Eq 36, and the same without the impact."""
    scene = meng_scene()
    result, report = run_scene(scene)
    if figures is not None:
        figures.mkdir(parents=True, exist_ok=True)
        impacts = sorted({(p.start, p.end) for p in scene.pulses})
        plots.plot_tracking(result, figures / "meng_eq35_tracking.png", scene.name, FIGURES["meng2010"][0], impacts)
        plots.plot_drives(result, figures / "meng_eq35_drives.png", scene.name, "torque", "speed", units("pmsm"),
                            FIGURES["meng2010"][1], impacts)
    # the same run without the impact: its pulses at zero, so that it takes the same steps
    quiet, _ = run_scene(scene.changed({"load.pulses": [dataclasses.replace(p, value=0.0).document()
                                                        for p in scene.pulses]}))
    t = result["time"]
    torque = np.column_stack([result[c] for c in per_leg("torque")])
    speed = np.column_stack([result[c] for c in per_leg("speed")])
    ideal = inverse_torques(scene, t)
    # start: the drives' torque against the inverse model's along the reference
    shock = np.abs(torque - ideal).max(axis=1)
    band = 0.05 * np.abs(ideal).max()
    start_settling = _settling_time(t, shock, band, 0.0, 2.0)
    # impact: this run against the run without it
    quiet_torque = np.column_stack([quiet[c] for c in per_leg("torque")])
    quiet_speed = np.column_stack([quiet[c] for c in per_leg("speed")])
    torque_change = np.abs(torque - quiet_torque).max(axis=1)
    after = (t >= 2.5) & (t <= 3.5)
    impact_peak = float(torque_change[after].max())
    impact_settling = _settling_time(t, torque_change, 0.05 * impact_peak, 2.52, 3.5)
    pose_change = np.array([np.abs(result[f"pose.{a}"] - quiet[f"pose.{a}"])[after].max() for a in POSE])
    speed_change = float(np.abs(speed - quiet_speed)[after].max())
    errors = report.largest_error
    rows = [Row(f"{DOF_NAMES[a]} tracking error, largest after 1 s", "'acceptable' (Fig 7, no number)",
                float(errors[k] * 1e3), "mm" if k < 3 else "mrad", "the paper gives plots only")
            for k, a in enumerate(POSE)]
    rows += [
        Row("torque shocks at the start settle within", "about 0.15 s (Fig 8b)", start_settling, "s",
            f"settled: every leg within {band:.2f} N m (5 % of the largest torque) of the inverse model's "
            "torque along the reference"),
        Row("impact (Eq 36): largest position change", "'do not change at all'", float(pose_change[:3].max() * 1e6),
            "um", f"rotations {pose_change[3:].max() * 1e6:.2f} urad; against the same run without the impact"),
        Row("impact: largest motor speed change", "'do not change at all'", speed_change, "rad/s",
            f"against motor speeds up to {np.abs(speed).max():.0f} rad/s"),
        Row("impact: largest torque shock", "'some shocks'", impact_peak, "N m", ""),
        Row("impact: torque shock settles within", "'a short time'", impact_settling, "s",
            "after the load ends (2.52 s), to 5 % of the shock"),
    ]
    data = dict(errors=errors, start_settling=start_settling, impact_settling=impact_settling,
                pose_change=pose_change, speed_change=speed_change, impact_peak=impact_peak,
                report=report)
    return rows, data


# ---- Fig 6: bandwidths --------------------------------------------------------------------------

FREQUENCIES = (1.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0, 14.0, 16.0, 18.0, 20.0, 25.0, 30.0, 40.0)
PAPER_BANDWIDTH = {"x": "14-15 Hz", "y": "14-15 Hz", "z": "11-12 Hz", "roll": "11-12 Hz", "pitch": "11-12 Hz",
                   "yaw": "14-15 Hz"}


def frequency_response(dof: str, frequency: float, amplitude: float | None = None) -> complex:
    """Closed-loop response pose/pose_ref of one DOF at one frequency: a small sine about the
    neutral pose (1 mm or 1 mrad), fitted over whole periods after the start transient."""
    amplitude = amplitude or 1e-3
    trajectory = {"z": Signal(NEUTRAL_Z), dof: Signal(NEUTRAL_Z if dof == "z" else 0.0, (Sine(amplitude, frequency),))}
    periods = max(3, int(np.ceil(0.3 * frequency)))
    settle = 0.4
    duration = settle + periods / frequency
    step = min(1e-3, 1.0 / (40 * frequency))
    scene = meng_scene(changes={"trajectory": signals_document(trajectory), "load.pulses": [],
                                "scene.duration": round(duration / step) * step, "scene.step": step})
    result, _ = run_scene(scene)
    t = result["time"]
    window = t >= t[-1] - periods / frequency - 1e-12
    w = 2 * np.pi * frequency
    basis = np.column_stack([np.sin(w * t[window]), np.cos(w * t[window]), np.ones(window.sum())])
    a, b, _ = np.linalg.lstsq(basis, result[f"pose.{dof}"][window], rcond=None)[0]
    return complex(a, b) / amplitude  # sin -> 1, so the phase is atan2(b, a)


def bandwidth(frequencies: np.ndarray, gain_db: np.ndarray) -> float:
    """First frequency where the gain falls through -3 dB (log-interpolated), or nan."""
    below = np.nonzero(gain_db < -3.0)[0]
    if not len(below) or below[0] == 0:
        return float("nan")
    k = below[0]
    f0, f1, g0, g1 = np.log(frequencies[k - 1]), np.log(frequencies[k]), gain_db[k - 1], gain_db[k]
    return float(np.exp(f0 + (f1 - f0) * (-3.0 - g0) / (g1 - g0)))


def bandwidths(figures: Path | None = None, frequencies=FREQUENCIES, dofs=POSE) -> tuple[list[Row], dict]:
    f = np.array(frequencies)
    responses = {dof: np.array([frequency_response(dof, x) for x in f]) for dof in dofs}
    found = {dof: bandwidth(f, 20 * np.log10(np.abs(r))) for dof, r in responses.items()}
    peaks = {dof: float(20 * np.log10(np.abs(r).max())) for dof, r in responses.items()}
    if figures is not None:
        import matplotlib.pyplot as plt
        fig, (gain_ax, phase_ax) = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
        for dof, r in responses.items():
            gain_ax.semilogx(f, 20 * np.log10(np.abs(r)), "o-", ms=3, label=f"{DOF_NAMES[dof]} ({found[dof]:.1f} Hz)")
            phase_ax.semilogx(f, np.degrees(np.unwrap(np.angle(r))), "o-", ms=3)
        gain_ax.axhline(-3, color="k", lw=0.8, ls="--")
        gain_ax.set(ylabel="gain [dB]", title="Closed-loop frequency response per DOF (as Meng Fig 6a)")
        phase_ax.set(ylabel="phase [deg]", xlabel="frequency [Hz]")
        for ax in (gain_ax, phase_ax):
            ax.grid(True, which="both", alpha=0.3)
        gain_ax.legend(fontsize=8)
        plots.save_figure(fig, figures / "meng_fig6_bode.png")
    rows = [Row(f"{DOF_NAMES[d]} bandwidth (-3 dB)", PAPER_BANDWIDTH[d], found[d], "Hz",
                f"resonance peak {peaks[d]:+.1f} dB" if peaks[d] > 0.5 else "") for d in dofs]
    return rows, dict(frequencies=f, responses=responses, bandwidths=found, peaks=peaks)


# ---- Table 5 ------------------------------------------------------------------------------------

TABLE_5 = [  # amplitude [m], angular frequency [rad/s], Ratio_1, Ratio_2 [%] as printed
    (0.01, 2 * np.pi, 4.0, 16.1), (0.01, 4 * np.pi, 8.8, 19.9), (0.01, 6 * np.pi, 13.2, 22.9),
    (0.1, 0.3 * np.pi, 3.8, 17.3), (0.1, 0.6 * np.pi, 8.2, 20.1), (0.025, 2 * np.pi, 6.0, 20.0),
    (0.3, 0.1 * np.pi, 2.3, 16.2), (0.3, 0.2 * np.pi, 3.2, 16.4),
]
VARIANTS = {"full": {}, "without motor systems": {"effects.motor_inertia": False},
            "without actuators and motor systems": {"effects.motor_inertia": False, "effects.actuator_inertia": False}}


def eq_40(with_effect: np.ndarray, without: np.ndarray, reading: str) -> float:
    """Eq 40 in % for torques (n x legs): A is the peak value (max |T| over legs and time) or the
    largest peak-to-peak value of a leg (max T - min T)."""
    def amplitude(torque):
        if reading == "peak":
            return np.abs(torque).max()
        return (torque.max(axis=0) - torque.min(axis=0)).max()
    return float(100 * abs(amplitude(with_effect) - amplitude(without)) / amplitude(with_effect))


# The closed-loop variants without the motor systems need a 0.2 ms coupling step: the drives' speed
# loops are designed for the motor-side inertia with the rotor (the paper's Table 2 design), and
# without the rotor's inertia they are about three times faster; at 1 ms and 0.5 ms they diverge.
CLOSED_LOOP_STEP = 2e-4


def _surge_scene(amplitude: float, w: float) -> Scene:
    """A surge sine from the neutral pose: 0.5 s to settle, then two periods (one if longer than 2 s)."""
    period = 2 * np.pi / w
    periods = 1 if period > 2.0 else 2
    trajectory = {"x": Signal(0.0, (Sine(amplitude, w / (2 * np.pi)),)), "z": Signal(NEUTRAL_Z)}
    return meng_scene("meng_surge_eq37", {"trajectory": signals_document(trajectory), "load.pulses": [],
                                          "scene.duration": round((0.5 + periods * period) * 1000) / 1000,
                                          "scene.step": CLOSED_LOOP_STEP})


def table_5(closed_loop: bool = True, rows: list[int] | None = None) -> tuple[list[Row], dict]:
    """Ratio_1 (motor systems) and Ratio_2 (actuators and motor systems) of every row (or of the
    given row indices), inverse model and (closed_loop) co-simulation with the drives, in both
    readings of Eq 40."""
    cores = {name: Core().use_start_values(values) for name, values in VARIANTS.items()}
    out = []
    for row in (rows if rows is not None else range(len(TABLE_5))):
        amplitude, w, paper_1, paper_2 = TABLE_5[row]
        scene = _surge_scene(amplitude, w)
        t = np.linspace(0.0, 2 * np.pi / w, 400)
        inverse = {name: inverse_torques(scene, t, core) for name, core in cores.items()}
        loop = {}
        if closed_loop:
            for name, values in VARIANTS.items():
                result, _ = run_scene(scene.changed({"mechanics.parameters": dict(values)}))
                late = result["time"] >= 0.5
                loop[name] = np.column_stack([result[c][late] for c in per_leg("torque")])
        entry = dict(row=row + 1, amplitude=amplitude, w=w, paper=(paper_1, paper_2))
        for model, torques in (("inverse", inverse), ("closed loop", loop)):
            if not torques:
                continue
            for reading in ("peak", "peak-to-peak"):
                entry[(model, reading)] = (eq_40(torques["full"], torques["without motor systems"], reading),
                                           eq_40(torques["full"], torques["without actuators and motor systems"],
                                                 reading))
        out.append(entry)
    table = []
    for e in out:
        def cell(model, reading):
            r = e.get((model, reading))
            return f"{r[0]:.1f} / {r[1]:.1f}" if r else "-"
        table.append(Row(f"{e['row']}: x = {e['amplitude']:g} sin({e['w'] / np.pi:g} pi t) m",
                        f"{e['paper'][0]:.1f} / {e['paper'][1]:.1f}",
                        cell("inverse", "peak"), "%",
                        f"peak-to-peak {cell('inverse', 'peak-to-peak')}; closed loop: peak {cell('closed loop', 'peak')}, "
                        f"peak-to-peak {cell('closed loop', 'peak-to-peak')}"))
    return table, dict(entries=out)


def surge_rows(entries) -> dict[str, np.ndarray]:
    """The entries as arrays: paper and ours (n x 2) per (model, reading)."""
    keys = [k for k in entries[0] if isinstance(k, tuple)]  # (model, reading)
    return {"paper": np.array([e["paper"] for e in entries]), **{k: np.array([e[k] for e in entries]) for k in keys}}


def stroke_study() -> tuple[list[Row], dict]:
    """Which stroke, or which middle leg length l_0, carries Eq 35 (issue 23): the scene's reference
    motion on Meng's platform with l_0 from 1.70 to 2.02 m in 10 mm steps (cosim.platform.design.
    scene_fit), every leg's range and the largest joint angle against the stroke and joint limit."""
    from ..design.search.scene_fit import scene_fit
    scene = meng_scene()
    fit = scene_fit(scene, "geometry.middle_leg_length", np.round(np.arange(1.70, 2.0201, 0.01), 10))
    k = int(np.argmin(np.abs(fit.values - 1.86)))
    centre = 0.5 * (fit.stroke[0] + fit.stroke[1])
    middle = 0.5 * (fit.shortest + fit.longest)
    centred = float(np.interp(centre, middle, fit.values))
    best = int(np.argmin(fit.needed_stroke))
    rows = [Row("Eq 35 on Meng's platform (l_0 = 1.86 m): leg lengths over the motion", "",
                f"{1e3 * fit.shortest[k]:.0f} - {1e3 * fit.longest[k]:.0f}", "mm",
                f"the stroke is {1e3 * fit.stroke[0]:.0f} - {1e3 * fit.stroke[1]:.0f} mm (Table 4): "
                f"{1e3 * (fit.stroke[0] - fit.shortest[k]):.0f} mm short at the bottom, "
                f"{1e3 * (fit.longest[k] - fit.stroke[1]):.0f} mm at the top"),
            Row("the stroke Eq 35 needs", f"{1e3 * (fit.stroke[1] - fit.stroke[0]):.0f} mm given",
                float(1e3 * fit.needed_stroke[k]), "mm",
                f"the least over the l_0 tried: {1e3 * fit.needed_stroke[best]:.0f} mm at l_0 = {fit.values[best]:.2f} m; "
                f"{'no' if not fit.carries.any() else int(fit.carries.sum())} l_0 of {len(fit.values)} carries it"),
            Row("l_0 that centres Eq 35 in the stroke", "1.86 m given", centred, "m",
                "the motion's middle leg length at the stroke's middle"),
            Row("largest joint angle over Eq 35", "", float(np.degrees(fit.joint_angle[k])), "deg",
                f"against the mechanics' default limit {np.degrees(fit.joint_limit):.0f} deg (Halder's; Meng gives none)")]
    return rows, dict(fit=fit, centred=centred)
