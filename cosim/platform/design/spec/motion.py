"""The motions a study asks a platform to carry: each DOF alone from one end of its range to the
other in the shortest time its speed and acceleration limits allow (the basic motions, Halder's
Section V), or one recorded motion; as poses along a path for the kinematic limits, as a timed
profile for the forces, and finely sampled for the co-simulation."""

from __future__ import annotations

import math

import numpy as np

from .study import DOFS, ROTATIONS, Study


LONGEST = 3600.0  # [s] the longest basic motion a study may ask for (the confirmation plays it at 1 ms)


def ramp_and_cruise(distance: float, v_max: float, a_max: float) -> tuple[float, float]:
    """The shortest-time rest-to-rest move's phases over `distance`: how long it accelerates (and
    as long again decelerates) and how long it cruises at v_max between [s]."""
    t_ramp = min(v_max / a_max, math.sqrt(distance / a_max))
    v_top = a_max * t_ramp
    return t_ramp, max(0.0, (distance - a_max * t_ramp ** 2) / v_top) if v_top > 0 else 0.0


def shortest_time(distance: float, v_max: float, a_max: float, samples: int = 41) -> tuple[np.ndarray, ...]:
    """The shortest-time rest-to-rest move over `distance` under |v| <= v_max, |a| <= a_max:
    accelerate at a_max, cruise at v_max (if reached), decelerate. Returns times, displacements,
    velocities and accelerations sampled in each phase with the phase's own (constant)
    acceleration at both its ends, so the extremes of anything the acceleration drives are seen."""
    t_ramp, t_cruise = ramp_and_cruise(distance, v_max, a_max)
    v_top = a_max * t_ramp
    times, s, v, a = [], [], [], []
    for phase, (start, length, accel) in enumerate([(0.0, t_ramp, a_max), (t_ramp, t_cruise, 0.0),
                                                    (t_ramp + t_cruise, t_ramp, -a_max)]):
        if length <= 0.0:
            continue
        tau = np.linspace(0.0, length, samples)
        if phase == 0:
            s0, v0 = 0.0, 0.0
        elif phase == 1:
            s0, v0 = 0.5 * a_max * t_ramp ** 2, v_top
        else:
            s0, v0 = 0.5 * a_max * t_ramp ** 2 + v_top * t_cruise, v_top
        times.append(start + tau)
        s.append(s0 + v0 * tau + 0.5 * accel * tau ** 2)
        v.append(v0 + accel * tau)
        a.append(np.full_like(tau, accel))
    return tuple(np.concatenate(x) for x in (times, s, v, a))


def basic_motions(study: Study, neutral: np.ndarray, timed: bool = False) -> dict[str, tuple[np.ndarray, ...]]:
    """Each DOF from -range to +range about the neutral pose: poses (n x 6) and, with `timed`, the
    shortest-time profile's rates and accelerations (n x 6 each); otherwise `samples` poses evenly
    along the path (what the kinematic limits need)."""
    return {dof: (neutral + offsets, rates, accelerations)
            for dof, (offsets, rates, accelerations) in displacements(study, timed).items()}


_PROFILES: dict[tuple, dict] = {}


def displacements(study: Study, timed: bool) -> dict[str, tuple[np.ndarray, ...]]:
    """basic_motions about a zero pose (the same at every design point: computed once), or the
    recorded motion (its every sample, rates and accelerations either way)."""
    if study.recorded is not None:
        r = study.recorded
        return {r.name: (r.displacement, r.rates, r.accelerations)}
    key = (tuple(sorted(study.motion.ranges.items())), study.motion.velocity, study.motion.acceleration,
           study.motion.angular_velocity, study.motion.angular_acceleration, study.samples, study.phase_samples, timed)
    if key in _PROFILES:
        return _PROFILES[key]
    out = {}
    for k, dof in enumerate(DOFS):
        half = study.motion.ranges.get(dof, 0.0)
        if half <= 0.0:
            continue
        rotation = dof in ROTATIONS
        if timed:
            m = study.motion
            _, s, v, a = shortest_time(2 * half, m.angular_velocity if rotation else m.velocity,
                                       m.angular_acceleration if rotation else m.acceleration, study.phase_samples)
            displacement = s - half
        else:
            displacement = np.linspace(-half, half, study.samples)
            v = a = np.zeros_like(displacement)
        offsets = np.zeros((len(displacement), 6))
        offsets[:, k] = displacement
        rates, accelerations = np.zeros_like(offsets), np.zeros_like(offsets)
        rates[:, k], accelerations[:, k] = v, a
        out[dof] = (offsets, rates, accelerations)
    _PROFILES[key] = out
    return out


def motion_profile(study: Study, motion: str) -> tuple[np.ndarray, ...]:
    """A motion of the study as the co-simulation plays it: times from 0, displacements from the
    neutral (n x 6), rates and accelerations; a basic motion's shortest-time move finely sampled
    (400 per phase), or the recorded motion."""
    if study.recorded is not None:
        r = study.recorded
        return r.times - r.times[0], r.displacement, r.rates, r.accelerations
    k, half, m = DOFS.index(motion), study.motion.ranges[motion], study.motion
    rotation = motion in ROTATIONS
    t, s, v, a = shortest_time(2 * half, m.angular_velocity if rotation else m.velocity,
                               m.angular_acceleration if rotation else m.acceleration, 400)
    keep = np.r_[True, np.diff(t) > 0]  # the phases' shared instants once
    out = [np.zeros((keep.sum(), 6)) for _ in range(3)]
    for array, column in zip(out, (s - half, v, a)):
        array[:, k] = column[keep]
    return (t[keep], *out)
