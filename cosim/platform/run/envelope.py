"""The motion envelope of a platform (fmu/mechanics/envelope.c, docs/guide/realtime.md): where a
guarded reference may go. Every leg within its stroke (limit.leg_length_min/max) less
limit.stroke_margin at each end and every joint within limit.joint_angle less limit.joint_margin,
margins that cover the platform's tracking error; every leg's speed and acceleration within
limit.leg_velocity and limit.leg_acceleration. The step kernel's guard holds the reference inside it
on what is actually applied, braking in time, and brings one that is outside back in; a scene's own
reference is checked against it before a real-time run.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from ...engine.errors import UsageError
from ..core import Core, PlatformEnvelope, mechanics_value

# what the guard's bits (ENVELOPE_STROKE, _JOINT, _LEG_VELOCITY, _LEG_ACCELERATION, _RETURN) are called in
# the report, and the cueing FMU's outputs that count them (guard.held.<kind>: fmu/cueing/guard.c)
GUARD_KINDS = ("the stroke", "a joint's tilt", "a leg's speed", "a leg's acceleration",
               "its way back in from outside")
GUARD_OUTPUTS = tuple(f"guard.held.{kind}" for kind in ("stroke", "joint", "leg_velocity", "leg_acceleration", "return"))


def held_line(held: dict[str, int]) -> str | None:
    """The report's line of the steps on which the envelope held the reference back, by what held
    it (None where nothing did)."""
    held = {k: v for k, v in held.items() if v}
    return ("the envelope held the reference back at " + ", ".join(f"{v} steps by {k}" for k, v in held.items())
            if held else None)


@dataclass(frozen=True)
class Envelope:
    """A platform's envelope: the stroke [m] and its margin [m], the joints' largest tilt [rad] and
    its margin [rad], the legs' largest speed [m/s] and acceleration [m/s^2]."""
    stroke: tuple[float, float]
    margin: float
    joint_angle: float
    leg_velocity: float
    leg_acceleration: float
    joint_margin: float = 0.0

    @classmethod
    def of(cls, mechanics_values: Mapping[str, object]) -> "Envelope":
        def value(name: str) -> float:
            return float(mechanics_value(mechanics_values, f"limit.{name}"))
        envelope = cls((value("leg_length_min"), value("leg_length_max")), value("stroke_margin"),
                       value("joint_angle"), value("leg_velocity"), value("leg_acceleration"), value("joint_margin"))
        if envelope.usable[0] >= envelope.usable[1]:
            raise UsageError(f"limit.stroke_margin = {envelope.margin:g} m leaves no stroke of "
                             f"{envelope.stroke[0]:g}-{envelope.stroke[1]:g} m for a guarded reference")
        if envelope.usable_joint_angle <= 0.0:
            raise UsageError(f"limit.joint_margin = {envelope.joint_margin:g} rad leaves no tilt of limit.joint_angle = "
                             f"{envelope.joint_angle:g} rad for a guarded reference")
        return envelope

    @property
    def usable(self) -> tuple[float, float]:
        """The legs' lengths a reference may take [m]: the stroke less the margin."""
        return self.stroke[0] + self.margin, self.stroke[1] - self.margin

    @property
    def usable_joint_angle(self) -> float:
        """The tilt a reference may take at a joint [rad]: the limit less its margin."""
        return self.joint_angle - self.joint_margin

    def words(self) -> str:
        return (f"the stroke {self.stroke[0]:g}-{self.stroke[1]:g} m less {1e3 * self.margin:g} mm at each end, "
                f"joints within {np.degrees(self.joint_angle):.3g} deg less {np.degrees(self.joint_margin):.3g} deg")

    def c_struct(self, core: Core, acceleration_max: Sequence[float]) -> PlatformEnvelope:
        """The C side's envelope for `core`'s platform, braking at `acceleration_max` per channel."""
        arm = float(np.linalg.norm(np.array(core.p.upper_joint[:]).reshape(-1, 3), axis=1).max())
        return PlatformEnvelope(core.p, *self.usable, self.usable_joint_angle, self.leg_velocity,
                                self.leg_acceleration, (ctypes.c_double * 6)(*acceleration_max), arm)


def within(core: Core, envelope: PlatformEnvelope, poses: np.ndarray) -> np.ndarray:
    """Per pose (n x 6): inside the envelope's stroke and joint limits (the guard's own test)."""
    contains = core.dll.platform_envelope_contains
    contains.argtypes, contains.restype = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_double)], ctypes.c_int
    poses = np.ascontiguousarray(poses, dtype=float).reshape(-1, 6)
    pointer = ctypes.cast(ctypes.pointer(envelope), ctypes.c_void_p)
    return np.array([bool(contains(pointer, row.ctypes.data_as(ctypes.POINTER(ctypes.c_double)))) for row in poses])


def check_reference(name: str, core: Core, envelope: Envelope, times: np.ndarray, poses: np.ndarray) -> str | None:
    """What to say, before a run in real time, of a scene's own reference that leaves the
    envelope: past the legs' stroke (a rig's end stops), or within it into the margin or past a
    joint's tilt; None if it stays inside. (The run's guard holds it within the envelope.)"""
    bare = Envelope(envelope.stroke, 0.0, 3.2, np.inf, np.inf)  # the stroke alone
    inside = within(core, bare.c_struct(core, [1.0] * 6), poses)
    if not inside.all():
        return (f"{name}: its own reference takes {_where(core, bare, times, poses, inside)}, past the legs' stroke "
                f"({envelope.stroke[0]:g}-{envelope.stroke[1]:g} m): this run's guard holds it within the envelope "
                f"({envelope.words()})")
    inside = within(core, envelope.c_struct(core, [1.0] * 6), poses)
    if inside.all():
        return None
    return (f"{name}: its own reference takes {_where(core, envelope, times, poses, inside)}, outside the envelope "
            f"({envelope.words()}): this run's guard holds it within")


def _where(core: Core, envelope: Envelope, times: np.ndarray, poses: np.ndarray, inside: np.ndarray) -> str:
    """Where a reference first leaves the envelope: which leg, how far, when."""
    first = int(np.flatnonzero(~inside)[0])
    kinematics = core.pose_kinematics(poses[first:first + 1])
    lengths = kinematics["length"][0]
    beyond = np.maximum(envelope.usable[0] - lengths, lengths - envelope.usable[1])
    worst = int(np.argmax(beyond))
    if beyond[worst] > 0:
        return f"leg {worst + 1} to {lengths[worst]:.4f} m at t = {times[first]:.3f} s"
    tilt = np.maximum(kinematics["lower_angle"][0], kinematics["upper_angle"][0])
    worst = int(np.argmax(tilt))
    return f"a joint of leg {worst + 1} to {np.degrees(tilt[worst]):.2f} deg at t = {times[first]:.3f} s"
