"""Where a platform went past its limits (the run's report and `cosim view`): each stretch of time
a leg spends past the top or the bottom of its stroke or past its joints' limit, how long, and the
farthest it went there, from the poses at every sample (the dynamics core's kinematics: the same
the mechanics FMU integrates)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from ..core import Core, mechanics_value
from ..ports import POSE


@dataclass(frozen=True)
class Excursion:
    """One stretch of time a leg spends past a limit, from the first sample past it to the first
    back inside (the run's end if none), with the farthest it went."""
    leg: int            # 1 .. 6
    limit: str          # "the stroke's top", "the stroke's bottom", "the joints' limit"
    start: float        # [s]
    end: float          # [s]
    extreme: float      # [m] the longest (shortest) leg, or [rad] the largest tilt
    beyond: float       # [m or rad] past the limit there

    def words(self) -> str:
        if self.limit == "the joints' limit":
            at = f"at most {np.degrees(self.extreme):.2f} deg ({np.degrees(self.beyond):.2f} deg past)"
        else:
            at = f"{'at most' if 'top' in self.limit else 'at least'} {self.extreme:.4f} m ({1e3 * self.beyond:.1f} mm past)"
        return (f"leg {self.leg} past {self.limit} from t = {self.start:.3f} to {self.end:.3f} s "
                f"({self.end - self.start:.3f} s), {at}")


def excursions(time: np.ndarray, length: np.ndarray, tilt: np.ndarray, stroke: tuple[float, float],
               joint_limit: float) -> list[Excursion]:
    """Every stretch of time a leg (columns of `length` [m] and `tilt` [rad], a row per time) spends
    past its stroke or its joints' limit, in order of start."""
    low, high = stroke
    found = []
    kinds = (("the stroke's top", length > high, length, np.argmax, lambda v: v - high),
             ("the stroke's bottom", length < low, length, np.argmin, lambda v: low - v),
             ("the joints' limit", tilt > joint_limit, tilt, np.argmax, lambda v: v - joint_limit))
    for limit, past, value, extreme, beyond in kinds:
        for leg in range(past.shape[1]):
            edges = np.diff(np.r_[0, past[:, leg].astype(np.int8), 0])
            for first, after in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
                at = first + int(extreme(value[first:after, leg]))
                end = time[after] if after < len(time) else time[-1]
                found.append(Excursion(leg + 1, limit, float(time[first]), float(end), float(value[at, leg]),
                                       float(beyond(value[at, leg]))))
    return sorted(found, key=lambda e: (e.start, e.leg))


def platform_excursions(mechanics_values: Mapping[str, object], time: np.ndarray, pose: np.ndarray) -> list[Excursion]:
    """The excursions of the platform of these mechanics values at these poses (n x 6)."""
    kinematics = Core(values=mechanics_values).pose_kinematics(pose)
    stroke = (float(mechanics_value(mechanics_values, "limit.leg_length_min")),
              float(mechanics_value(mechanics_values, "limit.leg_length_max")))
    return excursions(time, kinematics["length"], np.maximum(kinematics["lower_angle"], kinematics["upper_angle"]),
                      stroke, float(mechanics_value(mechanics_values, "limit.joint_angle")))


def excursion_lines(found: list[Excursion], most: int = 8, subject: str = "the platform past its limits") -> list[str]:
    """What a report says of the excursions of `subject` (the platform as it ran, or the reference
    it was asked for): the `most` that went farthest (a millimetre weighed as a degree), in time
    order, and how many there were."""
    if not found:
        return []
    farthest = sorted(found, key=lambda e: -e.beyond / (np.radians(1.0) if "joint" in e.limit else 1e-3))
    shown = sorted(farthest[:most], key=lambda e: (e.start, e.leg))
    longest = max(e.end - e.start for e in found)
    lines = [f"{len(found)} excursions of {subject} (the longest {longest:.3f} s)" +
             (f"; the {most} farthest:" if len(found) > most else ":")]
    return lines + [e.words() for e in shown]


def result_excursion_lines(mechanics_values: Mapping[str, object], result: np.ndarray) -> list[str]:
    """A run's excursions (its recorded pose, every sample), as its report says them."""
    pose = np.column_stack([result[f"pose.{a}"] for a in POSE])
    return excursion_lines(platform_excursions(mechanics_values, result["time"], pose))
