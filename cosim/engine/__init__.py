"""A generic FMI 2.0 co-simulation engine: any system of co-simulation FMUs, described as SSP.

It knows FMU instances (fmi), system structures (structure, ssp), the coupling algorithms and step
controllers (settings; implemented once, in the C step kernel: kernel), one way to run a system
(run: a Plan through `run`, over the run loop of execution, which is its own), what a run gives
back (outcome) and observers (observers). It knows nothing of any particular system.
"""

import importlib

# each public name and the module that defines it, imported on first use (PEP 562): a command that
# needs the engine's errors or file locations does not load fmpy, lxml and the kernel with them
_WHERE = {"ArtifactMissing": "artifacts", "fmu_path": "artifacts", "ParameterError": "checks", "NoStep": "execution",
          "RunFailed": "execution", "FmuError": "fmi", "FmuInstance": "fmi", "DivergenceMonitor": "observers",
          "Diverged": "observers", "Observer": "observers", "Progress": "observers", "RecordFull": "observers",
          "Recorder": "observers", "Algorithm": "settings", "EnergyControl": "settings", "FixedStep": "settings",
          "SettingsError": "settings", "StepControl": "settings", "StepDoubling": "settings", "Bond": "structure",
          "Component": "structure", "Connection": "structure", "Experiment": "structure",
          "SystemStructure": "structure"}
__all__ = sorted(_WHERE)


def __getattr__(name: str):
    if name in _WHERE:
        return getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
