"""Halder et al.'s Section V beside ours: the paper's stated numbers (the points a, b, c of Fig 2,
the admissible zones, the chosen design's running lengths and forces) against the map of a study
in the paper's plane (Halder's layout over r_b and z_p0), and the validation report's Figs 2-4."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..report.rows import Row
from .figures import plot_dynamic, plot_kinematic
from .map import DesignMap, limit_along, nearest
from .study import Actuator, Study, stubs

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
    """Fig 2's points a, b, c on the map: along the sway motion at r_b = 1.03 m, for the shorter
    actuator, the z_p0 where each constraint starts or stops holding (None where none holds);
    empty where the map does not show them (another plane, no sway, r_b out of its range)."""
    rows = next(iter(design.study.axes.values()))
    if not (is_section5(design.study) and "sway" in design.motions and rows[0] <= POINTS_AT <= rows[-1]):
        return {}
    return {label: limit_along(design, shortest(design.study), constraint, "sway", POINTS_AT)
            for label, constraint in POINTS.items()}


def marks(design: DesignMap) -> tuple[dict[str, tuple[float, float]], dict[str, tuple[float, float]]]:
    """What the figures mark: the points a, b, c (on the shorter actuator's), the paper's chosen
    design (on the others'); both empty for a study outside the paper's plane."""
    points = {label: (POINTS_AT, z) for label, z in paper_points(design).items() if z is not None}
    return points, ({"chosen": PAPER["chosen"]} if is_section5(design.study) else {})


def paper_rows(design: DesignMap) -> list[Row]:
    """Section V's stated numbers beside ours (validation rows), and what the paper's
    simplification of the dynamics costs, for a study over base_radius and disc_height."""
    study = design.study
    s = stubs(study)
    short, long_ = shortest(study), longest(study)
    out = []
    for label, found in paper_points(design).items():
        out.append(Row(f"point {label}: sway at r_b = {POINTS_AT:g} m, {POINTS[label]} limit ({short.name})",
                       f"{PAPER[label]:.2f}", "none" if found is None else found, "m of z_p0",
                       "" if found is not None and abs(found - PAPER[label]) < 1e-9 else "one grid step (0.01 m)"))
    (_, rows), (_, columns) = list(study.axes.items())
    for actuator, key in ((short, "zone_450"), (long_, "zone_600")):
        ok = design.admissible(actuator)
        r, c = np.nonzero(ok)
        out.append(Row(f"kinematically admissible zone, {actuator.name}", f"around ({PAPER[key][0]:.2f}, {PAPER[key][1]:.2f})",
                       f"centroid ({rows[r].mean():.2f}, {columns[c].mean():.2f}), {ok.sum()} points" if ok.any() else "none",
                       "m (r_b, z_p0)", "a band along the heave stroke limits, as the paper's figure"))
    r, c = nearest(study, PAPER["chosen"])
    admissible = design.kinematic_admissible(long_)
    failing = [f"{name} in {', '.join(m for k, m in enumerate(design.motions) if not v[r, c, k])}"
               for name, v in admissible.items() if not v[r, c].all()]
    highest = limit_along(design, long_, "max stroke", "heave", PAPER["chosen"][0])
    out.append(Row(f"r_b = 1.10 m, z_p0 = 1.40 m with {long_.name}", "admissible",
                   "admissible" if not failing else "outside: " + "; ".join(failing), "",
                   "" if not failing else f"+0.3 m heave needs the running length below; the highest admissible z_p0 at "
                   f"r_b = 1.10 m is {highest} m"))
    needed = (design.length_min[r, c].min() + s, design.neutral_length[r, c] + s, design.length_max[r, c].max() + s)
    out.append(Row("running lengths there, min / neutral / max", " / ".join(f"{1e3 * v:.0f}" for v in PAPER["lengths"]),
                   " / ".join(f"{1e3 * v:.0f}" for v in needed), "mm",
                   "the paper quotes the actuator's limits, we what the six motions need; the neutral matches by "
                   "construction (params/halder2013.toml)"))
    if design.force_paper is not None:
        allowed = study.allowed_force(long_)
        out.append(Row("peak leg force there, payload only (Eq 16)", f"below {allowed:.0f}", float(design.force_paper[r, c].max()),
                       "N", f"{long_.continuous_force:g} N / (1 + {study.force_margins[0]:g}) / (1 + {study.force_margins[1]:g}); "
                       "the margins read as factors on the demand"))
        out.append(Row("the same with the legs' weight, inertia and friction", "", float(design.force_full[r, c].max()), "N",
                       "what the paper's simplification leaves out"))
        full_ok = design.admissible(long_) & (design.force_full.max(axis=2) <= allowed)
        out.append(Row("admissible points with the force limit", "", f"{design.admissible(long_, True).sum()} / "
                       f"{full_ok.sum()} of {design.admissible(long_).sum()}", "points",
                       "payload only / full model, of the kinematically admissible"))
    share = float(np.mean(design.bottom_angle > design.top_angle + 1e-9))
    out.append(Row("bottom joint angle above the top one", "never", f"{share:.1%} of points and motions", "", ""))
    out.append(Row("leg Jacobian at r_b = 1.10 m, z_p0 = 1.40 m over the motions", "",
                   f"smallest singular value {design.smallest_singular[r, c].min():.3f}, condition number "
                   f"{design.condition[r, c].max():.1f}", "", "far from a singular pose"))
    return out


def figures(design: DesignMap, folder: Path) -> list[Path]:
    """The validation report's Figs 2, 3 and 4 of the shipped Section V study's map."""
    points, chosen = marks(design)
    short, long_ = shortest(design.study), longest(design.study)
    return [plot_kinematic(design, short, folder / "halder_fig2.png", points),
            plot_kinematic(design, long_, folder / "halder_fig3.png", chosen),
            plot_dynamic(design, long_, folder / "halder_fig4.png", chosen)]
