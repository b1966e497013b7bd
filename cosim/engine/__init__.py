"""A generic FMI 2.0 co-simulation engine: any system of co-simulation FMUs, described as SSP.

It knows FMU instances (fmi), system structures (structure, ssp), the coupling algorithms and step
controllers (settings; implemented once, in the C step kernel: kernel), one way to run a system
(run: a Plan through `run`, over the run loop of execution, which is its own), what a run gives
back (outcome) and observers (observers). It knows nothing of any particular system.
"""

from .artifacts import ArtifactMissing, fmu_path
from .checks import ParameterError
from .execution import NoStep, RunFailed
from .fmi import FmuError, FmuInstance
from .observers import DivergenceMonitor, Diverged, Observer, Progress, RecordFull, Recorder
from .settings import Algorithm, EnergyControl, FixedStep, SettingsError, StepControl, StepDoubling
from .structure import Bond, Component, Connection, Experiment, SystemStructure

__all__ = ["Algorithm", "ArtifactMissing", "NoStep", "ParameterError", "Bond", "Component", "Connection", "DivergenceMonitor", "Diverged",
           "EnergyControl", "Experiment", "FixedStep", "FmuError", "FmuInstance", "Observer",
           "Progress", "RecordFull", "Recorder", "RunFailed", "SettingsError", "StepControl", "StepDoubling", "SystemStructure",
           "fmu_path"]
