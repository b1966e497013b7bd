"""The platform is known once: what the platform application computes about a platform (its
neutral pose, leg lengths, leg plants and static loads, the drive design's input) comes from the
mechanics FMU's own parameter mapping, so that every parameter the FMU takes moves the Python
side's answers exactly as it moves the FMU's outputs.

Before this held, the Python side read only explicit joints and a list of masses: a layout-1
geometry, gravity or a switch changed the FMU and not the drives' design (a 0.6 m upper radius
under lunar gravity: 2066 N of static load in Python where the FMU said 341 N)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cosim.engine.artifacts import fmu_path
from cosim.engine.checks import variables
from cosim.engine.fmi import FmuInstance
from cosim.platform.scene.parameter_sets import mechanics_start_values, scene_mechanics
from cosim.platform.core import Core, LayoutImpossible, neutral_pose
from cosim.platform.ports import POSE
from cosim.platform.run.tuning import leg_plants

# Every parameter of these groups is swept: the platform's geometry, masses and inertias, the
# transmission, friction, gravity and the effect switches.
GROUPS = ("geometry.", "platform.", "actuator.", "motor_system.", "transmission.", "motor.", "joint.",
          "environment.", "effects.")


def swept_parameters() -> list[str]:
    found = variables(fmu_path("mechanics"))
    return sorted(name for name, v in found.items() if v.causality == "parameter" and name.startswith(GROUPS)
                  and name != "geometry.layout")


def changed(name: str, value: object) -> object:
    """A change of the parameter that keeps the platform buildable and its start pose admissible."""
    if isinstance(value, bool):
        return not value
    if "pair_centre" in name or name.startswith("geometry.neutral.") and name[-1] not in "xyz":
        return value + 0.05  # rad
    if name.startswith("environment.gravity"):
        return value * 0.165 if value else 1.3  # the Moon's, or a sideways pull
    if "_joint[" in name or name.startswith("geometry.neutral."):
        return value + 0.03  # m
    if name == "transmission.force_torque":
        return value * 0.93  # K_FT <= i_theta: an efficiency of at most 1
    return value * 1.07 + (0.01 if value == 0 else 0.0)


@pytest.fixture(scope="module")
def mechanics():
    instances = []

    def make(values: dict) -> FmuInstance:
        instance = FmuInstance(fmu_path("mechanics"), f"mechanics{len(instances)}")
        instances.append(instance)
        instance.initialize(values)
        return instance

    yield make
    for instance in instances:
        instance.free()


def fmu_value(name: str):
    v = variables(fmu_path("mechanics"))[name]
    if v.type == "Boolean":
        return v.start == "true"
    return float(v.start)


@pytest.mark.parametrize("parameter_set", ["meng2010", "sumnu2015", "halder2013"])
def test_every_platform_parameter_moves_python_and_the_fmu_alike(parameter_set, mechanics):
    """For each geometry, mass, transmission, friction, environment and switch parameter, changed
    on its own: the Python side's neutral pose is where the FMU's motor angles are zero, its leg
    lengths there are the FMU's, and its leg plants at the start pose (inertia with the other legs
    held, static force) are the FMU's leg[i].plant.* outputs, to round-off (one C function builds
    both platforms; the FMU integrates from a quaternion state, hence 1e-9 rather than 0)."""
    base = mechanics_start_values(parameter_set)
    moved = 0
    for name in swept_parameters():
        value = base.get(name, fmu_value(name))
        values = {**base, name: changed(name, value)}
        try:
            neutral = neutral_pose(values)
        except LayoutImpossible:
            pytest.fail(f"{parameter_set}: {name} = {values[name]!r} gives no platform; choose another change")
        values.update({f"initial.pose.{dof}": float(neutral[k]) for k, dof in enumerate(POSE)})
        fmu = mechanics(values)
        angles = np.array([fmu.get(f"leg[{i}].angle") for i in range(1, 7)])
        lengths = np.array([fmu.get(f"leg[{i}].length") for i in range(1, 7)])
        inertia = np.array([fmu.get(f"leg[{i}].plant.inertia") for i in range(1, 7)])
        static = np.array([fmu.get(f"leg[{i}].plant.static_force") for i in range(1, 7)])
        plants = leg_plants(values)
        core = Core().use_start_values(values)
        np.testing.assert_allclose(angles, 0.0, atol=1e-9, err_msg=f"{parameter_set}: {name}")
        np.testing.assert_allclose(core.leg_lengths(neutral), lengths, rtol=1e-12, err_msg=name)
        np.testing.assert_allclose([p.mass for p in plants], inertia, rtol=1e-9, err_msg=f"{parameter_set}: {name}")
        scale = max(1.0, float(np.abs(static).max()))
        np.testing.assert_allclose([p.static_force for p in plants], static, rtol=0, atol=1e-9 * scale,
                                   err_msg=f"{parameter_set}: {name}")
        base_plants = leg_plants({**base, **{f"initial.pose.{d}": float(x) for d, x in
                                             zip(POSE, neutral_pose(base))}})
        moved += not np.allclose([p.mass for p in plants], [p.mass for p in base_plants], rtol=1e-12) or \
            not np.allclose([p.static_force for p in plants], [p.static_force for p in base_plants], rtol=1e-12)
    assert moved >= 10  # the sweep changes the plants, it does not compare a platform with itself


def test_the_issue_s_platform_static_load_is_the_fmu_s():
    """The case that was wrong: Meng's platform with a 0.6 m upper radius under lunar gravity."""
    values = {**mechanics_start_values("meng2010"), "geometry.upper_joint_radius": 0.6,
              "environment.gravity_z": -1.62}
    values = scene_mechanics("meng2010", parameters=values)
    plants = leg_plants(values)
    fmu = FmuInstance(fmu_path("mechanics"), "mechanics")
    try:
        fmu.initialize(values)
        static = [fmu.get(f"leg[{i}].plant.static_force") for i in range(1, 7)]
    finally:
        fmu.free()
    assert static[0] == pytest.approx(341, rel=0.01)
    np.testing.assert_allclose([p.static_force for p in plants], static, rtol=1e-9)


def test_a_scene_starts_at_its_own_neutral_pose():
    """A scene that moves the neutral pose (a shorter middle leg) starts the platform there, not at
    the FMU's default start pose (the default layout's neutral); one that gives a start pose keeps it."""
    values = scene_mechanics("meng2010", parameters={"geometry.middle_leg_length": 1.70})
    assert values["initial.pose.z"] == pytest.approx(neutral_pose(values)[2], abs=0)
    assert values["initial.pose.z"] < 1.6 and math.isfinite(values["initial.pose.z"])
    given = scene_mechanics("meng2010", parameters={"geometry.middle_leg_length": 1.70, "initial.pose.z": 1.58})
    assert given["initial.pose.z"] == 1.58
