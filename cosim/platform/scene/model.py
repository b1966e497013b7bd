"""A scene as the program holds it: the file's document (checked against its schema) and, derived
from it once, the typed scene the run is built from, the engine's settings objects among them.

A Scene is never edited in place: `scene.changed({"scene.step": 5e-4})` is the scene with values
set at keys of its document, read and checked as if its file said them, without reading the file
again. Its derived fields cannot be given to `dataclasses.replace` (they are not init fields),
so no change can bypass the checks or be lost when the scene is changed again."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Mapping

from ...engine.schema import Document
from ...engine.settings import Algorithm, StepControl


@dataclass(frozen=True)
class Sine:
    amplitude: float
    frequency: float  # [Hz]
    phase: float = 0.0  # [rad]


@dataclass(frozen=True)
class Step:
    time: float
    height: float


@dataclass(frozen=True)
class Ramp:
    start: float
    end: float
    slope: float


@dataclass(frozen=True)
class Signal:
    """One DOF's reference: an offset plus sines, steps and ramps."""
    offset: float = 0.0
    sines: tuple[Sine, ...] = ()
    steps: tuple[Step, ...] = ()
    ramps: tuple[Ramp, ...] = ()

    def document(self) -> dict[str, Any]:
        """The signal as a scene file writes it ([trajectory.<dof>]), for `Scene.changed`."""
        return {"offset": self.offset, **{kind: [asdict(item) for item in getattr(self, kind)]
                                          for kind in ("sines", "steps", "ramps") if getattr(self, kind)}}


@dataclass(frozen=True)
class Pulse:
    component: str  # force.x ... torque.z
    value: float
    start: float
    end: float
    frame: str = "base"  # or "platform": a follower load that turns with the platform

    def document(self) -> dict[str, Any]:
        """The pulse as a scene file writes it (an entry of [load] pulses)."""
        return asdict(self)


@dataclass(frozen=True)
class Scene:
    """A scene: its file (path, text and TOML document) and the overrides set over it (dotted keys,
    as the file writes them); everything else is derived from them when the scene is made
    (cosim.platform.scene.reader.derive) and checked there."""
    path: Path
    text: str = field(repr=False)
    data: Mapping[str, Any] = field(repr=False)  # the file's TOML document, as read
    overrides: Mapping[str, Any] = field(default_factory=dict)  # the dotted keys set over the file
    given: Mapping[str, str] = field(default_factory=dict, repr=False)  # how some were given ('--set step=...')
    document: Document = field(init=False, repr=False)  # the file with the overrides, checked
    name: str = field(init=False)
    duration: float = field(init=False)  # [s]
    fmi: int = field(init=False)  # [scene] fmi: the FMI version of our FMUs (2 or 3)
    drive: str = field(init=False)  # the drive kind: "pmsm" or "linear"
    tuning: str = field(init=False)  # "auto": the drives' loops designed for this platform, or "defaults"
    drive_set: str | None = field(init=False)  # params/<name>.toml: a drive sized for this platform
    drive_parameters: dict[str, Any] = field(init=False)  # [drive.parameters]
    drive_fmu: Path | None = field(init=False)  # [drive] fmu: a drive FMU of the user's own on every leg
    leg_fmus: dict[int, Path] = field(init=False)  # [drive.leg.<i>] fmu: leg i's own drive FMU
    leg_parameters: dict[int, dict[str, Any]] = field(init=False)  # [drive.leg.<i>] parameters
    continuous_limit: dict[int, str] = field(init=False)  # per leg: the user's drive's parameter that holds
    #                                                      its continuous torque or force, for the sizing check
    parameter_set: str = field(init=False)  # the platform's: meng2010 or sumnu2015
    mass_set: str = field(init=False)
    mechanics_parameters: dict[str, Any] = field(init=False)  # [mechanics.parameters]
    algorithm: Algorithm = field(init=False)  # the coupling (cosim.engine.settings)
    control: StepControl = field(init=False)  # the macro-step control, its finer start and edge windows
    interface_jacobian: bool = field(init=False)  # the drives' slopes d effort / d flow wired to the mechanics
    trajectory: dict[str, Signal] = field(init=False)  # per DOF
    neutral: tuple[str, ...] = field(init=False)  # the DOFs whose offset is the platform's neutral pose
    table: Path | None = field(init=False)  # [trajectory] table
    vehicle: Path | None = field(init=False)  # [motion] vehicle: the pose reference from motion cueing
    cueing_parameters: dict[str, Any] = field(init=False)  # [cueing.parameters]
    cueing_algorithm: str = field(init=False)  # [cueing] algorithm: "classical" or "mpc"
    cueing_preview: float = field(init=False)  # [cueing] preview: seconds of the recording the MPC reads ahead [s]
    head: tuple[float, float, float] = field(init=False)  # [cueing] head: the occupant's head, platform frame [m]
    cueing_ranges: dict[str, tuple[float, float]] | None = field(init=False)  # [cueing.tune] ranges
    cueing_search: tuple[int, int, int] = field(init=False)  # [cueing.tune] iterations, population, seed
    cueing_judge: str = field(init=False)  # [cueing.tune] judge: "project" or "both" (perception.JUDGES)
    interpolation: str = field(init=False)
    pulses: tuple[Pulse, ...] = field(init=False)
    outputs_mechanics: tuple[str, ...] = field(init=False)
    outputs_drive: tuple[str, ...] | None = field(init=False)  # None: the drive kind's default
    output_interval: float | None = field(init=False)  # [s] None: every macro step

    def __post_init__(self):
        from .reader import derive
        for name, value in derive(self).items():
            object.__setattr__(self, name, value)

    @property
    def step(self) -> float:
        """The macro step [s] (the first one, under an adaptive control)."""
        return self.control.step

    def leg_fmu(self, leg: int) -> Path | None:
        """Leg `leg`'s (1..6) drive FMU when it is not ours."""
        return self.leg_fmus.get(leg, self.drive_fmu)

    def changed(self, overrides: Mapping[str, Any], given: Mapping[str, str] | None = None) -> "Scene":
        """This scene with values set at dotted keys of its document (over the ones set before),
        read and checked as if its file said them (`given`: how some were given, which their errors
        name); the file is not read again."""
        return Scene(self.path, self.text, self.data, {**self.overrides, **overrides},
                     {**{k: v for k, v in self.given.items() if k not in overrides}, **(given or {})})


def signals_document(trajectory: Mapping[str, Signal]) -> dict[str, dict[str, Any]]:
    """The [trajectory.<dof>] tables of these signals, as a scene file writes them: a scene with
    another reference is `scene.changed({"trajectory": signals_document(...)})`."""
    return {dof: signal.document() for dof, signal in trajectory.items()}
