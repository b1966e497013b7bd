"""What an occupant feels: the motion at the head and the vestibular models that turn it into
perceived motion, the measure by which motion cueing is judged (docs/guide/cueing.md).

Six channels, in the occupant's frame (x forward, y left, z up): the specific force along x, y and
z (z less gravity: the heave cue) and the angular velocity about x, y and z. The otoliths sense
the specific force, the semicircular canals the angular velocity, each axis alike:

  otoliths (Young and Meiry 1968; the constants as Telban and Cardullo 2005, Table 2.1, give them):
      f^ / f = K (1 + tau_a s) / ((1 + tau_L s)(1 + tau_S s)), K = 0.4 (the static gain),
      tau_a = 13.2 s (the afferent's lead), tau_L = 5.33 s (the otolith's long time constant),
      tau_S = 0.66 s (its short one): a gain that rises from 0.4 at rest to its largest, 0.89 near
      0.5 rad/s, and falls off as 1.5 / w above about 2 rad/s;
  semicircular canals (Telban and Cardullo 2005, after Zacharias 1978):
      w^ / w = tau_a s / (1 + tau_a s) * tau_1 s (1 + tau_L s) / ((1 + tau_1 s)(1 + tau_2 s)),
      tau_a = 80 s (adaptation), tau_1 = 5.73 s (the cupula's long time constant), tau_2 = 0.005 s,
      tau_L = 0.06 s (the afferent's lead): unit gain between about 0.03 and 2.5 Hz.

A cue is felt where it passes the perception threshold of its channel (Reid and Nahon 1985):
0.17 m/s^2 along x and y, 0.28 m/s^2 along z, 3.0, 3.6 and 2.6 deg/s about x, y and z. The cues
are sorted as the cueing literature sorts them, per channel (e.g. Grant and Reid 1997): a
spurious cue where the platform is felt and the vehicle is not, a sign error where both are felt
with opposite signs, a missing cue where the vehicle is felt and the platform is not.

A second model judges the same motions (second_opinion: Reid and Nahon's organs, SECOND_ORGANS), so
that a cueing is not judged only by the model it was tuned or planned with.

The vehicle's motion comes as the cueing FMU took it (its `vehicle.*` outputs); the platform's is
its simulated motion at the head point: from the pose and the twist (base frame) of the mechanics,
f = R^T (a_head - g), a_head = a + alpha x r + w x (w x r), w_head = R^T w, with R = Rz Ry Rx
(the mechanics' convention).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

CHANNELS = ("specific_force.x", "specific_force.y", "specific_force.z", "angular_rate.x", "angular_rate.y",
            "angular_rate.z")
UNITS = ("m/s^2",) * 3 + ("rad/s",) * 3
THRESHOLDS = np.array([0.17, 0.17, 0.28, math.radians(3.0), math.radians(3.6), math.radians(2.6)])
TWIST = ("twist.vx", "twist.vy", "twist.vz", "twist.wx", "twist.wy", "twist.wz")


@dataclass(frozen=True)
class Vestibular:
    """A sense organ's transfer function, as zeros, poles [rad/s] and gain."""
    name: str
    zeros: tuple[float, ...]
    poles: tuple[float, ...]
    gain: float

    def response(self, frequency: np.ndarray) -> np.ndarray:
        """The complex frequency response at `frequency` [rad/s]."""
        s = 1j * np.asarray(frequency, dtype=float)
        out = np.full(s.shape, self.gain, dtype=complex)
        for z in self.zeros:
            out *= s - z
        for p in self.poles:
            out /= s - p
        return out

    def static_gain(self) -> float:
        return float(self.response(np.array([0.0]))[0].real)

    def modes(self) -> tuple[np.ndarray, float]:
        """Its partial fractions H(s) = sum r_i / (s - p_i) + d (real, distinct, stable poles):
        the residues r_i and the direct term d."""
        poles, zeros = np.array(self.poles), np.array(self.zeros)
        residues = np.array([self.gain * np.prod(p - zeros) / np.prod(p - np.delete(poles, i))
                             for i, p in enumerate(poles)])
        return residues, self.gain if len(zeros) == len(poles) else 0.0

    def perceive(self, times: np.ndarray, signal: np.ndarray) -> np.ndarray:
        """Its output along evenly spaced `times` for `signal` (linear between samples), starting
        settled on the signal's first value (a motion that was going on before). Exact: each mode
        x' = p x + u over a step h with the input linear between its samples is
        x+ = e^{ph} x + (I0 - I1) u + I1 u+, I0 = (e^{ph} - 1) / p, I1 = (e^{ph} - 1 - ph) / (p^2 h),
        a first-order recursion (scipy.signal.lfilter)."""
        from scipy.signal import lfilter
        h = float(times[1] - times[0]) if len(times) > 1 else 1.0
        u0 = float(signal[0])
        deviation = np.asarray(signal, dtype=float) - u0  # from the settled state, zero before the start
        recursions, direct = self.recursions(h)
        out = np.full(len(deviation), self.static_gain() * u0) + direct * deviation
        for decay, previous, now, residue in recursions:
            out += residue * lfilter([now, previous], [1.0, -decay], deviation)
        return out

    def recursions(self, h: float) -> tuple[list[tuple[float, float, float, float]], float]:
        """Its modes over a step h with the input linear between samples (perceive's recursions):
        per mode (e^{ph}, i0 - i1, i1, its residue) in x+ = e^{ph} x + (i0 - i1) u + i1 u+, the
        output sum residue x + direct u; and the direct term."""
        residues, direct = self.modes()
        out = []
        for r, p in zip(residues, self.poles):
            i0 = np.expm1(p * h) / p
            i1 = (np.expm1(p * h) - p * h) / (p * p * h)
            out.append((float(np.exp(p * h)), float(i0 - i1), float(i1), float(r)))
        return out, float(direct)


# the otoliths (Young and Meiry 1968, as Telban and Cardullo 2005 give them): gain, lead, long and short lags
OTOLITH_K, OTOLITH_TAU_A, OTOLITH_TAU_L, OTOLITH_TAU_S = 0.4, 13.2, 5.33, 0.66
# the canals (Telban and Cardullo 2005, after Zacharias 1978): adaptation, cupula long and short, afferent lead
TAU_A, TAU_1, TAU_2, TAU_L = 80.0, 5.73, 0.005, 0.06
OTOLITH = Vestibular("otoliths (Young and Meiry 1968)", (-1.0 / OTOLITH_TAU_A,),
                     (-1.0 / OTOLITH_TAU_L, -1.0 / OTOLITH_TAU_S),
                     OTOLITH_K * OTOLITH_TAU_A / (OTOLITH_TAU_L * OTOLITH_TAU_S))
CANAL = Vestibular("semicircular canals (Telban and Cardullo 2005)", (0.0, 0.0, -1.0 / TAU_L),
                   (-1.0 / TAU_A, -1.0 / TAU_1, -1.0 / TAU_2), TAU_L / TAU_2)
ORGANS = (OTOLITH,) * 3 + (CANAL,) * 3

# A second opinion, to judge a cueing by a model it was not tuned or planned with: the vestibular
# models of Reid and Nahon's washout studies (1985), as the motion-cueing literature restates them
# (e.g. Asadi et al. 2015): otoliths K (1 + tau_a s) / ((1 + tau_L s)(1 + tau_S s)) with K = 0.4,
# tau_a = 10 s, tau_L = 5 s, tau_S = 0.016 s (after Fernandez and Goldberg's afferents: a faster
# otolith than Young and Meiry's); canals tau_a tau_L s^2 / ((1 + tau_a s)(1 + tau_L s)) with
# tau_a = 80 s, tau_L = 5.73 s (no short lag, no lead). The thresholds are the same.
SECOND_OTOLITH = Vestibular("otoliths (Reid and Nahon 1985)", (-1.0 / 10.0,), (-1.0 / 5.0, -1.0 / 0.016),
                            0.4 * 10.0 / (5.0 * 0.016))
SECOND_CANAL = Vestibular("semicircular canals (Reid and Nahon 1985)", (0.0, 0.0), (-1.0 / 80.0, -1.0 / 5.73), 1.0)
SECOND_ORGANS = (SECOND_OTOLITH,) * 3 + (SECOND_CANAL,) * 3
# by what a cueing may be tuned (`[cueing.tune] judge`): the project's model, or both alike (the mean of
# the two perceived errors)
JUDGES = ("project", "both")


def rotations(poses: np.ndarray) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll) of each pose (n x 6: x, y, z, roll, pitch, yaw): n x 3 x 3,
    platform frame to base frame."""
    from scipy.spatial.transform import Rotation
    return Rotation.from_euler("ZYX", poses[:, [5, 4, 3]]).as_matrix()


def platform_motion(times: np.ndarray, poses: np.ndarray, twist: np.ndarray, head: np.ndarray,
                    gravity: np.ndarray) -> np.ndarray:
    """The platform's motion at the head point (`head`, platform frame, from the platform's
    origin) in the six channels (n x 6, the platform frame), from its poses (n x 6), twists (n x 6:
    the origin's velocity and the angular velocity, base frame) and the base frame's gravity
    vector; accelerations by second-order differences in time (uneven times allowed)."""
    R = rotations(poses)
    v, w = twist[:, :3], twist[:, 3:]
    acceleration = np.gradient(v, times, axis=0, edge_order=2)
    angular_acceleration = np.gradient(w, times, axis=0, edge_order=2)
    r = R @ np.asarray(head, dtype=float)
    a_head = acceleration + np.cross(angular_acceleration, r) + np.cross(w, np.cross(w, r))
    force = np.einsum("nji,nj->ni", R, a_head - np.asarray(gravity, dtype=float))
    rate = np.einsum("nji,nj->ni", R, w)
    force[:, 2] -= float(np.linalg.norm(gravity))  # the heave cue: less the 1 g of rest
    return np.column_stack([force, rate])


def vehicle_motion(forces: np.ndarray, rates: np.ndarray, gravity: float) -> np.ndarray:
    """The vehicle's motion in the six channels (n x 6): its specific force (less `gravity` along
    z) and angular rate at the head, each n x 3."""
    out = np.column_stack([forces, rates]).astype(float)
    out[:, 2] -= gravity
    return out


@dataclass
class Perceived:
    """Vehicle and platform, their motion and what the occupant perceives of each, per channel,
    on an even time grid."""
    times: np.ndarray
    vehicle: np.ndarray             # n x 6
    platform: np.ndarray            # n x 6
    vehicle_perceived: np.ndarray   # n x 6
    platform_perceived: np.ndarray  # n x 6


def perceive(times: np.ndarray, vehicle: np.ndarray, platform: np.ndarray, step: float | None = None,
             organs: tuple[Vestibular, ...] = ORGANS) -> Perceived:
    """Both motions (n x 6 at `times`, uneven allowed) resampled every `step` seconds (linear;
    default: the times' most common spacing, so that a run's samples are taken as they are) and
    through the vestibular models (`organs`, one per channel: the project's, or SECOND_ORGANS)."""
    step = step or float(np.median(np.diff(times)))
    grid = np.arange(times[0], times[-1] + 0.5 * step, step)
    grid = grid[grid <= times[-1]]
    at = [np.column_stack([np.interp(grid, times, m[:, c]) for c in range(6)]) for m in (vehicle, platform)]
    felt = [np.column_stack([organs[c].perceive(grid, m[:, c]) for c in range(6)]) for m in at]
    return Perceived(grid, at[0], at[1], felt[0], felt[1])


def second_opinion(p: Perceived) -> float:
    """The perceived error of the same motions by the second model (SECOND_ORGANS)."""
    return perceived_error(quality(perceive(p.times, p.vehicle, p.platform, organs=SECOND_ORGANS)))


@dataclass(frozen=True)
class ChannelQuality:
    """How well one channel's cue is felt: the perceived platform motion against the perceived
    vehicle motion, and its cues sorted by kind (felt: above the channel's threshold): spurious
    (the platform felt, the vehicle not), sign error (both felt, opposite signs), missing (the
    vehicle felt, the platform not); per kind its time [s] and largest size (the platform's
    perceived motion for a spurious cue or a sign error, the vehicle's for a missing one)."""
    channel: str
    unit: str
    rms_error: float         # of perceived platform - perceived vehicle
    rms_vehicle: float       # of the perceived vehicle motion (the scale of the error)
    correlation: float       # Pearson's, nan where either is constant
    spurious_time: float
    spurious_largest: float
    sign_error_time: float
    sign_error_largest: float
    missing_time: float
    missing_largest: float
    threshold: float
    rms_felt_error: float = 0.0  # of that error less the threshold (an error below it is not felt: 0)

    @property
    def false_cue_time(self) -> float:
        """The time of the false cues, spurious or of the wrong sign [s]."""
        return self.spurious_time + self.sign_error_time


CUE_KINDS = ("spurious", "sign error", "missing")


def cue_kinds(vehicle: np.ndarray, platform: np.ndarray, threshold: float) -> dict[str, np.ndarray]:
    """Where each kind of cue is, sample by sample, for one channel's perceived motions."""
    vehicle_felt, platform_felt = np.abs(vehicle) > threshold, np.abs(platform) > threshold
    return {"spurious": platform_felt & ~vehicle_felt,
            "sign error": platform_felt & vehicle_felt & (platform * vehicle < 0.0),
            "missing": vehicle_felt & ~platform_felt}


def quality(p: Perceived) -> list[ChannelQuality]:
    """Per channel: rms error and correlation of the perceived motions, and the cues by kind
    (cue_kinds), their times and largest sizes."""
    out = []
    dt = float(np.mean(np.diff(p.times))) if len(p.times) > 1 else 0.0
    for c, channel in enumerate(CHANNELS):
        vehicle, platform = p.vehicle_perceived[:, c], p.platform_perceived[:, c]
        error = platform - vehicle
        constant = np.ptp(vehicle) < 1e-12 or np.ptp(platform) < 1e-12
        correlation = float("nan") if constant else float(np.corrcoef(vehicle, platform)[0, 1])
        kinds = cue_kinds(vehicle, platform, THRESHOLDS[c])
        figures = []
        for kind, felt in (("spurious", platform), ("sign error", platform), ("missing", vehicle)):
            where = kinds[kind]
            figures += [float(where.sum() * dt), float(np.abs(felt[where]).max()) if where.any() else 0.0]
        felt_error = np.maximum(np.abs(error) - THRESHOLDS[c], 0.0)  # the indifference threshold's dead zone
        out.append(ChannelQuality(channel, UNITS[c], float(np.sqrt(np.mean(error ** 2))),
                                  float(np.sqrt(np.mean(vehicle ** 2))), correlation, *figures, float(THRESHOLDS[c]),
                                  float(np.sqrt(np.mean(felt_error ** 2)))))
    return out


def perceived_error(channels: list[ChannelQuality]) -> float:
    """One number for a cueing's quality (what tuning minimises): per channel the rms of the
    perceived error that passes the channel's indifference threshold (an error below it is not
    felt and does not count; above, by as much as it passes it), in thresholds, summed."""
    return float(sum(q.rms_felt_error / q.threshold for q in channels))


def cue_figures(q: ChannelQuality) -> list[tuple[str, float, float]]:
    """A channel's cues by kind: (kind, time [s], largest size)."""
    return [("spurious", q.spurious_time, q.spurious_largest), ("sign error", q.sign_error_time, q.sign_error_largest),
            ("missing", q.missing_time, q.missing_largest)]


def quality_lines(channels: list[ChannelQuality]) -> list[str]:
    """The quality per channel, a line each, and the sum tuning minimises."""
    lines = []
    for q in channels:
        correlation = "constant" if math.isnan(q.correlation) else f"{q.correlation:.2f}"
        cues = "; ".join(f"{kind} {time:.2f} s" + (f" (up to {largest:.3g})" if time else "")
                         for kind, time, largest in cue_figures(q))
        lines.append(f"perceived {q.channel}: rms error {q.rms_error:.3g} {q.unit} (the vehicle's {q.rms_vehicle:.3g}), "
                     f"correlation {correlation}; cues beyond the threshold {q.threshold:.3g}: {cues}")
    lines.append(f"perceived error (rms per channel of what passes its threshold, in thresholds, summed): "
                 f"{perceived_error(channels):.3f}")
    return lines
