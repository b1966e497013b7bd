"""A design confirmed by co-simulation: each motion of the study played closed loop through the
mechanics FMU with the design's platform (legs, their weight, inertia and friction) and six drives
(ideal force sources, or our PMSM or linear-motor drive FMUs with the platform's drive set, their
loops designed for each leg), its leg forces and currents against the actuator's limits and the
full inverse dynamics' prediction."""

from __future__ import annotations

import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from ....engine import FixedStep
from ....engine.run import Plan, run
from ...core import Core
from ...ports import POSE, platform_algorithm
from ...report.rows import Row
from ...run.system import columns, platform_structure
from ...run.tuning import SizingError, check_limit, check_sizing, design, drive_defaults, leg_plants
from ...scene import Signal
from ...scene.parameter_sets import drive_set, drive_set_name
from ...scene.signals import trajectory_parameters
from ..spec.motion import displacements, motion_profile
from ..spec.schema import DRIVEN
from ..spec.study import DOFS, ROTATIONS, Actuator, Study, platform_values

HOLD = 0.5  # [s] at the start pose before a basic motion, and after it
START_UP = 0.2  # [s] of a motion that starts moving at once, left out of its forces and currents


def drive_parameters(study: Study, drive: str) -> tuple[dict, dict, str]:
    """For a confirmation through our drive FMU of kind `drive`: its parameters and what it changes
    on the legs (the platform's drive set where the project has one, e.g. meng2010_linear; the
    FMU's own defaults otherwise: Meng's PMSM, Sumnu's linear motor), and the drive's name."""
    name = drive_set_name(study.parameter_set, drive)
    if name is None:
        return {}, {}, {"pmsm": "pmsm_drive (Meng's PMSM, Table 2)", "linear": "linear_motor (Sumnu's motor)"}[drive]
    drive_values, mechanics_values = drive_set(name)
    return drive_values, mechanics_values, f"the drive set {name}"


def confirm_motion(study: Study, point: dict[str, float], actuator: Actuator, dof: str, step: float = 1e-3,
                   folder: Path | None = None, drive: str = "force") -> dict[str, Any]:
    """One motion of a design, closed loop through the co-simulation: the mechanics FMU with the
    study's platform (legs, their weight, inertia and friction), six drives (DRIVEN: ideal force
    sources, or our PMSM or linear-motor drive FMU with the platform's drive set), their loops
    designed for each leg's plant (tuning "auto"), the trajectory FMU playing the motion from a
    table (in `folder`, or a temporary one) after HOLD s at its start. Returns the largest
    tracking error (m, rad) after the first HOLD; over the motion the peak and rms leg force [N] (a
    PMSM's torque times K_FT) against the actuator's continuous force, and the full inverse
    dynamics' peak along the reference [N]; with our drives the peak and rms current [A] against
    the drive's current limit and the current the actuator's continuous force takes. A drive that
    cannot hold the start pose returns its reason as "problem"."""
    t, displacement, rates, accelerations = motion_profile(study, dof)
    kind, drive_values, on_legs, what = _drives(study, actuator, drive)
    values = {**platform_values(study, point, effects=True), **on_legs}
    core = Core().use_start_values(values)
    neutral = core.neutral_pose
    values.update({f"initial.pose.{axis}": float(v) for axis, v in zip(POSE, neutral + displacement[0])})
    problem = _sizing_problem(kind, drive, actuator, leg_plants(values), drive_values)
    if problem is not None:
        return {"motion": dof, "drive": what, "problem": problem}
    with _folder(folder) as where:  # the table lives until the run has read it
        table = _table(where / f"{dof}.csv", t, displacement)
        result = _closed_loop(kind, drive != "force", values, drive_values, neutral, table, step, HOLD + t[-1] + HOLD)
    # over the motion; where it starts moving at once (a recorded motion's rate at its start), from
    # START_UP later: no actuator follows a jump of speed, and its shock is the drive's, not the design's
    begins = HOLD + (START_UP if np.abs(rates[0]).max() > 0 else 0.0)
    late = result["time"] >= begins
    moving = late & (result["time"] <= HOLD + t[-1])
    force_torque = float(core.p.force_torque) if kind == "pmsm" else 1.0
    effort, current = EFFORT_CURRENT[kind]
    forces = force_torque * np.column_stack([result[f"{effort}{'_applied' if drive != 'force' else ''}[{i}]"]
                                             for i in range(1, 7)])
    out = {"motion": dof, "drive": what, "peak_force": float(np.abs(forces[moving]).max()),
           "tracking": max(float(np.abs(result[f"pose.{axis}"] - result[f"pose_ref.{axis}"])[late].max())
                           for axis in POSE),
           "rms_force": float(np.sqrt(np.mean(forces[moving] ** 2))),
           "predicted_peak": float(np.abs(core.leg_forces_many(neutral + displacement, rates, accelerations)).max()),
           "continuous_force": actuator.continuous_force, "steps": len(result) - 1, "from": begins - HOLD}
    if drive != "force":
        given = {**drive_defaults(kind), **drive_values}
        currents = np.column_stack([result[f"{current}[{i}]"] for i in range(1, 7)])[moving]
        per_ampere = force_torque * given["motor.torque_constant"] if kind == "pmsm" else given["motor.force_constant"]
        out.update(peak_current=float(np.abs(currents).max()), rms_current=float(np.sqrt(np.mean(currents ** 2))),
                   current_limit=float(given["limit.current"]), continuous_current=actuator.continuous_force / per_ampere)
    return out


EFFORT_CURRENT = {"pmsm": ("torque", "current.q"), "linear": ("force", "current")}  # recorded per drive kind


def _drives(study: Study, actuator: Actuator, drive: str) -> tuple[str, dict, dict, str]:
    """The drive FMU's kind, its values, what it changes on the legs and its name: ideal force
    sources (the linear motor with its electrical model off, at the actuator's continuous force,
    unlimited), or our drive with the platform's drive set."""
    if drive == "force":
        return "linear", {"effects.electrical": False, "motor.continuous_force": actuator.continuous_force,
                          "limit.force": 1e6, "limit.current": 1e6}, {}, DRIVEN["force"]
    return (drive, *drive_parameters(study, drive))


def _sizing_problem(kind: str, drive: str, actuator: Actuator, plants: list, drive_values: dict) -> str | None:
    """Why the actuator (its continuous force) or our drive cannot hold the start pose, or None."""
    try:
        for leg, plant in enumerate(plants, start=1):
            check_limit("linear", plant, actuator.continuous_force, f"{actuator.name}'s continuous force", leg)
        if drive != "force":
            check_sizing(kind, plants, drive_values)
    except SizingError as error:
        return str(error)
    return None


@contextmanager
def _folder(folder: Path | None) -> Iterator[Path]:
    """The given folder (made), or a temporary one removed afterwards."""
    if folder is not None:
        Path(folder).mkdir(parents=True, exist_ok=True)
        yield Path(folder)
        return
    with tempfile.TemporaryDirectory(prefix="cosim-confirm-") as scratch:
        yield Path(scratch)


def _table(path: Path, t: np.ndarray, displacement: np.ndarray) -> Path:
    """The motion as the trajectory FMU's table: HOLD s at its start, the motion, HOLD s at its end;
    instants that the offset by HOLD rounds onto the one before (a ramp far shorter than any step,
    from an all but unlimited acceleration) once."""
    times = np.r_[0.0, HOLD + t, HOLD + t[-1] + HOLD]
    played = np.vstack([displacement[:1], displacement, displacement[-1:]])
    keep = np.r_[True, np.diff(times) > 0]
    times, played = times[keep], played[keep]
    np.savetxt(path, np.column_stack([times, played]), delimiter=",", header=",".join(["time", *POSE]), comments="")
    return path


def _closed_loop(kind: str, ours: bool, values: dict, drive_values: dict, neutral: np.ndarray, table: Path,
                 step: float, duration: float) -> np.ndarray:
    """The platform playing the table about the neutral pose, each drive's loops designed for its
    leg: our drives through the interface Jacobian (their damping integrated implicitly by the
    mechanics: stable at the macro step on any geometry, their efforts recorded as the legs felt
    them), their start-up shock and the motion's start (a jump of the reference's rate where a
    recorded motion starts moving) at a sixteenth of the step, as the shipped scenes take them."""
    trajectory = trajectory_parameters({axis: Signal(offset=float(neutral[n])) for n, axis in enumerate(POSE)},
                                       table=table, interpolation="cubic")
    legs = [design(kind, [plant], drive_values)[0] for plant in leg_plants(values)]
    structure = platform_structure(kind, values, drive_values, trajectory, leg_values=legs, interface_jacobian=ours)
    control = FixedStep(step, 0.1, step / 16, ((HOLD - step, HOLD + 0.02),)) if ours else FixedStep(step)
    record = columns(kind, drive_outputs=EFFORT_CURRENT[kind], applied=ours)
    result, _ = run(Plan(structure, platform_algorithm(kind), control, duration, *record, clock="mechanics"))
    return result


def confirm(study: Study, point: dict[str, float], actuator: Actuator, workers: int | None = 0,
            scheduler: str | None = None, motions: tuple[str, ...] | None = None,
            drive: str = "force") -> list[dict[str, Any]]:
    """Every basic motion of a design through the co-simulation (confirm_motion), on Dask when
    workers/scheduler say so (one motion per task), in this process otherwise."""
    chosen = [m for m in displacements(study, False) if motions is None or m in motions]
    if workers == 0 and scheduler is None:
        return [confirm_motion(study, point, actuator, dof, drive=drive) for dof in chosen]
    from ....engine.sweep.dask_run import dask_client
    with dask_client(workers, scheduler) as client:
        return client.gather([client.submit(confirm_motion, study, point, actuator, dof, drive=drive, pure=False)
                              for dof in chosen])


def study_confirmation(study: Study, workers: int | None = 0, scheduler: str | None = None) -> list | None:
    """The study's [confirm] design through the co-simulation, or None if it names none."""
    spec = study.confirm
    if spec is None:
        return None
    return confirm(study, spec.point, study.actuator(spec.actuator), workers, scheduler, drive=spec.drive)


def confirmation_rows(runs: list[dict[str, Any]], where: str) -> list[Row]:
    """Each confirmed motion's forces and currents, as rows; `where`: the design and its actuator."""
    out = []
    for r in runs:
        quantity = f"co-simulated {r['motion']} ({where}; {r['drive']})"
        if "problem" in r:
            out.append(Row(quantity, "", "cannot hold the start pose", "", r["problem"]))
            continue
        unit = "rad" if r["motion"] in ROTATIONS else "m" if r["motion"] in DOFS else "m, rad"
        note = (f"the full inverse dynamics' peak {r['predicted_peak']:.0f} N "
                f"({100 * (r['peak_force'] / r['predicted_peak'] - 1):+.1f} %); tracking within "
                f"{r['tracking']:.1e} {unit}; continuous {r['continuous_force']:.0f} N")
        if r.get("from"):
            note += f"; from {r['from']:g} s into the motion (it starts moving at once)"
        if "peak_current" in r:
            note += (f"; current peak {r['peak_current']:.1f} A (limit {r['current_limit']:g} A), rms "
                     f"{r['rms_current']:.1f} A (the continuous force takes {r['continuous_current']:.1f} A)")
        out.append(Row(quantity, "", f"peak {r['peak_force']:.0f} N, rms {r['rms_force']:.0f} N", "N", note))
    return out
