"""Halder et al.'s Section V beside ours: the paper's stated numbers (the points a, b, c of Fig 2,
the admissible zones, the chosen design's running lengths and forces) against the map of a study
in the paper's plane (Halder's layout over r_b and z_p0), and the validation report's Figs 2-4."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...report.rows import Row
from .figures import plot_dynamic, plot_kinematic
from ..search.map import DesignMap, along, at, limit_along
from ..spec.study import Actuator, Study, stubs
from ..spec.verdicts import conditioning

PAPER = {"a": 1.19, "b": 1.06, "c": 0.62, "chosen": (1.10, 1.40), "lengths": (1.286, 1.647, 1.886),
         "zone_450": (1.25, 0.95), "zone_600": (1.10, 1.40)}
POINTS = {"a": "max stroke", "b": "min stroke", "c": "joint angle"}  # Fig 2's points: the constraint of each
POINTS_AT = 1.03  # [m] the base radius of Fig 2's points, along the sway motion


def is_section5(study: Study) -> bool:
    """A study of Halder's layout in the paper's plane (r_b, z_p0): its stated numbers apply."""
    return study.parameter_set == "halder2013" and list(study.axes) == ["base_radius", "disc_height"]


def shortest(study: Study) -> Actuator:
    return min(study.actuators, key=lambda a: a.stroke)


def longest(study: Study) -> Actuator:
    return max(study.actuators, key=lambda a: a.stroke)


def paper_points(design: DesignMap) -> dict[str, float | None]:
    """Fig 2's points a, b, c: along the sway motion at exactly r_b = 1.03 m (whatever rows the
    grid holds), over the grid's disc heights, for the shorter actuator, the z_p0 where each
    constraint starts or stops holding (None where none holds); empty where the map does not show
    them (another plane, no sway, r_b out of its range)."""
    rows = next(iter(design.study.axes.values()))
    if not (is_section5(design.study) and "sway" in design.motions and rows[0] <= POINTS_AT <= rows[-1]):
        return {}
    line = along(design.study, POINTS_AT)
    return {label: limit_along(line, shortest(design.study), constraint, "sway")
            for label, constraint in POINTS.items()}


def marks(design: DesignMap) -> tuple[dict[str, tuple[float, float]], dict[str, tuple[float, float]]]:
    """What the figures mark: the points a, b, c (on the shorter actuator's), the paper's chosen
    design (on the others'); both empty for a study outside the paper's plane."""
    points = {label: (POINTS_AT, z) for label, z in paper_points(design).items() if z is not None}
    return points, ({"chosen": PAPER["chosen"]} if is_section5(design.study) else {})


def _against(found: float | None, paper: float, study: Study) -> str:
    """How a point found on the grid's columns stands to the paper's."""
    step = study.step("disc_height")
    grid = f"the grid's step is {step:g} m" if step else "the grid has one disc height"
    if found is None:
        return f"the constraint holds at no disc height of the grid ({grid})"
    if abs(found - paper) < 1e-9:
        return ""
    return f"{1e3 * (found - paper):+.{max(0, study.decimals('disc_height') - 3)}f} mm; {grid}, the paper's figure " \
           "reads to 0.01 m"


def paper_rows(design: DesignMap) -> list[Row]:
    """Section V's stated numbers beside ours (validation rows), and what the paper's
    simplification of the dynamics costs, for a study over base_radius and disc_height. Every row
    about the paper's chosen design is of that design (evaluated at exactly its values); every
    row about the grid quotes the grid."""
    study = design.study
    d = {key: study.decimals(key) for key in study.axes}
    short, long_ = shortest(study), longest(study)
    out = []
    for label, found in paper_points(design).items():
        out.append(Row(f"point {label}: sway at r_b = {POINTS_AT:g} m, {POINTS[label]} limit ({short.name})",
                       f"{PAPER[label]:.2f}", "none" if found is None else f"{found:.{d['disc_height']}f}",
                       "m of z_p0", _against(found, PAPER[label], study)))
    (_, rows), (_, columns) = list(study.axes.items())
    for actuator, key in ((short, "zone_450"), (long_, "zone_600")):
        ok = design.admissible(actuator)
        r, c = np.nonzero(ok)
        out.append(Row(f"kinematically admissible zone, {actuator.name}", f"around ({PAPER[key][0]:.2f}, {PAPER[key][1]:.2f})",
                       f"centroid ({rows[r].mean():.{d['base_radius']}f}, {columns[c].mean():.{d['disc_height']}f}), "
                       f"{ok.sum()} points" if ok.any() else "none", "m (r_b, z_p0)",
                       "a band along the heave stroke limits, as the paper's figure"))
    return out + chosen_rows(design, at(study, dict(zip(study.axes, PAPER["chosen"]))))


def chosen_rows(design: DesignMap, chosen: DesignMap) -> list[Row]:
    """The paper's chosen design (`chosen`: its map of one point) beside the paper: admissible with
    the longer actuator, its running lengths, its forces, its conditioning; the grid's counts."""
    study, long_ = design.study, longest(design.study)
    s = stubs(study)
    r_b, z = PAPER["chosen"]
    where = f"r_b = {r_b:.2f} m, z_p0 = {z:.2f} m"
    failing = {name: [m for k, m in enumerate(chosen.motions) if not v[0, 0, k]]
               for name, v in chosen.kinematic_admissible(long_).items() if not v[0, 0].all()}
    needed = (chosen.actuated_length_min[0, 0].min() + s, chosen.neutral_length[0, 0] + s, chosen.actuated_length_max[0, 0].max() + s)
    note = []
    if "max stroke" in failing:
        highest = limit_along(along(study, r_b), long_, "max stroke", failing["max stroke"][0])
        step = study.step("disc_height")
        note.append(f"{', '.join(failing['max stroke'])} needs a running length of {1e3 * needed[2]:.0f} mm against "
                    f"the actuator's {1e3 * long_.running_length_max:.0f} mm; the highest z_p0 at r_b = {r_b:.2f} m that "
                    f"{failing['max stroke'][0]} admits is " + ("none of the grid" if highest is None else
                    f"{highest:.{study.decimals('disc_height')}f} m" + (f" (on the grid's {step:g} m steps)" if step else "")))
    out = [Row(f"{where} with {long_.name}", "admissible", "admissible" if not failing else "outside: " + "; ".join(
                   f"{name} in {', '.join(motions)}" for name, motions in failing.items()), "", "; ".join(note)),
           Row("running lengths there, min / neutral / max", " / ".join(f"{1e3 * v:.0f}" for v in PAPER["lengths"]),
               " / ".join(f"{1e3 * v:.0f}" for v in needed), "mm",
               "the paper quotes the actuator's limits, we what the motions need; the neutral matches by "
               "construction (params/halder2013.toml)")]
    if chosen.force_paper is not None:
        allowed = study.allowed_force(long_)
        friction, other = study.force_margins
        peak, peak_full = float(chosen.force_paper.max()), float(chosen.force_full.max())
        out.append(Row("peak leg force there, payload only (Eq 16)",
                       f"{long_.continuous_force:g} N less {friction:.0%} and {other:.0%}", f"{peak:.0f}", "N",
                       f"{'within' if peak <= allowed else 'above'} the {allowed:.0f} N the margins leave, read as "
                       f"'{study.force_margins_mode}'"))
        out.append(Row("the same with the legs' weight, inertia and friction", "", f"{peak_full:.0f}", "N",
                       f"what the paper's simplification leaves out; {'within' if peak_full <= allowed else 'above'} "
                       f"the {allowed:.0f} N"))
        full_ok = design.admissible(long_) & (design.force_full.max(axis=2) <= allowed)
        out.append(Row("admissible points of the grid with the force limit", "", f"{design.admissible(long_, True).sum()} / "
                       f"{full_ok.sum()} of {design.admissible(long_).sum()}", "points",
                       "payload only / full model, of the kinematically admissible"))
    share = float(np.mean(design.bottom_angle > design.top_angle + 1e-9))
    out.append(Row("bottom joint angle above the top one, over the grid", "never", f"{share:.1%} of points and motions",
                   "", ""))
    condition = float(chosen.condition[0, 0].max())
    out.append(Row(f"leg Jacobian at {where} over the motions", "",
                   f"smallest singular value {chosen.smallest_singular[0, 0].min():.3f}, condition number "
                   f"{condition:.1f}", "", conditioning(study, condition)))
    return out


def figures(design: DesignMap, folder: Path) -> list[Path]:
    """The validation report's Figs 2, 3 and 4 of the shipped Section V study's map."""
    points, chosen = marks(design)
    short, long_ = shortest(design.study), longest(design.study)
    return [plot_kinematic(design, short, folder / "halder_fig2.png", points),
            plot_kinematic(design, long_, folder / "halder_fig3.png", chosen),
            plot_dynamic(design, long_, folder / "halder_fig4.png", chosen)]
