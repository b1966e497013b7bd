"""Co-simulation of an electrically driven 6-DOF Stewart platform (FMI 2.0, fmpy).

The public API (cosim.api): `simulate`, `load`, `export_ssp`, `export_fmu`, `sweep`, `advise`; the command
line is `cosim` (or `python -m cosim`).
"""

__all__ = ["Advice", "Run", "RunStopped", "Scene", "SceneError", "advise", "export_fmu", "export_ssp", "load", "simulate",
           "sweep"]


def __getattr__(name: str):
    """The API's names, cosim.api imported on first use (PEP 562): `cosim --help` loads no engine."""
    if name in __all__:
        from . import api
        return getattr(api, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
