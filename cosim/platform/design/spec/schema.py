"""The design study file's keys (docs/reference/study.md is generated from here): every table and
key with its type, range, unit, default and what it does. What depends on the platform family
(which design values exist) and on other keys the reader checks (cosim.platform.design.spec.reader)."""

from __future__ import annotations

from ....engine.errors import InputError
from ....engine.schema import Key, Schema, Table
from ....engine.values import REQUIRED, Choice, Flag, Free, ListOf, Number, Row, Text
from .study import (CONDITION_REASON, DOFS, FAMILIES, MARGIN_MODES, NEAR_REASON, OBJECTIVES, ROTATIONS,
                    Thresholds)


class StudyError(InputError):
    """A study file that cannot run: one line naming the file, the line and the reason."""


DRIVEN = {"force": "ideal force sources (linear-motor FMUs, electrical model off)",
          "pmsm": "our PMSM drive FMU (current, speed and position loops)",
          "linear": "our linear-motor drive FMU (its current loop and electrical model)"}
POSITIVE = Number(low=0, above=True)
NON_NEGATIVE = Number(low=0)
FRACTION = Number(low=0, high=1, below=True)
RECORDED = ("scene", "table", "vehicle", "cueing", "samples")  # [motion] keys of a motion given as a time series

SCHEMA = Schema("study file", "A configuration design study (`cosim design STUDY`): which platform of a family "
                "carries a motion, after Halder et al. Section V (docs/guide/design.md). Paths are relative to the "
                "study's folder.", (
    Table("", "The file holds the tables below; [axes], [motion] and at least one [[actuator]] are required."),
    Table("study", "The platform family, its payload and the limits.", (
        Key("name", Text(), "the name the summary shows (default: the file's name)"),
        Key("parameter_set", Choice(tuple(FAMILIES)), "the platform family: "
            + "; ".join(f"{name}: {family.describe}" for name, family in FAMILIES.items()), "halder2013"),
        Key("payload_mass", Number("kg", 0, above=True), "the payload (default: the parameter set's)"),
        Key("payload_inertia", Row((POSITIVE,) * 3), "its inertia diagonal [kg m^2] (default: the parameter set's)"),
        Key("joint_angle_limit_deg", Number("deg", 0, above=True), "both joints' largest tilt from the neutral", 20.0),
        Key("top_joint_angle_limit_deg", Number("deg", 0, above=True), "the top (universal) joint's own limit"),
        Key("bottom_joint_angle_limit_deg", Number("deg", 0, above=True), "the bottom (spherical) joint's own "
            "limit"),
        Key("payload_from", Text(), "where the payload's mass and inertia come from, printed with the assumptions "
            "(default: the study file where it gives them, the parameter set otherwise)"),
        Key("force_margins", Row((FRACTION, FRACTION)), "[friction, other]: shares of the continuous force kept for "
            "friction and for other factors", [0.07, 0.20]),
        Key("force_margins_mode", Choice(tuple(MARGIN_MODES)), "how the margins leave the force the demand may "
            "reach: " + "; ".join(f"{k}: {v}" for k, v in MARGIN_MODES.items()), "subtract"),
        Key("chosen", Free("axis = value"), "the design the summary's assumptions are judged at (default: "
            "[confirm]'s, else [workspace]'s, else the grid's middle)"),
        Key("samples", Number(low=3, high=10001, whole=True), "poses per basic motion along its path", 121),
        Key("fixed", Free("design value = number"), "design values of the family held at other values than the "
            "parameter set's (a stub, which cannot be an axis)"))),
    Table("thresholds", "Where the words of the summary change: each verdict is computed against these.", (
        Key("condition_number", Number(low=1, above=True), "above it a design is ill conditioned: "
            + CONDITION_REASON, Thresholds.condition_number),
        Key("singular_distance_factor", Number(low=0, above=True), "a singular pose nearer to the neutral than this "
            "many times the motion's half range along a DOF is near: " + NEAR_REASON,
            Thresholds.singular_distance_factor))),
    Table("axes.<value>", "The two design values the map sweeps (each a design value of the family, e.g. "
          "base_radius, disc_height for Halder's).", (
        Key("from", NON_NEGATIVE, "the first value (above 0 for a size: a length, an angle, a scale)", REQUIRED),
        Key("to", NON_NEGATIVE, "the last value (not below from)", REQUIRED),
        Key("step", POSITIVE, "the spacing (at most 2000 values an axis)", REQUIRED))),
    Table("motion", "What the platform must carry: each DOF from -range to +range in the shortest time its limits "
          "allow (the basic motions), or a time series (scene or table).", (
        *(Key(dof, Number("m", 0, 100), f"the {dof} half range [m] (at most 100 m: a hexapod's is a fraction of "
              "its legs)", 0.0) for dof in DOFS if dof not in ROTATIONS),
        *(Key(f"{dof}_deg", Number("deg", 0, 90, below=True), f"the {dof} half range [deg] (below 90: the Euler "
              "angles' pitch is singular there)", 0.0) for dof in ROTATIONS),
        Key("velocity", POSITIVE, "the translations' largest speed [m/s]"),
        Key("acceleration", POSITIVE, "their largest acceleration [m/s^2]"),
        Key("angular_velocity_deg", POSITIVE, "the rotations' largest speed [deg/s]"),
        Key("angular_acceleration_deg", POSITIVE, "their largest acceleration [deg/s^2]"),
        Key("scene", Text(path=True), "a scene whose reference motion (less its neutral pose) is the motion (a path, "
            "or a shipped scene's name)"),
        Key("table", Text(path=True), "a CSV of displacements from the neutral pose: a time column and any of x, y, "
            "z, roll, pitch, yaw [m, rad]"),
        Key("vehicle", Text(path=True), "a CSV of a vehicle's motion at the occupant's head (as a scene's [motion] "
            "vehicle): the motion is the platform's through the motion cueing (docs/guide/cueing.md)"),
        Key("cueing", Free("cueing FMU variable = value"), "with vehicle: the cueing's parameters (as a scene's "
            "[cueing.parameters])"),
        Key("samples", Number(low=4, high=100001, whole=True), "samples of the time series over its duration", 1001)),
          required=True),
    Table("actuator", "An actuator the designs are judged with; a rotary one may be given by its motor (torques and "
          "speed through the family's screw).", (
        Key("name", Text(), "its name", REQUIRED),
        Key("stroke", POSITIVE, "[m]", REQUIRED),
        Key("running_length_min", POSITIVE, "the leg system's length at the shortest stroke, stubs included [m]",
            REQUIRED),
        Key("continuous_force", POSITIVE, "at 100 % duty cycle [N] (or continuous_torque)"),
        Key("peak_force", POSITIVE, "what it gives for a moment, against the full model's peak [N]"),
        Key("speed", POSITIVE, "the largest extension rate [m/s]"),
        Key("continuous_torque", POSITIVE, "the motor's continuous torque [N m], times the screw's K_FT"),
        Key("peak_torque", POSITIVE, "the motor's peak torque [N m]"),
        Key("motor_speed", POSITIVE, "the motor's largest speed [rad/s], over the screw ratio"),
        Key("rotor_inertia", NON_NEGATIVE, "the motor's rotor and screw about its axis [kg m^2] (default: the "
            "parameter set's)"),
        Key("drive", Choice(tuple(DRIVEN)), "what a co-simulated confirmation of a [pareto] design drives it with "
            "(default: pmsm for an actuator given by its motor, force otherwise)")), many=True, required=True),
    Table("workspace", "The reach of one design: the positions and orientations it reaches within the actuator's "
          "running lengths and the joint limits, and how far it is from a singular pose.", (
        Key("point", Free("axis = value"), "the design: a value of each axis", REQUIRED),
        Key("actuator", Text(), "one of the study's actuators, by name", REQUIRED),
        Key("spacing", Number("m", 0, above=True), "the positions' grid", 0.02),
        Key("angle_step_deg", Number("deg", 0, above=True), "the orientations' grid", 1.0))),
    Table("optimise", "Within the axes' ranges, the design whose smallest margin over every constraint and motion is "
          "largest (differential evolution).", (
        Key("actuator", Text(), "one of the study's actuators, by name", REQUIRED),
        Key("seed", Number(low=0, whole=True), "the search's seed (the same seed, the same design)", 1),
        Key("iterations", Number(low=1, whole=True), "its generations at most", 60))),
    Table("pareto", "Geometry and actuator chosen together: the designs no other beats in every objective at once "
          "(NSGA-II, pymoo), each an admissible design of the map with an actuator of the catalogue (and, for one "
          "given by its motor, a screw lead); the knee and each objective's best confirmed by co-simulation.", (
        Key("objectives", ListOf(Choice(tuple(OBJECTIVES)), 2), "what is traded: " + "; ".join(
            f"{k}: {v}" for k, v in OBJECTIVES.items()), REQUIRED),
        Key("actuators", ListOf(Text(), 1), "the catalogue: names of the study's actuators (default: all)"),
        Key("screw_lead", Row((POSITIVE, POSITIVE)), "[from, to] the screw's travel per motor turn [m] an actuator "
            "given by its motor may take (a design variable; default: the parameter set's lead alone)"),
        Key("population", Number(low=4, high=1000, whole=True), "designs per generation", 40),
        Key("generations", Number(low=1, high=1000, whole=True), "generations", 25),
        Key("seed", Number(low=0, whole=True), "the search's seed (the same seed, the same front)", 1),
        Key("workspace_spacing", Number("m", 0.005, high=0.5), "the workspace objective's grid of positions", 0.05),
        Key("confirm", Flag(), "co-simulate the knee and each objective's best design, each with its actuator's "
            "drive", True))),
    Table("confirm", "One design through the co-simulation, every motion, closed loop.", (
        Key("point", Free("axis = value"), "the design: a value of each axis", REQUIRED),
        Key("actuator", Text(), "one of the study's actuators, by name", REQUIRED),
        Key("drive", Choice(tuple(DRIVEN)), "; ".join(f"{k}: {v}" for k, v in DRIVEN.items()), "force"))),
), StudyError)
