"""The scene file's keys: every table and key a scene may hold, with its type, range, unit, default
and what it does (docs/reference/scene.md is generated from here). What a key's value means
beyond its own range (a drive set that must exist, a finer start that needs its step) the reader
checks (cosim.platform.scene.reader)."""

from __future__ import annotations

from ...engine.errors import InputError
from ...engine.schema import Key, Schema, Table
from ...engine.values import REQUIRED, Choice, Either, Flag, Free, Items, ListOf, Number, Row, Text
from ...engine.settings import COUPLING_KEYS
from ..perception import JUDGES
from ..ports import DRIVES, LEGS, POSE

FRAMES = {"base": 1, "platform": 2}  # as the trajectory FMU's pulse[k].frame numbers them
WRENCH_COMPONENTS = ("force.x", "force.y", "force.z", "torque.x", "torque.y", "torque.z")
CAPACITY = {"sines": 3, "steps": 2, "ramps": 2, "pulses": 2}  # what the trajectory FMU holds (pulses: per component)
PLATFORMS = ("meng2010", "sumnu2015")  # the platforms' parameter sets a scene may name
NATIVE_DRIVE = {"meng2010": "pmsm", "sumnu2015": "linear"}  # the drive each platform's papers use


class SceneError(InputError):
    """A scene file that cannot be run: the message names the file, the key and its line."""


SECONDS = Number("s", 0, above=True)
SECONDS_OR_NONE = Number("s", 0)
ANY = Number()
ENGINE = {k.name: k for k in COUPLING_KEYS}

SCHEMA = Schema("scene file", "A scene (`cosim run SCENE`): one run of the platform, as FMUs and their connections "
                "(docs/guide/scenes.md). Paths are relative to the scene's folder.", (
    Table("", "The file holds the tables below; [scene] with its duration is required."),
    Table("scene", "The run.", (
        Key("name", Text(), "the name its reports show (default: the file's name)"),
        Key("duration", SECONDS, "the simulated time", REQUIRED),
        Key("step", SECONDS, "the macro step (at most the duration)", 1e-3),
        Key("fmi", Number("", 2, 3, whole=True), "the FMI version of our FMUs the run takes: 2, or 3 (the same models "
            "as FMI 3.0 Co-Simulation FMUs, which take their inputs' derivatives through inputs of their own, "
            "fmi.rate.* and fmi.curvature.*: the same run, bit for bit; docs/guide/fmus.md)", 2)),
          required=True),
    Table("drive", "The six legs' drives: one line swaps them (`kind`).", (
        Key("kind", Choice(tuple(DRIVES)), "the drive: a PMSM with a ball screw (pmsm_drive) or a linear motor "
            "(linear_motor); with `fmu`, the kind of its ports", "pmsm"),
        Key("tuning", Choice(("auto", "defaults")), "auto: each drive's loops designed for its leg "
            "(cosim.platform.run.tuning); defaults: the FMU's (default on the drive's own platform, auto on another)"),
        Key("parameter_set", Text(), "a drive set sized for this platform, params/<platform>_<kind>.toml (default for "
            "a swapped drive where one exists), or \"none\": the FMU's own values"),
        Key("parameters", Free("drive FMU variable = value"), "values of the drive FMU's parameters, checked against "
            "its modelDescription; they win over the drive set and the design"),
        Key("fmu", Text(path=True), "a drive FMU of your own on every leg, with the drive ports of INTERFACES.md; it "
            "keeps its own gains"),
        Key("continuous_limit", Text(), "the parameter of your drive FMU that holds its continuous torque or force "
            "(the sizing check holds it to the legs' static load)"))),
    Table("drive.leg.<i>", "Leg i's own drive (i = 1..6): its FMU, or values over [drive.parameters].", (
        Key("fmu", Text(path=True), "leg i's drive FMU (the same kind as the others)"),
        Key("parameters", Free("drive FMU variable = value"), "leg i's values, over [drive.parameters]"),
        Key("continuous_limit", Text(), "as [drive] continuous_limit, for leg i's FMU")), names=tuple(map(str, LEGS))),
    Table("mechanics", "The platform: its parameter set and values of the mechanics FMU.", (
        Key("parameter_set", Choice(PLATFORMS), "the platform: Meng et al. 2010 or Sumnu 2015", "meng2010"),
        Key("mass_set", Text(), "one of the parameter set's mass sets (Sumnu's: heavy, light)", "heavy"),
        Key("parameters", Free("mechanics FMU variable = value"), "values of the mechanics FMU's parameters, checked "
            "against its modelDescription; they win over the parameter set"))),
    Table("coupling", "How the FMUs are coupled and the macro step chosen (cosim.engine.settings).", (
        ENGINE["algorithm"], ENGINE["order"],
        Key("step_control", Choice(("fixed", "doubling", "energy")), "fixed: scene.step throughout (with a finer "
            "start); doubling: the local error by step doubling, with rollback; energy: ECCO, the power bonds' energy "
            "residual", "fixed"),
        Key("rtol", Number(low=0, above=True), "an adaptive control's relative tolerance (default: the control's)"),
        Key("atol", Number(low=0, above=True), "an adaptive control's absolute tolerance: m and rad of the legs' "
            "outputs for doubling (default 1e-3), J for energy (default: the control's)"),
        Key("h_min", SECONDS, "an adaptive control's smallest step (default: the control's)"),
        Key("h_max", SECONDS, "an adaptive control's largest step (default: the control's)"),
        Key("startup_time", SECONDS_OR_NONE, "fixed steps: the first seconds at the finer startup_step, for the drives' "
            "start-up shock (rounded up to whole steps; 0: none)", 0.0),
        Key("startup_step", SECONDS_OR_NONE, "the finer step (the largest whole fraction of the step no longer than "
            "this)"),
        Key("edge_time", SECONDS_OR_NONE, "fixed steps: the seconds after each load pulse's edges at startup_step too",
            0.0),
        ENGINE["threads"],
        Key("interface_jacobian", Flag(), "each drive's slope d effort / d flow wired to the mechanics with the flow "
            "the drive saw: the drives' damping integrated implicitly, stable at longer steps (needs order 1 or 2)",
            False),
        ENGINE["feedthrough"])),
    Table("trajectory", "The reference pose: per DOF below, and a table of samples added to it.", (
        Key("table", Text(path=True), "a CSV file: a time column and any of x, y, z, roll, pitch, yaw [m, rad]"),
        Key("interpolation", Choice(("cubic", "linear")), "between the table's samples", "cubic"))),
    Table("trajectory.<dof>", "One DOF's reference (x, y, z [m]; roll, pitch, yaw [rad]): an offset plus sines, steps "
          "and ramps.", (
        Key("offset", Either((ANY, Choice(("neutral",)))), "a constant, or \"neutral\": the platform's neutral pose "
            "solved from its geometry", 0.0),
        Key("sines", Items((Key("amplitude", ANY, "m or rad", REQUIRED), Key("frequency", ANY, "[Hz]", REQUIRED),
                            Key("phase", ANY, "[rad]", 0.0)), CAPACITY["sines"]), "a sum of sines"),
        Key("steps", Items((Key("time", ANY, "[s]", REQUIRED), Key("height", ANY, "m or rad", REQUIRED)),
                           CAPACITY["steps"]), "steps at their times"),
        Key("ramps", Items((Key("start", ANY, "[s]", REQUIRED), Key("end", ANY, "[s]", REQUIRED),
                            Key("slope", ANY, "m/s or rad/s", REQUIRED)), CAPACITY["ramps"]),
            "ramps from start to end")), names=POSE),
    Table("load", "External loads on the platform.", (
        Key("pulses", Items((Key("component", Choice(WRENCH_COMPONENTS), "the wrench component", REQUIRED),
                             Key("value", ANY, "N or N m", REQUIRED), Key("start", ANY, "[s]", REQUIRED),
                             Key("end", ANY, "[s]", REQUIRED),
                             Key("frame", Choice(tuple(FRAMES)), "base, or platform: a follower load along the "
                                 "platform's own axes", "base"))),
            f"rectangular pulses, {CAPACITY['pulses']} per component"),)),
    Table("outputs", "What is recorded besides the pose and its reference.", (
        Key("mechanics", ListOf(Text()), "mechanics outputs"),
        Key("drive", ListOf(Text()), "per drive (default: its effort, speed or velocity and current)"),
        Key("interval", SECONDS, "results written every interval (default: every macro step)"))),
    Table("motion", "A vehicle's motion instead of a pose reference (docs/guide/fmus.md, cueing): the cueing FMU, "
          "the classical washout, turns it into the platform's pose reference; the trajectory then gives the loads "
          "alone.", (
        Key("vehicle", Text(path=True), "a CSV of the vehicle's motion at the occupant's head: time, then any of "
            "specific_force.x/y/z [m/s^2] and angular_rate.x/y/z [rad/s] (vehicle frame: x forward, y left, z up)"),)),
    Table("cueing", "The motion cueing of a [motion] vehicle.", (
        Key("algorithm", Choice(("classical", "mpc")), "the classical washout (Reid and Nahon), or model-predictive "
            "cueing: the perceived error least over a horizon, the legs within their stroke (docs/guide/cueing.md)",
            "classical"),
        Key("parameters", Free("cueing FMU variable = value"), "values of the cueing FMU's parameters (gains, limits, "
            "filter frequencies and dampings, the tilt's rate limit), checked against its modelDescription"),
        Key("head", Row((Number("m"),) * 3), "the occupant's head in the platform's frame, from its origin: where "
            "the platform's motion is felt and judged against the vehicle's (docs/guide/cueing.md)", [0.0, 0.0, 0.0]),
        Key("preview", Number("s", 0), "how far ahead of now the MPC may read the recorded drive: foresight, which "
            "a live driver does not give (0: none, as live; the motion beyond predicted from what it read: the "
            "cueing FMU's mpc.prediction_trend and mpc.prediction_decay)", 0.0))),
    Table("cueing.tune", "What `cosim tune SCENE` searches (docs/guide/cueing.md): the cueing parameters that "
          "feel most like the vehicle within the platform's limits, by differential evolution on Dask.", (
        Key("ranges", Free("cueing FMU parameter = [low, high]"), "the parameters searched and their ranges (default: "
            "for the classical washout the gain and frequency of the x and y translation, the tilt and the yaw rotation; "
            "for the MPC its weights of the perceived specific force and angular rate, the position, the angle and the "
            "acceleration, and its prediction's decay)"),
        Key("iterations", Number("", 1, whole=True), "generations of the search", 15),
        Key("population", Number("", 1, whole=True), "points per parameter in a generation", 6),
        Key("seed", Number("", 0, whole=True), "the search's seed: the same seed, the same answer", 1),
        Key("judge", Choice(JUDGES), "by which perception model the search judges a cueing: the project's, or "
            "both alike (the mean of its perceived error and the second model's, Reid and Nahon's): a cueing tuned "
            "by one model may spend the stroke on what the other feels less", "project"))),
    Table("live", "A live input's limits (`cosim run SCENE --listen udp://HOST:PORT`, docs/guide/realtime.md): the "
          "reference moves towards each pose received, braking in time, within these; refused packets and a silent "
          "sender leave it where it is going.", (
        Key("velocity_max", Number("m/s", 0, above=True), "the reference's largest speed along x, y, z", 0.25),
        Key("angular_velocity_max", Number("rad/s", 0, above=True), "its largest roll, pitch and yaw rate", 0.5),
        Key("acceleration_max", Number("m/s^2", 0, above=True), "its largest acceleration along x, y, z", 2.0),
        Key("angular_acceleration_max", Number("rad/s^2", 0, above=True), "its largest angular acceleration", 4.0),
        Key("watchdog", SECONDS, "wall seconds without a good packet after which the reference goes back to the "
            "neutral pose", 0.5),
        Key("late_after", SECONDS, "a packet for a simulated time older than this is late and refused", 0.1))),
), SceneError)


def setting_key(name: str) -> str:
    """The scene key a run setting given by its name sets (`cosim run SCENE --set step=5e-4`: the
    names of cosim.engine.settings), a dotted key as it is; SceneError for a setting a scene does
    not take."""
    if "." in name:
        return name
    if name == "step":
        return "scene.step"
    coupling = SCHEMA.table("coupling")
    if coupling.key(name) is not None:
        return f"coupling.{name}"
    raise SceneError(f"'{name}' is not a run setting a scene takes (a scene's: step, "
                     f"{', '.join(k.name for k in coupling.keys)}; or any of its keys as table.key, e.g. "
                     "'mechanics.parameters.\"platform.mass\"')")
