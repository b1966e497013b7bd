"""Tuning a scene's motion cueing: the cueing parameters (within ranges the scene gives) that make
the platform's motion feel most like the vehicle's (cosim.platform.perception: the rms errors of
the perceived motion, each in thresholds of its channel, summed) while every leg stays in its
stroke, every joint within its angle and every drive within its current.

What the search minimises is the perceived error by the project's perception model, or by it and a
second one (Reid and Nahon's, perception.SECOND_ORGANS) alike: `[cueing.tune] judge`, so that a
cueing tuned by one model does not spend the stroke on what another feels less. Every figure gives
both.

Two judges, as the design studies have them: the kinematic screening plays the cueing FMU alone
and takes the platform on its reference (leg lengths and joint angles from the dynamics core, the
currents from its inverse dynamics along the reference); scipy's differential evolution searches
with it, on Dask. The co-simulation then confirms the best and the scene's own parameters: the
whole scene run, the platform's simulated motion felt, its legs, joints and drive currents
measured.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import numpy as np

from ..core import Core, gravity_of, mechanics_value
from ..perception import (ChannelQuality, Perceived, perceive, perceived_error, platform_motion, quality, second_opinion,
                          vehicle_motion)
from ..ports import DRIVES, LEGS, POSE
from ..run.compile import scene_cueing, scene_values
from ..run.errors import BUILD_ERRORS, scene_error
from ..run.runner import run_scene
from ..scene import Scene
from ..run.alone import play_cueing
from .search.optimise import evolve
from .cueing_bound import CueingBound, scene_bound

# searched where the scene's [cueing.tune] names no ranges, per [cueing] algorithm: for the classical
# washout the horizontal channels and the tilt, the ones a ground vehicle's motion exercises most;
# for the MPC its weights (each a decade or more about its default) and how fast its prediction of the
# vehicle's motion returns to rest beyond what it reads (mpc.prediction_decay) and how long its trend
# there carries on (mpc.prediction_trend)
DEFAULT_RANGES = {
    "classical": {"translation.x.gain": (0.1, 1.0), "translation.x.frequency": (0.5, 5.0),
                  "translation.y.gain": (0.1, 1.0), "translation.y.frequency": (0.5, 5.0),
                  "tilt.gain": (0.1, 1.0), "tilt.frequency": (0.5, 5.0),
                  "rotation.yaw.gain": (0.1, 1.0), "rotation.yaw.frequency": (0.1, 2.0)},
    "mpc": {"mpc.weight.specific_force": (0.2, 5.0), "mpc.weight.angular_rate": (3.0, 100.0),
            "mpc.weight.position": (0.1, 5.0), "mpc.weight.angle": (0.1, 5.0),
            "mpc.weight.acceleration": (0.01, 1.0), "mpc.prediction_decay": (0.2, 5.0),
            "mpc.prediction_trend": (0.0, 2.0)}}
# the drive's effort per ampere, by drive kind: the PMSM's torque constant, the linear motor's force constant
PER_AMPERE = {"pmsm": "motor.torque_constant", "linear": "motor.force_constant"}
CURRENT = {"pmsm": "current.q", "linear": "current"}
# [s] the screening's drives take a jump of the reference's rate (where the tilt's rate limit takes
# hold) over this long, about their speed loops' response; the co-simulation has the drives' own
SPREAD = 0.004
PENALTY = 100.0  # the objective's price of a limit's violation, per fraction of that limit


@dataclass(frozen=True)
class Limits:
    """What the platform must stay within: the legs' stroke [m], the joints' angle [rad], the
    drives' current [A] and the effort a drive gives per ampere (N m/A, N/A)."""
    leg_length: tuple[float, float]
    joint_angle: float
    current: float
    per_ampere: float

    def margins(self, lengths: np.ndarray, angles: np.ndarray, currents: np.ndarray) -> dict[str, float]:
        """Each limit's margin as a fraction of it (negative: violated): the stroke at both ends
        (of the stroke), the joint angle and the current (of their limits)."""
        low, high = self.leg_length
        stroke = high - low
        return {"stroke (long end)": float((high - np.nanmax(lengths)) / stroke),
                "stroke (short end)": float((np.nanmin(lengths) - low) / stroke),
                "joint angle": float(1.0 - np.nanmax(angles) / self.joint_angle),
                "current": float(1.0 - np.nanmax(np.abs(currents)) / self.current)}


def scene_limits(scene: Scene) -> Limits:
    """A scene's limits: its mechanics' stroke and joint angle, its drives' current limit (ours)."""
    mechanics, drives = scene_values(scene)
    from ...engine.artifacts import fmu_path
    from ...engine.checks import variables
    drive = variables(fmu_path(DRIVES[scene.drive].fmu))

    def of_drive(name: str) -> float:
        return float(drives.get(name, drive[name].start))
    return Limits((float(mechanics_value(mechanics, "limit.leg_length_min")),
                   float(mechanics_value(mechanics, "limit.leg_length_max"))),
                  float(mechanics_value(mechanics, "limit.joint_angle")), of_drive("limit.current"),
                  of_drive(PER_AMPERE[scene.drive]))


@dataclass
class Judged:
    """A cueing's parameters judged: the perceived error (by the project's model, per channel, and by
    the second model), and the limits' margins."""
    parameters: dict[str, float]
    perceived_error: float
    channels: list[ChannelQuality]
    margins: dict[str, float]
    how: str  # "screened" (the platform on its reference) or "co-simulated"
    second: float  # the perceived error by the second model (perception.SECOND_ORGANS)

    @classmethod
    def of(cls, parameters: dict[str, float], felt: Perceived, margins: dict[str, float], how: str) -> "Judged":
        channels = quality(felt)
        return cls(dict(parameters), perceived_error(channels), channels, margins, how, second_opinion(felt))

    @property
    def within(self) -> bool:
        return all(m >= 0.0 for m in self.margins.values())

    def judged(self, judge: str = "project") -> float:
        """The perceived error by the judge (JUDGES): the project's model's, or the mean of both models'."""
        return self.perceived_error if judge == "project" else 0.5 * (self.perceived_error + self.second)

    def objective(self, judge: str = "project") -> float:
        """What the search minimises: the perceived error by the judge, plus PENALTY per fraction a limit
        is passed by."""
        return self.judged(judge) + PENALTY * sum(max(0.0, -m) for m in self.margins.values())

    def line(self) -> str:
        worst = min(self.margins, key=self.margins.get)
        return (f"{self.how}: perceived error {self.perceived_error:.3f} (by the second model {self.second:.3f}), "
                + ", ".join(f"{k} margin {v:.1%}" for k, v in self.margins.items())
                + (" (within every limit)" if self.within else f" (past the {worst} limit)"))


def screen(scene: Scene, parameters: dict[str, float]) -> Judged:
    """The kinematic screening of cueing `parameters` (over the scene's own): the cueing FMU alone
    at the scene's step, the platform on its reference (its rates and accelerations by
    second-order differences, the accelerations averaged over SPREAD), felt at the scene's head
    point; leg lengths and joint angles from the dynamics core, the drives' currents from its
    inverse dynamics along the reference (no external load)."""
    mechanics, _ = scene_values(scene)
    values = {**scene_cueing(scene, mechanics), **parameters}
    times, poses, _, taken = play_cueing(values, scene.duration, scene.step)
    from scipy.ndimage import uniform_filter1d
    rates = np.gradient(poses, times, axis=0, edge_order=2)
    accelerations = np.gradient(rates, times, axis=0, edge_order=2)
    spread = max(1, int(round(SPREAD / scene.step)))  # a jump of the rate (the tilt's limiter) as the drives take it
    accelerations = uniform_filter1d(accelerations, spread, axis=0, mode="nearest")
    twist = np.column_stack([rates[:, :3], euler_angular_velocity(poses, rates)])
    gravity = gravity_of(mechanics)
    felt = perceive(times, vehicle_motion(taken[:, :3], taken[:, 3:], float(np.linalg.norm(gravity))),
                    platform_motion(times, poses, twist, np.array(scene.head), gravity))
    core = _core(scene)
    kinematics = core.pose_kinematics(poses)
    efforts = core.inverse_dynamics_many(poses, rates, accelerations)
    limits = scene_limits(scene)
    margins = limits.margins(kinematics["length"], np.maximum(kinematics["lower_angle"], kinematics["upper_angle"]),
                             efforts / limits.per_ampere)
    return Judged.of(parameters, felt, margins, "screened")


def euler_angular_velocity(poses: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """The base-frame angular velocity (n x 3) of poses turning at their rates (R = Rz Ry Rx):
    w = roll' Rz Ry e_x + pitch' Rz e_y + yaw' e_z."""
    pitch, yaw = poses[:, 4], poses[:, 5]
    roll_rate, pitch_rate, yaw_rate = rates[:, 3], rates[:, 4], rates[:, 5]
    return np.column_stack([roll_rate * np.cos(yaw) * np.cos(pitch) - pitch_rate * np.sin(yaw),
                            roll_rate * np.sin(yaw) * np.cos(pitch) + pitch_rate * np.cos(yaw),
                            -roll_rate * np.sin(pitch) + yaw_rate])


_CORES: dict[str, Core] = {}


def _core(scene: Scene) -> Core:
    """The scene's platform in the dynamics core (one per platform and process: the search asks often)."""
    values = scene_values(scene)[0]
    key = repr(sorted((k, str(v)) for k, v in values.items()))
    if key not in _CORES:
        _CORES[key] = Core().use_start_values(values)
    return _CORES[key]


def confirm(scene: Scene, parameters: dict[str, float]) -> Judged:
    """Cueing `parameters` (over the scene's own) confirmed by co-simulating the scene: the
    platform's simulated motion felt at the head; the legs' lengths and joint angles at its
    simulated poses (the dynamics core), the drives' currents as they ran."""
    tuned = scene.changed({"cueing.parameters": {**scene.cueing_parameters, **parameters}})
    result, report = run_scene(tuned)
    core = _core(scene)
    keep = np.r_[True, np.diff(result["time"]) > 0]
    kinematics = core.pose_kinematics(np.column_stack([result[f"pose.{a}"] for a in POSE])[keep])
    current = CURRENT[scene.drive]
    currents = np.column_stack([result[f"{current}[{i}]"] for i in LEGS])
    margins = scene_limits(scene).margins(kinematics["length"], np.maximum(kinematics["lower_angle"],
                                                                          kinematics["upper_angle"]), currents)
    return Judged.of(parameters, report.perceived, margins, "co-simulated")


def _objective(x: np.ndarray, scene: Scene, keys: tuple[str, ...], judge: str) -> float:
    try:
        return screen(scene, dict(zip(keys, map(float, x)))).objective(judge)
    except Exception:  # the FMU refused these values (none in the ranges should): the worst there is
        return math.inf


@dataclass
class Tuning:
    """A tuned cueing: the scene's own and the best parameters, each screened and co-simulated."""
    ranges: dict[str, tuple[float, float]]
    best: dict[str, float]
    evaluations: int
    seconds: float
    screened: dict[str, Judged] = field(default_factory=dict)   # "scene", "tuned"
    confirmed: dict[str, Judged] = field(default_factory=dict)  # "scene", "tuned"
    floor: CueingBound | None = None  # the least error any cueing could reach on the drive (cueing_bound)
    judge: str = "project"  # what the search minimised (JUDGES)

    @property
    def better(self) -> bool:
        """The tuned parameters feel better than the scene's own by the judge in co-simulation, within
        every limit."""
        tuned, own = self.confirmed["tuned"], self.confirmed["scene"]
        return tuned.within and tuned.judged(self.judge) < own.judged(self.judge)

    def lines(self) -> list[str]:
        judged = ("the perceived error" if self.judge == "project" else
                  "the mean of the perceived errors by the project's model and the second")
        out = [f"tuned {len(self.ranges)} cueing parameters by differential evolution ({judged} least): "
               f"{self.evaluations} screenings in {self.seconds:.0f} s"]
        for name in ("scene", "tuned"):
            out.append("the scene's cueing:" if name == "scene" else "the tuned cueing:")
            out += [f"  {judged.line()}" for judged in (self.screened[name], self.confirmed[name])]
        out.append("tuned parameters: " + ", ".join(f"{k} = {v:.4g}" for k, v in self.best.items()))
        if self.floor is not None:
            tuned = self.confirmed["tuned"].perceived_error
            left = max(0.0, tuned - self.floor.perceived_error)
            out.append(f"the floor: no cueing within the platform's stroke and joints, tilting no faster than "
                       f"{_tilt_rates(self.floor)}, feels closer by the project's model than "
                       f"{self.floor.perceived_error:.3f}, even knowing the whole drive ("
                       + (f"the tuned cueing is {left:.3f} above it: at most {left / tuned:.0%} of its error is left to gain"
                          if left > 0.0 else "the tuned cueing is on it: nothing is left to gain")
                       + "; cosim.platform.design.cueing_bound)")
        out.append("verdict: the tuned cueing " + ("feels closer to the vehicle than the scene's, within every limit, "
                                                    "confirmed by co-simulation" if self.better else
                                                    "is not confirmed better within every limit by co-simulation"))
        return out


def _tilt_rates(floor: CueingBound) -> str:
    """The floor's tilt rate limit, in words: one for both axes, or roll's and pitch's."""
    if floor.pitch_rate_limit is None:
        return f"{math.degrees(floor.tilt_rate_limit):.3g} deg/s"
    return f"{math.degrees(floor.tilt_rate_limit):.3g} deg/s in roll and {math.degrees(floor.pitch_rate_limit):.3g} in pitch"


def tune(scene: Scene, ranges: dict[str, tuple[float, float]] | None = None, workers: int | None = 0,
         scheduler: str | None = None, seed: int = 1, iterations: int = 15, population: int = 6,
         progress: bool = False, judge: str = "project") -> Tuning:
    """The cueing parameters within `ranges` (default: the scene's [cueing.tune] ranges, or
    DEFAULT_RANGES of its algorithm) whose screened objective is least (Judged.objective), searched on Dask
    (workers, scheduler as for a sweep), then it and the scene's own confirmed by co-simulation;
    `progress`: the search's progress shown (the command line's); `judge`: by which perception
    model (JUDGES: the project's, or the mean of it and the second model's)."""
    ranges = dict(ranges or scene.cueing_ranges or DEFAULT_RANGES[scene.cueing_algorithm])
    keys = tuple(ranges)
    start = time.perf_counter()
    try:  # the scene's own cueing first: a vehicle file the cueing FMU refuses, or a run too long to record,
        own = screen(scene, {})  # is one line at the scene's key
    except BUILD_ERRORS as error:
        mapped = scene_error(scene, error)
        if mapped is None:
            raise
        raise mapped from None
    result = evolve(partial(_objective, scene=scene, keys=keys, judge=judge), [tuple(map(float, ranges[k])) for k in keys],
                    workers, scheduler, seed, iterations, population, progress="tune: screenings" if progress else None)
    best = dict(zip(keys, map(float, result.x)))
    tuning = Tuning(ranges, best, int(result.nfev), time.perf_counter() - start, judge=judge)
    for name, parameters in (("scene", {}), ("tuned", best)):
        tuning.screened[name] = own if name == "scene" else screen(scene, parameters)
        tuning.confirmed[name] = confirm(scene, parameters)
    rate_limit, pitch_rate_limit = (ranges.get(key, (None, None))[1]  # searched: the fastest it may take
                                    for key in ("tilt.rate_limit", "tilt.pitch_rate_limit"))
    try:
        tuning.floor = scene_bound(scene, rate_limit, pitch_rate_limit=pitch_rate_limit)
    except RuntimeError:  # the solver did not converge: the report goes without its floor
        tuning.floor = None
    return tuning


def tuned_scene_text(scene: Scene, best: dict[str, float]) -> str:
    """The scene's file (its comments kept) with what was set over it (`cosim tune --set`, each
    marked so) and the tuned values in its [cueing.parameters], every file it names by an absolute
    path, so that it runs from anywhere; the tuned values marked so."""
    import tomlkit
    from ...engine.schema import split_key
    document = tomlkit.parse(scene.text)
    for key, value in scene.overrides.items():
        *tables, name = split_key(key)
        table = document
        for part in tables:
            table = table.setdefault(part, tomlkit.table())
        table[name] = _marked(value, scene.given.get(key, "set over the scene"))
    cueing = document.setdefault("cueing", tomlkit.table())
    parameters = cueing.setdefault("parameters", tomlkit.table())
    for name, value in best.items():
        parameters[name] = _marked(float(f"{value:.6g}"), "tuned (cosim tune)")
    for table, key in _path_keys(document):
        if not Path(table[key]).is_absolute():
            table[key] = str((scene.path.parent / table[key]).resolve())
    return tomlkit.dumps(document)


def _marked(value: object, how: str):
    """A value as the tuned scene writes it, a comment saying how it was set (a table's cannot)."""
    import tomlkit
    item = tomlkit.item(value)
    return item if isinstance(item, (tomlkit.items.Table, tomlkit.items.AoT)) else item.comment(how)


def _path_keys(document) -> list[tuple[dict, str]]:
    """Every file's path in a scene's document (the schema's path keys): (its table, its key)."""
    from ..scene.schema import SCHEMA
    found = []
    for table in SCHEMA.tables:
        for key in (k.name for k in table.keys if getattr(k.type, "path", False)):
            places = [document]
            for part in table.name.split("."):
                places = [t[name] for t in places for name in (t if part.startswith("<") else [part])
                          if isinstance(t.get(name), dict)]
            found += [(t, key) for t in places if isinstance(t.get(key), str)]
    return found


def write_tuned(scene: Scene, tuning: Tuning, out: Path) -> Path:
    """The tuned scene beside the scene's results: out/<stem>_tuned.toml."""
    from ...engine.files import write_text
    return write_text(out / f"{scene.path.stem}_tuned.toml", tuned_scene_text(scene, tuning.best), "the tuned scene")
