"""The words a summary prints about a design, computed against the study's stated thresholds
([thresholds], study.Thresholds with their reasons): its conditioning (singular, ill or well
conditioned) and whether a singular pose is near along a DOF. Nothing here is fixed text."""

from __future__ import annotations

import math

import numpy as np

from .study import DOFS, ROTATIONS, Study

SINGULAR = 1e6  # a condition number above it is a singular Jacobian in double precision (1e-6 of its scale)


def conditioning(study: Study, condition: float) -> str:
    """'singular', 'ill conditioned' or 'well conditioned', with the threshold it was judged by."""
    limit = study.thresholds.condition_number
    if not math.isfinite(condition) or condition > SINGULAR:
        return "singular: the legs cannot hold every direction of the payload's load"
    if condition > limit:
        return f"ill conditioned: the condition number is above the study's {limit:g} (near a singular pose)"
    return f"well conditioned: the condition number is within the study's {limit:g}"


def motion_reach(study: Study) -> dict[str, float]:
    """Per DOF the motion's largest displacement from the neutral (m, rad): a basic motion's half
    range, a recorded motion's largest |displacement|."""
    if study.recorded is not None:
        return {dof: float(np.abs(study.recorded.displacement[:, k]).max()) for k, dof in enumerate(DOFS)}
    return {dof: float(study.motion.ranges.get(dof, 0.0)) for dof in DOFS}


def near_singular(study: Study, distances: dict[str, float]) -> dict[str, bool]:
    """Per DOF whether its nearest singular pose (from the neutral) lies within the study's
    singular_distance_factor times the motion's reach along it (a DOF the motion does not move is
    judged by its reach alone: never near)."""
    factor, reach = study.thresholds.singular_distance_factor, motion_reach(study)
    return {dof: bool(math.isfinite(d) and d <= factor * reach[dof]) for dof, d in distances.items()}


def near_text(study: Study, distances: dict[str, float]) -> str:
    """The verdict on the nearest singular poses, naming the DOFs where one is near."""
    factor, reach = study.thresholds.singular_distance_factor, motion_reach(study)
    near = [dof for dof, is_near in near_singular(study, distances).items() if is_near]

    def shown(dof: str, x: float) -> str:
        return f"{math.degrees(x):.1f} deg" if dof in ROTATIONS else f"{x:.3f} m"
    if not near:
        return f"every one beyond {factor:g} times the motion's reach along its DOF (the study's threshold)"
    return "near: " + ", ".join(f"{dof} at {shown(dof, distances[dof])}, within {factor:g} x the motion's "
                                f"{shown(dof, reach[dof])}" for dof in near)
