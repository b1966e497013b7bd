"""A system of co-simulation FMUs, as SSP describes one: components (an FMU each, with parameter
values), connections from outputs to inputs, power bonds, and the default experiment.

A `SystemStructure` is plain data: `cosim.engine.ssp` reads and writes it as an SSP archive, the
platform application compiles a scene into one, and `instantiate` makes the live FMU instances
that an `Execution` steps.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping


from .fmi import FmuInstance

Value = float | int | bool | str | Path  # a Path: a String parameter naming a file


@dataclass(frozen=True)
class Connection:
    source: tuple[str, str]  # (component, output variable)
    target: tuple[str, str]  # (component, input variable)

    def __str__(self) -> str:
        return f"{self.source[0]}.{self.source[1]} -> {self.target[0]}.{self.target[1]}"


@dataclass(frozen=True)
class Bond:
    """A power bond: an effort (torque, force) and a flow (speed, velocity) connection whose product
    is the power one side gives the other (ECCO, Sadjina et al. 2017). slope: where the effort's
    side also sends d effort / d flow (its interface Jacobian) to the flow's side, which then feels
    effort + slope (flow - the flow the effort's side was given); the energy it receives is reckoned
    so."""
    effort: Connection
    flow: Connection
    slope: Connection | None = None


@dataclass
class Component:
    name: str
    fmu: Path
    parameters: dict[str, Value] = field(default_factory=dict)


@dataclass
class Experiment:
    start: float = 0.0
    stop: float = 1.0
    step: float = 1e-3
    # where the step came from, when read from a file: this project's annotation, the OSP one, or
    # neither (the default above); a run that did not take it from our annotation says so
    step_source: str = field(default="", compare=False)


@dataclass
class SystemStructure:
    name: str
    components: list[Component]
    connections: list[Connection]
    bonds: list[Bond] = field(default_factory=list)
    experiment: Experiment = field(default_factory=Experiment)
    # how to run it (the algorithm and step control, see cosim.engine.settings): stored in an SSP
    # annotation, read back by `python -m cosim run FILE.ssp`
    settings: dict[str, Value] = field(default_factory=dict)
    # where an archive's files were unpacked (a tempfile.TemporaryDirectory): held while the system
    # lives, removed when it goes
    unpacked: object = field(default=None, compare=False, repr=False)

    def component(self, name: str) -> Component:
        for c in self.components:
            if c.name == name:
                return c
        raise KeyError(f"no component '{name}' in system '{self.name}'")

    def instantiate(self, logging_on: bool = False) -> dict[str, FmuInstance]:
        """Instantiates and initializes every component with its parameter values (FMUs of the
        same file share the process's one extraction); on failure, the instances made so far are freed."""
        instances: dict[str, FmuInstance] = {}
        try:
            for c in self.components:
                instance = FmuInstance(c.fmu, c.name, logging_on=logging_on)
                instances[c.name] = instance
                instance.initialize(c.parameters, start_time=self.experiment.start)
        except BaseException:
            for instance in instances.values():
                instance.free()
            raise
        return instances


def with_parameters(structure: SystemStructure, values: Mapping[str, Mapping[str, Value]]) -> SystemStructure:
    """A copy of `structure` with parameter values changed per component."""
    components = [Component(c.name, c.fmu, {**c.parameters, **values.get(c.name, {})}) for c in structure.components]
    return SystemStructure(structure.name, components, list(structure.connections), list(structure.bonds),
                           Experiment(**vars(structure.experiment)), dict(structure.settings), structure.unpacked)
