"""Co-simulation of an electrically driven 6-DOF Stewart platform (FMI 2.0, fmpy).

The public API (cosim.api): `simulate`, `load`, `export_ssp`, `sweep`, `advise`; the command
line is `cosim` (or `python -m cosim`).
"""

from .api import Advice, Run, RunStopped, Scene, SceneError, advise, export_ssp, load, simulate, sweep

__all__ = ["Advice", "Run", "RunStopped", "Scene", "SceneError", "advise", "export_ssp", "load", "simulate", "sweep"]
