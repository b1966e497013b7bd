"""ctypes access to the plain-C dynamics core of the mechanics (fmu/mechanics/platform.c, built by
CMake into build/lib/ as the library the FMU is built from): inverse dynamics, leg kinematics and
energies without the FMI layer, for tests and the validation report. Parameters come from
params/meng2010.toml, or from mechanics-FMU start values (Core.use_start_values)."""

from __future__ import annotations

import ctypes
import math

import numpy as np

from ..engine.artifacts import library_path
from .parameter_sets import load as load_parameter_set

LEGS = 6
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


class LegGeometry(ctypes.Structure):
    _fields_ = [("axis", D * 3), ("length", D), ("arm", D * 3), ("velocity", D)]


class Diagnostics(ctypes.Structure):
    _fields_ = [("mass_matrix", D * 36), ("kinetic", D), ("potential", D), ("drive_power", D),
                ("transmission_loss", D), ("friction_loss", D), ("load_power", D), ("singular", ctypes.c_int)]


def load() -> ctypes.CDLL:
    """The core's library, built if stale."""
    dll = ctypes.CDLL(str(library_path("libplatform_core.so")))
    P = ctypes.POINTER
    dll.platform_layout_from_radii.argtypes = [P(Platform), D, D, D, D, D, P(D), P(D)]
    dll.platform_layout_from_radii.restype = ctypes.c_int
    dll.platform_layout_from_joints.argtypes = [P(Platform), P(D), P(D), P(D)]
    dll.platform_layout_from_joints.restype = ctypes.c_int
    dll.platform_leg_lengths.argtypes = [P(Platform), P(D), P(D)]
    dll.platform_legs.argtypes = [P(Platform), P(D), P(LegGeometry)]
    dll.platform_derivatives.argtypes = [P(Platform), P(D), P(D), P(D), ctypes.c_void_p, P(D), P(D), P(Diagnostics)]
    dll.platform_derivatives.restype = ctypes.c_int
    dll.platform_inverse_dynamics.argtypes = [P(Platform), P(D), P(D), P(D), P(D), P(D)]
    dll.platform_inverse_dynamics.restype = ctypes.c_int
    dll.platform_state_from_pose.argtypes = [P(D), P(D), P(D)]
    dll.platform_leg_plants.argtypes = [P(Platform), P(D), P(D), P(D)]
    dll.platform_leg_plants.restype = ctypes.c_int
    return dll


def arr(values) -> ctypes.Array:
    values = np.asarray(values, dtype=float).ravel()
    return (D * len(values))(*values)


class Core:
    """The Meng platform of params/meng2010.toml, with the C core's functions on numpy arrays."""

    def __init__(self, dll: ctypes.CDLL | None = None, actuators: bool = True, motors: bool = True, friction: bool = True):
        self.dll = dll = dll or load()
        c = load_parameter_set("meng2010")
        g, pl, act, ms, tr, mo = (c["geometry"], c["platform"], c["actuator"], c["motor_system"],
                                  c["transmission"], c["motor"])
        p = Platform()
        assert dll.platform_layout_from_radii(
            ctypes.byref(p), g["upper_joint_radius"], g["lower_joint_radius"], g["upper_joint_spacing"],
            g["lower_joint_spacing"], g["middle_leg_length"], arr(g["lower_pair_centres_deg"]),
            arr(g["upper_pair_centres_deg"])) == 0
        p.platform_mass = pl["mass"]
        p.platform_inertia[:] = pl["inertia_diag"]
        p.moving_mass, p.moving_inertia, p.moving_com = (act["moving_part_mass"], act["moving_part_inertia"],
                                                         act["moving_part_com_from_upper_joint"])
        p.rotating_mass, p.rotating_inertia, p.rotating_com = (act["rotating_part_mass"],
                                                               act["rotating_part_inertia"],
                                                               act["rotating_part_com_from_lower_joint"])
        p.motor_mass, p.motor_inertia, p.motor_com = ms["mass"], ms["transverse_inertia"], ms["com_from_lower_joint"]
        p.rotor_inertia, p.screw_ratio = ms["rotor_screw_inertia"], tr["screw_ratio"]
        p.force_torque, p.viscous_friction = tr["force_torque_coefficient"], mo["viscous_friction"]
        p.gravity[:] = c["environment"]["gravity"]
        p.actuator_inertia_on, p.motor_inertia_on, p.friction_on = int(actuators), int(motors), int(friction)
        self.p, self.params = p, c

    def use_start_values(self, values: dict) -> "Core":
        """Overrides the platform with mechanics-FMU start values (explicit joints, masses, switches)."""
        p = self.p
        if values.get("geometry.layout") == 2:
            upper = [[values[f"geometry.platform_joint[{i}].{a}"] for a in "xyz"] for i in range(1, 7)]
            lower = [[values[f"geometry.base_joint[{i}].{a}"] for a in "xyz"] for i in range(1, 7)]
            neutral = [values[f"geometry.neutral.{a}"] for a in ("x", "y", "z", "roll", "pitch", "yaw")]
            assert self.dll.platform_layout_from_joints(ctypes.byref(p), arr(upper), arr(lower), arr(neutral)) == 0
        fields = {"platform.mass": "platform_mass", "actuator.moving_mass": "moving_mass",
                  "actuator.moving_inertia": "moving_inertia", "actuator.moving_com": "moving_com",
                  "actuator.rotating_mass": "rotating_mass", "actuator.rotating_inertia": "rotating_inertia",
                  "actuator.rotating_com": "rotating_com", "effects.motor_inertia": "motor_inertia_on",
                  "effects.friction": "friction_on", "effects.actuator_inertia": "actuator_inertia_on",
                  "actuator.spin_inertia": "leg_spin_inertia", "joint.friction_lower": "joint_friction_lower",
                  "joint.friction_upper": "joint_friction_upper", "motor_system.rotor_inertia": "rotor_inertia",
                  "transmission.screw_ratio": "screw_ratio", "transmission.force_torque": "force_torque",
                  "motor.viscous_friction": "viscous_friction", "motor_system.mass": "motor_mass",
                  "motor_system.inertia": "motor_inertia", "motor_system.com": "motor_com"}
        for name, field in fields.items():
            if name in values:
                setattr(p, field, type(getattr(p, field))(values[name]))
        for k, axis in enumerate(("xx", "yy", "zz")):
            if f"platform.inertia_{axis}" in values:
                p.platform_inertia[k] = values[f"platform.inertia_{axis}"]
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

    def state(self, pose, rate=np.zeros(6)) -> np.ndarray:
        out = (D * 13)()
        self.dll.platform_state_from_pose(arr(pose), arr(rate), out)
        return np.array(out[:])

    def derivatives(self, x, torque=np.zeros(6), force=np.zeros(6), wrench=np.zeros(6)):
        dx, diag = (D * 13)(), Diagnostics()
        status = self.dll.platform_derivatives(ctypes.byref(self.p), arr(x), arr(torque), arr(force), None,
                                               arr(wrench), dx, ctypes.byref(diag))
        assert status == 0
        return np.array(dx[:]), diag

    def energy(self, x) -> float:
        _, diag = self.derivatives(x)
        return diag.kinetic + diag.potential

    def leg_plants(self, pose) -> tuple[np.ndarray, np.ndarray]:
        """Per leg at `pose`: the inertia along its axis with the other legs held [kg] and the axial
        force that holds the pose [N] (what the mechanics FMU outputs as leg[i].plant.*)."""
        inertia, force = (D * LEGS)(), (D * LEGS)()
        assert self.dll.platform_leg_plants(ctypes.byref(self.p), arr(self.state(pose)), inertia, force) == 0
        return np.array(inertia[:]), np.array(force[:])

    def inverse_dynamics(self, pose, rate, acceleration, wrench=np.zeros(6)) -> np.ndarray:
        out = (D * LEGS)()
        assert self.dll.platform_inverse_dynamics(ctypes.byref(self.p), arr(pose), arr(rate), arr(acceleration),
                                                  arr(wrench), out) == 0
        return np.array(out[:])


def neutral_pose(values: dict) -> np.ndarray:
    """The pose at which every motor angle is zero for mechanics start values: given with explicit
    joints (layout 2), solved by the core from the radii, spacings and the middle leg length l_0
    otherwise (layout 1; the mechanics FMU solves the same)."""
    pose_names = ("x", "y", "z", "roll", "pitch", "yaw")
    if values.get("geometry.layout", 1) == 2:
        return np.array([values[f"geometry.neutral.{a}"] for a in pose_names])
    p = Platform()
    centres = {side: [math.degrees(values[f"geometry.{side}_pair_centre_{k}"]) for k in (1, 2, 3)]
               for side in ("lower", "upper")}
    if load().platform_layout_from_radii(
            ctypes.byref(p), values["geometry.upper_joint_radius"], values["geometry.lower_joint_radius"],
            values["geometry.upper_joint_spacing"], values["geometry.lower_joint_spacing"],
            values["geometry.middle_leg_length"], arr(centres["lower"]), arr(centres["upper"])) != 0:
        raise ValueError("the joint radii and spacings give no platform (spacing wider than a circle)")
    return np.array(p.neutral_pose[:])
