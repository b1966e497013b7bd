"""What a study assumes where its papers are loose, and what each assumption changes at the chosen
design: the force margins' reading, the payload (its inertia and where it came from) and, for
Halder's layout, the disc's plane as the design height and the stubs between the actuated and the
running length. Listed at the top of every summary and in the validation report, one line each."""

from __future__ import annotations

import copy

import numpy as np

from ...report.rows import Row
from ..search.map import DesignMap, at
from ..spec.study import MARGIN_MODES, Actuator, Study, parameter_set, point_text, stubs


def chosen(study: Study) -> tuple[dict[str, float], str]:
    """The design the assumptions are judged at, and which key named it: [study] chosen, else
    [confirm]'s, else [workspace]'s, else the grid's middle."""
    for point, key in ((study.chosen, "[study] chosen"), (study.confirm and study.confirm.point, "[confirm]"),
                       (study.workspace and study.workspace.point, "[workspace]")):
        if point:
            return point, key
    return {key: float(values[len(values) // 2]) for key, values in study.axes.items()}, "the grid's middle"


def judged_with(study: Study) -> Actuator:
    """The actuator the chosen design is judged with: [confirm]'s, [workspace]'s, [optimise]'s, else
    the longest stroke."""
    for spec in (study.confirm, study.workspace, study.optimise):
        if spec is not None:
            return study.actuator(spec.actuator)
    return max(study.actuators, key=lambda a: a.stroke)


def assumption_rows(study: Study) -> list[Row]:
    """One row per assumption: how the study reads it, and what it changes at the chosen design."""
    point, named = chosen(study)
    actuator = judged_with(study)
    here = at(study, point)
    rows = [_margins(study, actuator, here), _payload(study, point, here)]
    if study.parameter_set == "halder2013":
        rows += [_design_height(study, point, here), _stubs(study, actuator, here)]
    for row in rows:
        row.quantity = f"assumed: {row.quantity}"
    rows[0].quantity += f" (judged at {point_text(study, point)}, from {named}, with {actuator.name})"
    return rows


def _peak(design: DesignMap) -> tuple[float, str]:
    """The paper model's peak leg force at a one-design map, and the motion it comes in."""
    k = int(np.argmax(design.force_paper[0, 0]))
    return float(design.force_paper[0, 0, k]), design.motions[k]


def _margins(study: Study, actuator: Actuator, here: DesignMap) -> Row:
    friction, other = study.force_margins
    peak, motion = _peak(here)
    limits = {mode: study.allowed_force(actuator, mode) for mode in MARGIN_MODES}
    within = [mode for mode, limit in limits.items() if peak <= limit]
    verdict = ("within every reading" if len(within) == len(limits) else "above every reading" if not within else
               f"within {', '.join(within)} only")
    return Row(f"force margins {friction:.0%} and {other:.0%} read as '{study.force_margins_mode}'", "",
               f"{limits[study.force_margins_mode]:.0f}", "N",
               f"the peak leg force there, {peak:.0f} N ({motion}), is {verdict}: " + ", ".join(
                   f"{mode} {limit:.0f} N" for mode, limit in limits.items()))


def _payload(study: Study, point: dict[str, float], here: DesignMap) -> Row:
    mass, inertia = study.family.payload(parameter_set(study.parameter_set))
    ours = f"{study.payload_mass:g} kg, inertia ({', '.join(f'{v:g}' for v in study.payload_inertia)}) kg m^2"
    if np.allclose(study.payload_inertia, inertia):
        if study.payload_mass == mass:
            return Row("payload", "", ours, "", f"from {study.payload_from}: the parameter set's, nothing assumed")
        other, what = tuple(v * study.payload_mass / mass for v in inertia), "scaled by the mass"
    else:
        other, what = tuple(float(v) for v in inertia), f"the parameter set's ({mass:g} kg) unscaled"
    alternative = copy.copy(study)
    alternative.payload_inertia = other
    peak, motion = _peak(here)
    peak_other, motion_other = _peak(at(alternative, point))
    return Row("payload", "", ours, "", f"from {study.payload_from}; the peak leg force at the chosen design {peak:.0f} N "
               f"({motion}); with the inertia {what}, ({', '.join(f'{v:.4g}' for v in other)}) kg m^2: "
               f"{peak_other:.0f} N ({motion_other})")


def _at_values(study: Study, point: dict[str, float], changes: dict[str, float]) -> DesignMap:
    """The one-design map with some design values changed (on the axes or held fixed)."""
    alternative = copy.copy(study)
    alternative.fixed = {**study.fixed, **{k: v for k, v in changes.items() if k not in study.axes}}
    return at(alternative, {**point, **{k: v for k, v in changes.items() if k in study.axes}})


def _design_height(study: Study, point: dict[str, float], here: DesignMap) -> Row:
    values = {**study.family.design_values(parameter_set(study.parameter_set)), **study.fixed, **point}
    s = stubs(study)
    lower = _at_values(study, point, {"disc_height": values["disc_height"] - values["payload_com_above_disc"]})
    return Row("the design height z_p0 is the disc's (z_q0)", "", f"{values['disc_height']:g}", "m",
               f"the neutral running length there {1e3 * (here.neutral_length[0, 0] + s):.0f} mm (the paper's 1647 mm "
               f"at 1.4 m); read as the payload's centre of mass ({values['payload_com_above_disc']:g} m above the "
               f"disc): {1e3 * (lower.neutral_length[0, 0] + s):.0f} mm, {1e3 * (lower.actuated_length_min[0, 0].min() + s):.0f} "
               f"to {1e3 * (lower.actuated_length_max[0, 0].max() + s):.0f} mm over the motions")


def _stubs(study: Study, actuator: Actuator, here: DesignMap) -> Row:
    values = {**study.family.design_values(parameter_set(study.parameter_set)), **study.fixed}
    s = stubs(study)
    low, high = here.actuated_length_min[0, 0].min(), here.actuated_length_max[0, 0].max()

    def verdict(extra: float) -> str:
        fits = low + extra > actuator.running_length_min and high + extra < actuator.running_length_max
        return "within" if fits else "outside"
    return Row("the stubs between the joints and the actuator", "", f"{1e3 * s:.0f}", "mm",
               f"running length = actuated length + top_stub {values['top_stub']:g} m + bottom_stub "
               f"{values['bottom_stub']:g} m: {1e3 * (low + s):.0f} to {1e3 * (high + s):.0f} mm over the motions, "
               f"{verdict(s)} the actuator's {1e3 * actuator.running_length_min:.0f}-"
               f"{1e3 * actuator.running_length_max:.0f} mm; without them {1e3 * low:.0f} to {1e3 * high:.0f} mm, "
               f"{verdict(0.0)}")
