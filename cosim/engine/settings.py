"""How a system is run: the coupling algorithm and the macro-step control, as plain settings.

The step kernel (cosim/engine/kernel/kernel.c) implements each of them once; these classes only
choose and parameterise. They convert to and from flat string dictionaries, the form an SSP
annotation and the command line carry.
"""

from __future__ import annotations

import math
from dataclasses import MISSING, asdict, dataclass, fields
from typing import Mapping, Sequence

from .errors import InputError
from .schema import Key, Schema, Table
from .values import REQUIRED, Choice, Flag, Number, Text

ALGORITHMS = ("jacobi", "gauss-seidel")


class SettingsError(InputError):
    """A setting with a wrong name or value; the message names it, and `setting` is its name
    (a field of the settings classes) where one setting is at fault."""

    def __init__(self, message: str, setting: str | None = None):
        super().__init__(message)
        self.setting = setting


@dataclass(frozen=True)
class Algorithm:
    """Jacobi or Gauss-Seidel with input extrapolation of order 0, 1 or 2. `sequence`: the
    Gauss-Seidel stepping order (default: the components' order). `initial_sweeps`: fixed-point
    sweeps that make the outputs at the start consistent with the connected inputs (0: the outputs
    as the FMUs initialized them, as tools without such a sweep do). `zero_start`: every input is 0
    over the first macro step (the convention of fmpy.ssp, which starts its connections at 0).
    `threads`: 2 steps each Gauss-Seidel stage of components that feed none of each other (the
    platform's six drives) on two threads, bit for bit the results of one (worth it only while
    the second core is free: not inside a sweep that already uses every core). `feedthrough`:
    after each macro step, the outputs that depend on inputs at the same communication point
    (their FMUs' declared dependencies) are read again, in dependency order, with those inputs at
    their sources' new values, as OMSimulator does (an algebraic loop is refused, named)."""
    kind: str = "gauss-seidel"
    order: int = 1
    sequence: tuple[str, ...] | None = None
    initial_sweeps: int = 20
    zero_start: bool = False
    threads: int = 1
    feedthrough: bool = False

    def __post_init__(self):
        if self.kind not in ALGORITHMS:
            raise SettingsError(f"algorithm '{self.kind}': one of {', '.join(ALGORITHMS)}", "kind")
        if self.order not in (0, 1, 2):
            raise SettingsError(f"extrapolation order {self.order}: 0, 1 and 2 are supported", "order")
        if not (isinstance(self.initial_sweeps, int) and self.initial_sweeps >= 0):
            raise SettingsError(f"initial_sweeps {self.initial_sweeps!r}: a whole number >= 0", "initial_sweeps")
        if self.threads not in (1, 2):
            raise SettingsError(f"threads {self.threads!r}: 1 or 2", "threads")


def _positive(name: str, value: float) -> None:
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
        raise SettingsError(f"{name} = {value!r}: must be a positive finite number", name)


def _step_bounds(h_min: float, h_max: float) -> None:
    if h_min > h_max:
        raise SettingsError(f"h_min = {h_min!r} exceeds h_max = {h_max!r}", "h_min")


@dataclass(frozen=True)
class FixedStep:
    """Macro steps of `step`; the first `startup_time` seconds (a whole number of steps) at the
    finer `startup_step` (a whole fraction of the step), so that the start-up shock of the drives'
    efforts is resolved where it is steep (0: no finer start). `windows`: further (start, end)
    intervals [s] taken at the finer step too (where an input is known to jump, such as a load
    pulse's edges), widened to the regular steps they touch."""
    step: float
    startup_time: float = 0.0
    startup_step: float = 0.0
    windows: tuple[tuple[float, float], ...] = ()

    def __post_init__(self):
        _positive("step", self.step)
        for window in self.windows:
            if not (len(window) == 2 and all(math.isfinite(t) for t in window) and window[0] < window[1]):
                raise SettingsError(f"window {window!r}: a (start, end) pair with start < end", "windows")
        if self.windows and self.startup_time == 0.0:
            raise SettingsError("windows need startup_step, the finer step they are taken at (and a startup_time)",
                                "windows")
        if self.startup_time == 0.0:
            return
        _positive("startup_time", self.startup_time)
        _positive("startup_step", self.startup_step)
        per = self.step / self.startup_step
        if not (self.startup_step < self.step and abs(per - round(per)) < 1e-9 * per):
            raise SettingsError(f"startup_step = {self.startup_step!r}: must divide the step {self.step!r} a whole "
                                "number of times (more than once)", "startup_step")
        steps = self.startup_time / self.step
        if abs(steps - round(steps)) > 1e-9 * max(steps, 1.0) or round(steps) < 1:
            raise SettingsError(f"startup_time = {self.startup_time!r}: must be a whole number of steps of "
                                f"{self.step!r} s", "startup_time")


@dataclass(frozen=True)
class StepDoubling:
    """Step doubling with rollback: each macro step H once whole and once as two halves; the scaled
    difference of the outputs of the components named in `atol` (all, for one number) is the
    error against atol + rtol |y|. `force_reject`: a test hook, accepted-step indices whose first
    try is rejected."""
    step: float
    rtol: float = 1e-3
    atol: float | Mapping[str, float] = 1e-6
    h_min: float = 1e-6
    h_max: float = 1e-2
    force_reject: tuple[int, ...] = ()

    def __post_init__(self):
        for name in ("step", "rtol", "h_min", "h_max"):
            _positive(name, getattr(self, name))
        _step_bounds(self.h_min, self.h_max)
        for value in (self.atol.values() if isinstance(self.atol, Mapping) else [self.atol]):
            _positive("atol", value)


@dataclass(frozen=True)
class EnergyControl:
    """ECCO (Sadjina et al. 2017), the one law the kernel runs and the OSP export hands to libcosim:
    after each macro step H, per power bond the energy residual dE over the step against atol [J] +
    rtol |E| (E: the energy the bond transferred), eps = the largest over the bonds (at least 1e-10),
    and H_next = H min(change_max, max(change_min, safety eps^-(k_i + k_p) eps_prev^k_p)) within
    [h_min, h_max]; no rollback.

    Where libcosim's ecco_algorithm differs (and so a libcosim run of the exported system): it
    takes dE as the difference of the two sides' powers at the communication point times H, and E
    as the larger power times H, where we integrate both sides' powers over the step (trapezoid,
    with the interface-Jacobian correction a bond carries); it scales one bond (its first two
    simulators' first connections), where we take the largest over every bond; it keeps the step
    while an error is exactly zero. Its defaults are safety 0.99 and changes [0.2, 1.5]; ours are 1
    and [0.2, 2] (the step grows back twice as fast after a load pulse), and the export writes ours."""
    step: float
    rtol: float = 1e-3
    atol: float = 1e-4
    h_min: float = 1e-6
    h_max: float = 1e-2
    k_i: float = 0.15
    k_p: float = 0.2
    safety: float = 1.0
    change_min: float = 0.2
    change_max: float = 2.0

    def __post_init__(self):
        for name in ("step", "rtol", "atol", "h_min", "h_max", "safety", "change_min"):
            _positive(name, getattr(self, name))
        _step_bounds(self.h_min, self.h_max)
        for name in ("k_i", "k_p"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise SettingsError(f"{name} = {value!r}: must be a finite number >= 0", name)
        if not (self.change_min <= 1.0 <= self.change_max and math.isfinite(self.change_max)):
            raise SettingsError(f"change_min = {self.change_min!r}, change_max = {self.change_max!r}: the step's "
                                "change per step needs change_min <= 1 <= change_max", "change_max")


StepControl = FixedStep | StepDoubling | EnergyControl
CONTROLS = {"fixed": FixedStep, "doubling": StepDoubling, "energy": EnergyControl}


def control_name(control: StepControl) -> str:
    return {FixedStep: "fixed", StepDoubling: "doubling", EnergyControl: "energy"}[type(control)]


def to_strings(algorithm: Algorithm, control: StepControl) -> dict[str, str]:
    """The settings as name -> text (for an SSP annotation)."""
    out = {"algorithm": algorithm.kind, "order": str(algorithm.order),
           "initial_sweeps": str(algorithm.initial_sweeps), "step_control": control_name(control)}
    if algorithm.zero_start:
        out["zero_start"] = "true"
    if algorithm.threads != 1:
        out["threads"] = str(algorithm.threads)
    if algorithm.feedthrough:
        out["feedthrough"] = "true"
    if algorithm.sequence:
        out["sequence"] = " ".join(algorithm.sequence)
    for name, value in asdict(control).items():
        if name == "force_reject" or (name.startswith("startup_") and not getattr(control, "startup_time", 0.0)):
            continue
        if name == "windows":
            if value:
                out[name] = " ".join(f"{a!r}:{b!r}" for a, b in value)
            continue
        if isinstance(value, Mapping):
            value = " ".join(f"{k}={v!r}" for k, v in value.items())
        out[name] = repr(value) if isinstance(value, float) else str(value)
    return out


# -- the settings by name: their schema, and their text (an SSP annotation, the command line) -------

@dataclass(frozen=True)
class Names:
    """Component names, separated by spaces."""

    def describe(self) -> str:
        return "component names separated by spaces"

    def parse(self, text: str) -> tuple[str, ...]:
        return tuple(text.split())


@dataclass(frozen=True)
class Spans:
    """(start, end) pairs in seconds, written start:end separated by spaces."""

    def describe(self) -> str:
        return "start:end pairs [s] separated by spaces"

    def parse(self, text: str) -> tuple[tuple[float, ...], ...]:
        return tuple(tuple(float(t) for t in item.split(":", 1)) for item in text.split())


@dataclass(frozen=True)
class PerComponent:
    """A number, or component=number pairs separated by spaces (a value per component)."""
    unit: str = ""

    def describe(self) -> str:
        return "a positive number, or component=number pairs separated by spaces"

    def parse(self, text: str) -> float | dict[str, float]:
        if "=" in text:
            return {k: float(v) for k, v in (item.split("=", 1) for item in text.split())}
        return float(text)


def _default(cls: type, name: str):
    """A settings class's own default for a field (one source of the defaults)."""
    found = next(f for f in fields(cls) if f.name == name)
    return REQUIRED if found.default is MISSING and found.default_factory is MISSING else \
        (found.default if found.default is not MISSING else found.default_factory())


def _keys(cls: type, docs: Mapping[str, tuple]) -> tuple[Key, ...]:
    """Keys named as the settings name them, each with its field's default (the step's is the
    system's: its DefaultExperiment's)."""
    return tuple(Key(name, kind, doc, None if name == "step" else _default(cls, field_name))
                 for name, (field_name, kind, doc) in docs.items())


POSITIVE = Number(low=0, above=True)
SECONDS = Number("s", low=0, above=True)
COUPLING_KEYS = _keys(Algorithm, {
    "algorithm": ("kind", Choice(ALGORITHMS), "Jacobi (every component from the others' last outputs) or "
                  "Gauss-Seidel (in `sequence`, each from the newest outputs)"),
    "order": ("order", Number(low=0, high=2, whole=True), "the inputs' extrapolation over a step: 0 held, 1 "
              "linear, 2 quadratic (from the last outputs, or the FMUs' output derivatives)"),
    "sequence": ("sequence", Names(), "the Gauss-Seidel order of the components (default: the system's)"),
    "initial_sweeps": ("initial_sweeps", Number(low=0, whole=True), "fixed-point sweeps making the start's outputs "
                       "consistent with the connected inputs (0: as the FMUs initialized them)"),
    "zero_start": ("zero_start", Flag(), "every input 0 over the first step (fmpy.ssp's convention)"),
    "threads": ("threads", Number(low=1, high=2, whole=True), "2: each Gauss-Seidel stage of components that feed "
                "none of each other on two threads, bit for bit the same"),
    "feedthrough": ("feedthrough", Flag(), "after each step, outputs that depend on inputs at the same "
                    "communication point read again with those inputs' new values (as OMSimulator does)")})
FIXED_KEYS = _keys(FixedStep, {
    "step": ("step", SECONDS, "the macro step (default: the system's DefaultExperiment step)"),
    "startup_time": ("startup_time", Number("s", 0), "the first seconds at the finer startup_step (a whole number "
                     "of steps; 0: no finer start)"),
    "startup_step": ("startup_step", Number("s", 0), "the finer step of the start (a whole fraction of the step)"),
    "windows": ("windows", Spans(), "further spans taken at startup_step too (where an input jumps)")})
DOUBLING_KEYS = _keys(StepDoubling, {
    "step": ("step", SECONDS, "the first macro step (default: the system's DefaultExperiment step)"),
    "rtol": ("rtol", POSITIVE, "the relative tolerance of the local error"),
    "atol": ("atol", PerComponent(), "the absolute tolerance of the local error, in the outputs' units (one, or "
             "per component)"),
    "h_min": ("h_min", SECONDS, "the smallest step"),
    "h_max": ("h_max", SECONDS, "the largest step")})
ENERGY_KEYS = _keys(EnergyControl, {
    "step": ("step", SECONDS, "the first macro step (default: the system's DefaultExperiment step)"),
    "rtol": ("rtol", POSITIVE, "the energy residual's tolerance relative to the energy a bond transferred"),
    "atol": ("atol", POSITIVE, "the energy residual's absolute tolerance [J]"),
    "h_min": ("h_min", SECONDS, "the smallest step"),
    "h_max": ("h_max", SECONDS, "the largest step"),
    "k_i": ("k_i", Number(low=0), "the PI controller's integral gain"),
    "k_p": ("k_p", Number(low=0), "its proportional gain"),
    "safety": ("safety", POSITIVE, "the safety factor on the proposed step"),
    "change_min": ("change_min", POSITIVE, "the least factor a step changes by (at most 1)"),
    "change_max": ("change_max", POSITIVE, "the largest factor a step changes by (at least 1)")})
CONTROL_KEYS = {"fixed": FIXED_KEYS, "doubling": DOUBLING_KEYS, "energy": ENERGY_KEYS}
OUTPUT_KEYS = (Key("record", Text(), "what is recorded: component.variable=name separated by spaces (default: every "
                   "connected output, named component.variable)"),
               Key("output_interval", Number("s", 0, above=True), "results written every interval (default: every "
                   "macro step)"))
SCHEMA = Schema("run settings", "A system's run settings by name: the SSP annotation "
                "`com.stewart-cosim.settings` carries them, `cosim run SYSTEM --set NAME=VALUE` and a sweep's axes "
                "set them (cosim.engine.settings: Algorithm, FixedStep, StepDoubling, EnergyControl).", (
    Table("coupling", "How the components are coupled, whatever the step control.",
          (*COUPLING_KEYS, Key("step_control", Choice(tuple(CONTROLS)), "how the macro step is chosen: fixed (with a "
                               "finer start), doubling (local error by step doubling, with rollback) or energy "
                               "(ECCO: the power bonds' energy residual)", "fixed"))),
    *(Table(f"step_control = {name}", f"The settings of the {name} step control.", keys)
      for name, keys in CONTROL_KEYS.items()),
    Table("recording", "What the run records and how often.", OUTPUT_KEYS)), SettingsError, groups=True)


def from_strings(values: Mapping[str, str], default_step: float) -> tuple[Algorithm, StepControl]:
    """The settings from name -> text (an SSP annotation, command-line options); unknown names
    and bad values raise SettingsError naming them."""
    values = dict(values)
    name = values.pop("step_control", "fixed")
    if name not in CONTROLS:
        raise SettingsError(f"step_control '{name}': one of {', '.join(CONTROLS)}", "step_control")
    coupling = {k.name: k for k in COUPLING_KEYS}
    control = {k.name: k for k in CONTROL_KEYS[name]}
    unknown = sorted(set(values) - set(coupling) - set(control))
    if unknown:
        raise SettingsError(f"unknown setting '{unknown[0]}' for {name} step control (known: "
                            f"{', '.join(sorted({*coupling, *control}))})", unknown[0])
    parsed = {}
    for key, text in values.items():
        own = coupling.get(key) or control[key]
        try:
            parsed[key] = own.type.parse(str(text))
        except ValueError:
            raise SettingsError(f"{key} '{text}': must be {own.type.describe()}", key) from None
    algorithm = Algorithm(**{{"algorithm": "kind"}.get(k, k): parsed[k] for k in coupling if k in parsed})
    return algorithm, CONTROLS[name](**{"step": default_step, **{k: parsed[k] for k in control if k in parsed}})


# -- a system's settings as its SSP annotation carries them: how it runs, and what it records ---

OUTPUT_SETTINGS = tuple(k.name for k in OUTPUT_KEYS)


def system_settings(settings: Mapping[str, object], default_step: float,
                    overrides: Mapping[str, str] | None = None) -> tuple[Algorithm, StepControl]:
    """The run settings of a system's settings (its output settings left aside), with overrides
    (the command line's, a sweep point's) over them."""
    values = {k: str(v) for k, v in settings.items() if k not in OUTPUT_SETTINGS}
    values.update(overrides or {})
    return from_strings(values, default_step)


def output_settings(record: Sequence[tuple[str, str]], names: Sequence[str],
                    interval: float | None = None) -> dict[str, str]:
    """What a system records, as settings: record = 'component.variable=name ...', and the
    interval results are written at (none: every macro step)."""
    out = {"record": " ".join(f"{c}.{v}={n}" for (c, v), n in zip(record, names))}
    if interval:
        out["output_interval"] = repr(float(interval))
    return out


def recorded(settings: Mapping[str, object]) -> tuple[list[tuple[str, str]], list[str]] | None:
    """The (component, variable) pairs and column names of a `record` setting, or None."""
    text = settings.get("record")
    if not text:
        return None
    record, names = [], []
    for item in str(text).split():
        source, _, name = item.partition("=")
        component, _, variable = source.partition(".")
        if not (component and variable and name):
            raise SettingsError(f"record: {item!r} is not component.variable=name", "record")
        record.append((component, variable))
        names.append(name)
    return record, names


def output_interval(settings: Mapping[str, object]) -> float | None:
    interval = settings.get("output_interval")
    return float(interval) if interval else None
