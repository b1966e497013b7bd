"""ctypes access to the plain-C dynamics core of the mechanics (fmu/mechanics/platform.c, built by
CMake into build/lib/ with the FMU's own parameter mapping, fmu/mechanics/parameters.c): inverse
dynamics, leg kinematics, leg plants and energies without the FMI layer.

The platform is known once: a `Core` is built from mechanics-FMU variable values by name (the FMU's
start values, read from its modelDescription, with the given ones over them) through the same C
function the FMU builds its platform with, so every parameter the FMU takes (layout 1 radii and
spacings, explicit joints, masses, gravity, switches) changes the answers here exactly as there.
"""

from __future__ import annotations

import ctypes
from functools import lru_cache
from typing import Mapping

import numpy as np

from ..engine.artifacts import fmu_path, library_path
from ..engine.checks import variables
from ..engine.native import check_layout
from .ports import LEGS as PORT_LEGS

LEGS = len(PORT_LEGS)  # the dynamics core's PLATFORM_LEGS
D = ctypes.c_double


class Platform(ctypes.Structure):
    _fields_ = [
        ("upper_joint", D * 3 * LEGS), ("lower_joint", D * 3 * LEGS), ("neutral_pose", D * 6),
        ("neutral_length", D * LEGS), ("platform_mass", D), ("platform_inertia", D * 3),
        ("moving_mass", D), ("moving_inertia", D), ("moving_com", D),
        ("rotating_mass", D), ("rotating_inertia", D), ("rotating_com", D),
        ("motor_mass", D), ("motor_inertia", D), ("motor_com", D), ("rotor_inertia", D),
        ("screw_ratio", D), ("force_torque", D), ("viscous_friction", D), ("leg_spin_inertia", D),
        ("joint_friction_lower", D), ("joint_friction_upper", D), ("gravity", D * 3),
        ("actuator_inertia_on", ctypes.c_int), ("motor_inertia_on", ctypes.c_int), ("friction_on", ctypes.c_int),
    ]


class PlatformEnvelope(ctypes.Structure):
    """The motion envelope a live reference is held in (fmu/mechanics/envelope.h): the stroke less
    its margin [m], the joints' largest tilt [rad], the legs' largest speed [m/s] and acceleration
    [m/s^2], the reference's own largest acceleration per channel (its braking), and the farthest
    upper joint from the platform's origin [m] (how far a rotation moves a joint); the legs' neutral
    directions are the C side's to fill (prepared 0)."""
    _fields_ = [("platform", Platform), ("length_min", D), ("length_max", D), ("joint_angle_max", D),
                ("leg_velocity_max", D), ("leg_acceleration_max", D), ("acceleration_max", D * 6), ("arm", D),
                ("neutral_axis", D * 3 * LEGS), ("prepared", ctypes.c_int)]


class LegGeometry(ctypes.Structure):
    _fields_ = [("axis", D * 3), ("length", D), ("arm", D * 3), ("velocity", D)]


class Diagnostics(ctypes.Structure):
    _fields_ = [("mass_matrix", D * 36), ("kinetic", D), ("potential", D), ("drive_power", D),
                ("transmission_loss", D), ("friction_loss", D), ("load_power", D), ("singular", ctypes.c_int)]


@lru_cache(maxsize=None)
def core_library() -> ctypes.CDLL:
    """The core's library (its structs checked against the classes above)."""
    path = library_path("libplatform_core.so")
    dll = ctypes.CDLL(str(path))
    check_layout(dll, "platform_core_layout", path, [(Platform, "Platform"), (LegGeometry, "LegGeometry"),
                                                      (Diagnostics, "PlatformDiagnostics"),
                                                      (PlatformEnvelope, "PlatformEnvelope")])
    P = ctypes.POINTER
    dll.mechanics_platform_from_values.argtypes = [P(D), ctypes.c_int, P(Platform)]
    dll.mechanics_platform_from_values.restype = ctypes.c_int
    dll.mechanics_value_references.restype = ctypes.c_int
    dll.platform_leg_lengths.argtypes = [P(Platform), P(D), P(D)]
    dll.platform_legs.argtypes = [P(Platform), P(D), P(LegGeometry)]
    dll.platform_derivatives.argtypes = [P(Platform), P(D), P(D), P(D), ctypes.c_void_p, P(D), P(D), P(Diagnostics)]
    dll.platform_derivatives.restype = ctypes.c_int
    dll.platform_inverse_dynamics.argtypes = [P(Platform), P(D), P(D), P(D), P(D), P(D)]
    dll.platform_inverse_dynamics.restype = ctypes.c_int
    dll.platform_state_from_pose.argtypes = [P(D), P(D), P(D)]
    dll.platform_leg_plants.argtypes = [P(Platform), P(D), P(D), P(D)]
    dll.platform_pose_kinematics.argtypes = [P(Platform), ctypes.c_int, P(D), P(D), P(D), P(D), P(D)]
    dll.platform_leg_velocities_many.argtypes = [P(Platform), ctypes.c_int, P(D), P(D), P(D)]
    dll.platform_inverse_dynamics_many.argtypes = [P(Platform), ctypes.c_int, P(D), P(D), P(D), P(D), P(D)]
    dll.platform_inverse_dynamics_many.restype = ctypes.c_int
    dll.platform_leg_plants.restype = ctypes.c_int
    return dll


def _number(value: object) -> float:
    """A start value as the FMU holds it (Booleans and Integers as whole numbers)."""
    if isinstance(value, str):
        return 1.0 if value == "true" else 0.0 if value == "false" else float(value)
    if not isinstance(value, (bool, int, float, np.number)):
        raise ValueError(f"{value!r} is not a number")
    return float(value)


@lru_cache(maxsize=None)
def _start_values() -> tuple[dict[str, int], tuple[float, ...]]:
    """The mechanics FMU's value references by name and its start values by value reference."""
    found = variables(fmu_path("mechanics"))
    references = {name: v.valueReference for name, v in found.items()}
    values = [0.0] * (max(references.values()) + 1)
    for name, v in found.items():
        if v.start is not None and v.type != "String":
            values[v.valueReference] = _number(v.start)
    return references, tuple(values)


def mechanics_value(values: Mapping[str, object], name: str) -> object:
    """A mechanics variable's value: given in `values`, or the FMU's start value."""
    if name in values:
        return values[name]
    references, starts = _start_values()
    return starts[references[name]]


def gravity_of(values: Mapping[str, object]) -> np.ndarray:
    """The platform's gravity vector (base frame) [m/s^2] from mechanics values: the one gravity
    every FMU of a scene takes (the cueing FMU its magnitude)."""
    return np.array([float(mechanics_value(values, f"environment.gravity_{a}")) for a in "xyz"])


class LayoutImpossible(ValueError):
    """Mechanics parameters that give no platform (the FMU refuses them at initialization too)."""


class SingularPose(ValueError):
    """A pose at which the platform's dynamics have no answer (a singular leg Jacobian or mass
    matrix: a pose out of reach, or the joints crossing)."""


def build(values: Mapping[str, object] | None = None, dll: ctypes.CDLL | None = None) -> Platform:
    """The Platform the mechanics FMU builds from its start values with `values` (by variable
    name) over them: the FMU's own mapping (fmu/mechanics/parameters.c)."""
    dll = dll or core_library()
    references, starts = _start_values()
    full = list(starts)
    for name, value in (values or {}).items():
        if name in references:
            full[references[name]] = _number(value)
    p = Platform()
    status = dll.mechanics_platform_from_values(arr(full), len(full), ctypes.byref(p))
    if status == -2:
        raise RuntimeError(f"libplatform_core.so and mechanics.fmu come from different variable tables "
                           f"({dll.mechanics_value_references()} and {len(full)} value references): rebuild "
                           "with `bash scripts/setup.sh`")
    if status != 0:
        if int(full[references["geometry.layout"]]) == 2:
            raise LayoutImpossible("with the explicit joints a leg has zero length at geometry.neutral")
        raise LayoutImpossible("the joint radii and spacings give no platform (spacing wider than a circle, or "
                               "l_0 shorter than the legs' horizontal reach)")
    return p


def arr(values) -> ctypes.Array:
    values = np.asarray(values, dtype=float).ravel()
    return (D * len(values))(*values)


class Core:
    """A platform as the mechanics FMU builds it, with the dynamics core's functions on numpy
    arrays: the FMU's defaults (the Meng platform of params/meng2010.toml), its effect switches
    (actuators, motors, friction) as given, and any mechanics start values over them
    (use_start_values)."""

    def __init__(self, dll: ctypes.CDLL | None = None, actuators: bool = True, motors: bool = True,
                 friction: bool = True, values: Mapping[str, object] | None = None):
        self.dll = dll or core_library()
        self.values: dict[str, object] = {"effects.actuator_inertia": bool(actuators),
                                          "effects.motor_inertia": bool(motors), "effects.friction": bool(friction)}
        self.use_start_values(values or {})

    def use_start_values(self, values: Mapping[str, object]) -> "Core":
        """The platform of these mechanics start values (by FMU variable name) over the ones so far."""
        self.values.update(values)
        self.p = build(self.values, self.dll)
        return self

    @property
    def neutral_pose(self) -> np.ndarray:
        return np.array(self.p.neutral_pose[:])

    def leg_lengths(self, pose) -> np.ndarray:
        out = (D * LEGS)()
        self.dll.platform_leg_lengths(ctypes.byref(self.p), arr(pose), out)
        return np.array(out[:])

    def leg_velocities(self, x) -> np.ndarray:
        legs = (LegGeometry * LEGS)()
        self.dll.platform_legs(ctypes.byref(self.p), arr(x), legs)
        return np.array([leg.velocity for leg in legs])

    def upper_joints(self, x) -> np.ndarray:
        """Upper joint positions t + R a_i (6 x 3) at state x."""
        legs = (LegGeometry * LEGS)()
        self.dll.platform_legs(ctypes.byref(self.p), arr(x), legs)
        return np.array([np.array(x[:3]) + np.array(leg.arm[:]) for leg in legs])

    def upper_joints_at(self, poses: np.ndarray) -> np.ndarray:
        """Upper joint positions in the base frame (n x 6 x 3) at each of n poses (n x 6)."""
        return np.array([self.upper_joints(self.state(pose)) for pose in np.asarray(poses, float).reshape(-1, 6)])

    def state(self, pose, rate=np.zeros(6)) -> np.ndarray:
        out = (D * 13)()
        self.dll.platform_state_from_pose(arr(pose), arr(rate), out)
        return np.array(out[:])

    def derivatives(self, x, torque=np.zeros(6), force=np.zeros(6), wrench=np.zeros(6)):
        dx, diag = (D * 13)(), Diagnostics()
        status = self.dll.platform_derivatives(ctypes.byref(self.p), arr(x), arr(torque), arr(force), None,
                                               arr(wrench), dx, ctypes.byref(diag))
        if status != 0:
            raise SingularPose("the mass matrix is singular at this state")
        return np.array(dx[:]), diag

    def energy(self, x) -> float:
        _, diag = self.derivatives(x)
        return diag.kinetic + diag.potential

    def leg_plants(self, pose) -> tuple[np.ndarray, np.ndarray]:
        """Per leg at `pose`: the inertia along its axis with the other legs held [kg] and the axial
        force that holds the pose [N] (what the mechanics FMU outputs as leg[i].plant.*)."""
        inertia, force = (D * LEGS)(), (D * LEGS)()
        if self.dll.platform_leg_plants(ctypes.byref(self.p), arr(self.state(pose)), inertia, force) != 0:
            raise SingularPose(f"the legs are singular at the pose {np.round(np.asarray(pose, float), 6).tolist()}")
        return np.array(inertia[:]), np.array(force[:])

    def inverse_dynamics(self, pose, rate, acceleration, wrench=np.zeros(6)) -> np.ndarray:
        """The motor torques (the legs' forces over the screw's K_FT; forces on force-driven legs)
        that move the platform along the pose, rate and acceleration under the external wrench."""
        return self._inverse(self.p, pose, rate, acceleration, wrench)

    def leg_forces(self, pose, rate, acceleration, wrench=np.zeros(6)) -> np.ndarray:
        """The axial leg forces [N] of inverse_dynamics, before the screw turns them into torques."""
        return self._inverse(self._forces(), pose, rate, acceleration, wrench)

    def _forces(self) -> Platform:
        """This platform with the screw's force-torque factor taken as 1: its inverse dynamics give
        the legs' axial forces."""
        forces = Platform.from_buffer_copy(self.p)
        forces.force_torque = 1.0
        return forces

    def _inverse(self, p: Platform, pose, rate, acceleration, wrench) -> np.ndarray:
        out = (D * LEGS)()
        if self.dll.platform_inverse_dynamics(ctypes.byref(p), arr(pose), arr(rate), arr(acceleration),
                                              arr(wrench), out) != 0:
            raise SingularPose(f"the leg Jacobian is singular at the pose {np.round(np.asarray(pose, float), 6).tolist()}")
        return np.array(out[:])

    def pose_kinematics(self, poses: np.ndarray, jacobian: bool = False) -> dict[str, np.ndarray]:
        """At each pose (n x 6): per leg its length [m] and its tilt from the neutral direction at
        the lower and the upper joint [rad] (n x 6 each), and with `jacobian` the leg Jacobian
        (n x 6 x 6): the dynamics core's platform_pose_kinematics, one call for all poses."""
        poses = np.ascontiguousarray(poses, dtype=float).reshape(-1, 6)
        n = len(poses)
        out = {name: np.empty((n, LEGS)) for name in ("length", "lower_angle", "upper_angle")}
        jac = np.empty((n, 6, 6)) if jacobian else None

        def ptr(a):
            return a.ctypes.data_as(ctypes.POINTER(D)) if a is not None else None
        self.dll.platform_pose_kinematics(ctypes.byref(self.p), n, ptr(poses), ptr(out["length"]),
                                          ptr(out["lower_angle"]), ptr(out["upper_angle"]), ptr(jac))
        if jacobian:
            out["jacobian"] = jac
        return out

    def leg_velocities_many(self, poses: np.ndarray, rates: np.ndarray) -> np.ndarray:
        """Each leg's extension rate [m/s] at each of n poses moving at their rates (n x 6 each):
        the dynamics core's platform_leg_velocities_many, one call for all poses."""
        arrays = [np.ascontiguousarray(a, dtype=float).reshape(-1, 6) for a in (poses, rates)]
        out = np.empty_like(arrays[0])
        self.dll.platform_leg_velocities_many(ctypes.byref(self.p), len(out),
                                              *(a.ctypes.data_as(ctypes.POINTER(D)) for a in (*arrays, out)))
        return out

    def inverse_dynamics_many(self, poses: np.ndarray, rates: np.ndarray, accelerations: np.ndarray,
                              wrench=np.zeros(6)) -> np.ndarray:
        """inverse_dynamics at each of n poses with their rates and accelerations (n x 6 each):
        n x 6 motor torques, NaN where the legs are singular."""
        return self._inverse_many(self.p, poses, rates, accelerations, wrench)

    def leg_forces_many(self, poses: np.ndarray, rates: np.ndarray, accelerations: np.ndarray,
                        wrench=np.zeros(6)) -> np.ndarray:
        """leg_forces at each of n poses: n x 6 axial leg forces [N], NaN where singular."""
        return self._inverse_many(self._forces(), poses, rates, accelerations, wrench)

    def _inverse_many(self, p: Platform, poses, rates, accelerations, wrench) -> np.ndarray:
        arrays = [np.ascontiguousarray(a, dtype=float).reshape(-1, 6) for a in (poses, rates, accelerations)]
        out = np.empty_like(arrays[0])

        def ptr(a):
            return a.ctypes.data_as(ctypes.POINTER(D))
        self.dll.platform_inverse_dynamics_many(ctypes.byref(p), len(out), *(ptr(a) for a in arrays), arr(wrench),
                                                ptr(out))
        return out


def neutral_pose(values: Mapping[str, object]) -> np.ndarray:
    """The pose at which every motor angle is zero for mechanics start values: given with explicit
    joints (layout 2), solved from the radii, spacings and the middle leg length l_0 otherwise
    (layout 1), as the mechanics FMU does. Raises LayoutImpossible for values that give no platform."""
    return np.array(build(values).neutral_pose[:])
