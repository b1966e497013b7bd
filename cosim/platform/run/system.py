"""The platform as a system of FMUs: the trajectory FMU (reference pose and external wrench), the
mechanics FMU and six drive FMUs, wired as ../shared/INTERFACES.md says. This is the one wiring
table: the master, the SSP export and the other tools' runs all take it from `platform_structure`.

DRIVES holds what differs between drive kinds: swapping the kind changes those connections (and
the drive parameters that switch a wired input on) and nothing else. Each drive's effort (torque, force) and its flow (speed, velocity) form a power bond.
The default coupling is Gauss-Seidel with first-order extrapolation: the trajectory steps first
(its outputs' exact derivatives feed the mechanics), then the drives from the mechanics' last two
samples, then the mechanics with each effort interpolated between t and t + h.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

from ...engine import Bond, Component, Connection, Experiment, SystemStructure, fmu_path
from ..perception import CHANNELS, TWIST
from ..ports import BODY_WRENCH, DRIVES, LEGS, POSE, WRENCH, drive_names
from .envelope import GUARD_OUTPUTS


def platform_structure(drive: str, mechanics_values: Mapping[str, object] | None = None,
                       drive_values: Mapping[str, object] | None = None,
                       trajectory_values: Mapping[str, object] | None = None,
                       leg_values: Sequence[Mapping[str, object]] | None = None, name: str = "platform",
                       experiment: Experiment | None = None, interface_jacobian: bool = False,
                       drive_fmus: Sequence[Path] | None = None,
                       cueing_values: Mapping[str, object] | None = None, fmi: int = 2) -> SystemStructure:
    """Trajectory, mechanics and six drives of one kind with these parameter values (leg_values:
    per drive, on top of drive_values, e.g. each leg's force feedforward). drive_fmus: per leg, the
    drive's FMU (default: ours for the kind); a drive's optional ports (the reference's rate, the
    slope) are wired where its FMU has them. interface_jacobian: each drive's slope d effort / d
    flow feeds the mechanics, with the flow the drive was given (the mechanics' own flow output
    wired back to its `*_seen` input: every coupling algorithm hands both the same
    extrapolation), so the mechanics integrates the drives' damping implicitly. cueing_values: the
    pose reference comes from a cueing FMU with these values (a vehicle's motion through the
    classical washout), the trajectory's giving the loads alone. fmi: our FMUs as FMI 2.0 or 3.0."""
    from ...engine.checks import variables
    if drive not in DRIVES:
        raise ValueError(f"unknown drive kind '{drive}' (known: {', '.join(DRIVES)})")
    wiring = DRIVES[drive]
    fmus = [Path(f) for f in drive_fmus] if drive_fmus else [fmu_path(wiring.fmu, fmi=fmi)] * len(LEGS)
    has = {fmu: set(variables(fmu)) for fmu in set(fmus)}
    components = [Component("trajectory", fmu_path("trajectory", fmi=fmi), dict(trajectory_values or {})),
                  Component("mechanics", fmu_path("mechanics", fmi=fmi), dict(mechanics_values or {}))]
    for k, instance in enumerate(drive_names(drive)):
        wired = {key: value for key, value in wiring.wired_parameters if key in has[fmus[k]]}
        components.append(Component(instance, fmus[k], {**wired, **(drive_values or {}),
                                                        **(leg_values[k] if leg_values else {})}))
    if cueing_values is not None:
        components.insert(1, Component("cueing", fmu_path("cueing", fmi=fmi), dict(cueing_values)))
    source = pose_source(cueing_values is not None)
    connections = [*(Connection((source, f"pose_ref.{a}"), ("mechanics", f"pose_ref.{a}")) for a in POSE),
                   *(Connection(("trajectory", n), ("mechanics", n)) for n in [*WRENCH, *BODY_WRENCH])]
    source_fmu = next(c.fmu for c in components if c.name == source)
    if f"pose_ref_rate.{POSE[0]}" in variables(source_fmu):  # the exact rate, for masters without derivatives
        connections += [Connection((source, f"pose_ref_rate.{a}"), ("mechanics", f"pose_ref_rate.{a}")) for a in POSE]
    bonds = []
    for i, instance, fmu in zip(LEGS, drive_names(drive), fmus):
        for output, drive_input in (wiring.reference, wiring.position, wiring.velocity):
            connections.append(Connection(("mechanics", output.format(i=i)), (instance, drive_input)))
        flow = connections[-1]  # speed, velocity
        if wiring.reference_rate and wiring.reference_rate[1] in has[fmu]:
            output, drive_input = wiring.reference_rate
            connections.append(Connection(("mechanics", output.format(i=i)), (instance, drive_input)))
        effort, slope = Connection((instance, wiring.effort[0]), ("mechanics", wiring.effort[1].format(i=i))), None
        connections.append(effort)  # torque x speed, force x velocity
        if interface_jacobian and wiring.slope[0] in has[fmu]:
            slope_output, slope_input, seen_input = wiring.slope
            slope = Connection((instance, slope_output), ("mechanics", slope_input.format(i=i)))
            connections.append(slope)
            connections.append(Connection(("mechanics", wiring.velocity[0].format(i=i)),
                                          ("mechanics", seen_input.format(i=i))))
        bonds.append(Bond(effort, flow, slope))
    return SystemStructure(name, components, connections, bonds, experiment or Experiment())


def pose_source(cueing: bool) -> str:
    """The component that gives the mechanics its pose reference: the cueing FMU for a vehicle's
    motion, the trajectory otherwise."""
    return "cueing" if cueing else "trajectory"


def columns(drive: str, mechanics_outputs: Sequence[str] = (), drive_outputs: Sequence[str] = (),
            applied: bool = False, cueing: bool = False) -> tuple[list[tuple[str, str]], list[str]]:
    """What a platform run records and how the columns are named: pose_ref.<dof> (trajectory),
    pose.<dof> and the chosen mechanics outputs (mechanics), <output>[i] for each drive output;
    with `applied` (the interface-Jacobian coupling, where the legs feel the drives' efforts
    corrected by their slopes) the efforts the mechanics applied, <effort>_applied[i]; with
    `cueing` the pose reference from the cueing FMU, its tilt (tilt.roll, tilt.pitch), the vehicle's
    motion it took (vehicle.<channel>) and the platform's twist: what the occupant's perception is
    judged by (cosim.platform.perception); and the steps its guard held the reference back so far,
    by what held it (guard.held.<kind>)."""
    effort = DRIVES[drive].effort[0]
    record = [*[(pose_source(cueing), f"pose_ref.{a}") for a in POSE], *[("mechanics", f"pose.{a}") for a in POSE],
              *[("mechanics", n) for n in mechanics_outputs],
              *[(instance, n) for n in drive_outputs for instance in drive_names(drive)],
              *[("mechanics", f"leg[{i}].{effort}_applied") for i in LEGS if applied]]
    names = [*[f"pose_ref.{a}" for a in POSE], *[f"pose.{a}" for a in POSE], *mechanics_outputs,
             *[f"{n}[{i}]" for n in drive_outputs for i in LEGS], *[f"{effort}_applied[{i}]" for i in LEGS if applied]]
    if cueing:
        taken = [f"vehicle.{c}" for c in CHANNELS]
        twist = [n for n in TWIST if n not in mechanics_outputs]
        record += [("cueing", "tilt.roll"), ("cueing", "tilt.pitch"), *[("cueing", n) for n in taken],
                   *[("mechanics", n) for n in twist], *[("cueing", n) for n in GUARD_OUTPUTS]]
        names += ["tilt.roll", "tilt.pitch", *taken, *twist, *GUARD_OUTPUTS]
    return record, names
