"""The Python API: load a scene or an SSP system, run it, export it, sweep it, ask for advice.

The same run path as the `cosim` command, for a notebook or a script:

    import cosim
    run = cosim.simulate("meng_eq35", duration=2.0)            # a shipped scene, by name
    run["pose.z"], run["torque[1]"]                             # named result columns (numpy)
    print(run.report.text())                                   # what the command prints
    cosim.export_ssp("meng_eq35", "meng.ssp")                   # the whole system as SSP 1.0
    ssp = cosim.simulate("meng.ssp", settings={"step": "5e-4"})  # any SSP system

A scene is a TOML file (a shipped scene's name, or a path; `cosim copy NAME` copies one out to
edit), or a `Scene` from `load`, changed before it runs with `scene.changed({"scene.step": 5e-4})`
(values at the keys its file writes, checked as the file's own).
Mistakes in the input raise one-line errors (`SceneError`, `SspError`, `SettingsError`,
`SweepError`); a run that stops part way raises `RunStopped`, which carries the results computed
up to then (`.result`) and the report that says why (`.report`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .engine.errors import UsageError
from .engine.outcome import Report, RunStopped
from .engine.structure import SystemStructure
from .platform.scene import Scene, SceneError, load_scene

SYSTEM_SUFFIXES = (".ssp", ".ssd", ".fmu")  # a system: an SSP, or one Co-Simulation FMU

__all__ = ["Run", "Advice", "load", "simulate", "export_ssp", "export_fmu", "sweep", "advise", "RunStopped", "SceneError",
           "Scene"]


@dataclass
class Run:
    """A finished run.

    Attributes:
        values: the recorded results, a numpy structured array in fmpy's convention: a `time`
            column [s], then one column per recorded variable (`pose.z` [m], `pose_ref.roll`
            [rad], `torque[3]` [N m] for leg 3, ...; units as the FMUs declare them).
        report: what the run measured: macro steps, wall time, real-time factor, energy
            residual of the power bonds, tracking error (a scene's), the FMUs' warnings.
    """
    values: np.ndarray
    report: Report

    def __getitem__(self, name: str) -> np.ndarray:
        """One result column by name, e.g. `run["pose.z"]`."""
        return self.values[name]

    @property
    def names(self) -> list[str]:
        """The result columns' names, `time` first."""
        return list(self.values.dtype.names)


@dataclass
class Advice:
    """What `advise` found: every candidate it tried, the cheapest that keeps the tolerances
    (None if none does) and the text `cosim advise` prints."""
    candidates: list
    recommended: Any
    text: str


def load(model: str | Path, overrides: Mapping[str, Any] | None = None) -> Scene | SystemStructure:
    """A scene (a shipped scene's name or a .toml path) or an SSP system (.ssp, .ssd), read and
    checked.

    Args:
        model: `"meng_eq35"`, `"my_scene.toml"`, `"system.ssp"`.
        overrides: a scene's values at dotted keys, as its file writes them, e.g.
            `{"scene.step": 5e-4, 'mechanics.parameters."platform.mass"': 800.0}`.

    Raises:
        SceneError, SspError: one line naming the file, line, key and reason.
    """
    if Path(str(model)).suffix.lower() in SYSTEM_SUFFIXES:
        if overrides:
            raise UsageError("load: overrides are a scene's keys; an SSP system's run settings and parameter values "
                             "go to simulate(..., settings=...) or its components' parameters")
        if Path(str(model)).suffix.lower() == ".fmu":
            from .engine.single import fmu_system
            return fmu_system(Path(model))
        from .engine.ssp import read_ssp
        return read_ssp(Path(model))
    return load_scene(model, dict(overrides or {}))


def simulate(model: str | Path | Scene | SystemStructure, *, duration: float | None = None,
             overrides: Mapping[str, Any] | None = None, settings: Mapping[str, str] | None = None,
             out: str | Path | None = None, plots: bool = False, progress: bool = False, advice: bool = False,
             twin: bool = False, real_time: float | None = None, stream: str | None = None, listen: str | None = None,
             listen_key: str | Path | bytes | None = None, model_exchange: bool = False) -> Run:
    """Runs a scene or an SSP system and returns its named results.

    Args:
        model: a scene's name or path, a `Scene` (from `load`), an .ssp/.ssd path, a
            Co-Simulation .fmu (run alone: its outputs recorded) or a `SystemStructure`.
        duration: the simulated time [s], instead of the scene's or system's own.
        overrides: a scene's values at dotted keys (see `load`); with a `Scene`, over the ones
            it was made with (`Scene.changed`; its file is not read again).
        settings: an SSP system's run settings by name (`step`, `algorithm`, `order`,
            `step_control`, `rtol`, ...: cosim.engine.settings), as `cosim run --set`.
        out: a folder for the results as files (CSV, .mat, the log; a scene's plots and
            interactive report with `plots`).
        plots: draw a scene's figures and its HTML report into `out`.
        progress: a progress bar on a terminal.
        advice: a fixed-step run that diverges probes shorter steps on the same system, and its
            failure names the one that held (the command line asks for it).
        twin: judge a scene's run against its converged twin (the scene at a 16th of its step
            throughout), window by window (start-up, each load pulse, steady tracking).
        real_time: pace the run at this factor of the wall clock (1.0: real time); its lateness
            and overruns are in `.report.pacing` (docs/guide/realtime.md).
        stream: send the run's samples live to udp://HOST:PORT[?every=N] (`cosim.realtime.receive`).
        listen: take a scene's pose reference live from udp://HOST:PORT (`cosim.realtime.send`),
            held within the platform's motion envelope; an address other than the loopback
            (127.0.0.0/8, ::1) needs `listen_key`.
        listen_key: the shared key (bytes, or a file holding it) every live datagram is tagged
            with (HMAC-SHA256; docs/guide/realtime.md).
        model_exchange: a scene's FMUs as Model Exchange, integrated as one system by one solver
            (CVODE): no coupling (cosim.engine.monolithic; not with real_time, stream or listen).

    Raises:
        SceneError, SspError, SettingsError: the input cannot run (one line).
        UsageError: an argument that does not apply to the model (one line).
        RunStopped: the run stopped part way (an FMU failed, or the coupling diverged);
            `.result` holds the results up to then, `.report` says why.
    """
    target = Path(out) if out is not None else None
    if plots and target is None:
        raise UsageError("simulate: plots are drawn into a folder: give out as well")
    if isinstance(model, SystemStructure) or (not isinstance(model, Scene)
                                              and Path(str(model)).suffix.lower() in SYSTEM_SUFFIXES):
        given = [name for name, value in (("overrides", overrides), ("twin", twin),
                                          ("listen", listen), ("listen_key", listen_key),
                                          ("model_exchange", model_exchange)) if value]
        if given:
            raise UsageError(f"simulate: {given[0]} applies to a scene, not to an SSP system (its run settings go in "
                             "settings)")
        from contextlib import nullcontext
        from .engine.realtime import RealTime
        from .engine.run import run_system
        from .engine.ssp import opened
        source = None if isinstance(model, SystemStructure) else str(model)
        paced = RealTime(real_time, stream) if real_time is not None or stream else None
        with nullcontext(model) if isinstance(model, SystemStructure) else opened(Path(model)) as structure:
            values, report = run_system(structure, dict(settings or {}), duration, target, source=source,
                                        progress=progress, advice=advice, real_time=paced, plots=plots)
        return Run(values, report)
    if settings:
        raise UsageError("simulate: settings are an SSP system's run settings; a scene's are keys of its file, given "
                         "as overrides (e.g. {'scene.step': 5e-4, 'coupling.order': 2})")
    from .platform.run.runner import run_scene
    scene = model.changed(overrides or {}) if isinstance(model, Scene) else load_scene(model, overrides)
    if duration is not None:
        scene = scene.changed({"scene.duration": float(duration)})
    adapt = _scene_plan(model_exchange, real_time, stream, listen, listen_key)
    values, report = run_scene(scene, target, plots=plots, progress=progress, advice=advice, twin=twin,
                               adapt=adapt)
    return Run(values, report)


def _scene_plan(model_exchange: bool, real_time: float | None, stream: str | None, listen: str | None,
                listen_key: str | Path | bytes | None):
    """How a scene's compiled plan is made over for the run asked for (run_scene's adapt): as
    Model Exchange under one solver, or in real time; None: as compiled."""
    if listen_key is not None and not listen:
        raise UsageError("simulate: listen_key goes with listen")
    if isinstance(listen_key, (str, Path)):
        from .engine.realtime import read_key
        listen_key = read_key(listen_key, "listen_key")
    if model_exchange:
        if real_time is not None or stream or listen:
            raise UsageError("simulate: model_exchange integrates the system by one solver, as fast as it goes: not "
                             "with real_time, stream or listen")
        from .platform.run.compile import model_exchange_plan
        return model_exchange_plan
    if real_time is not None or stream or listen:
        from functools import partial

        from .platform.realtime import real_time_plan
        return partial(real_time_plan, factor=real_time, stream=stream, listen=listen, key=listen_key)
    return None


def export_ssp(scene: str | Path | Scene, path: str | Path, *, measure: bool = True) -> Path:
    """Writes a scene as an SSP 1.0 archive: its FMUs, parameter values (SSV), connections, our run
    settings in an annotation that other tools ignore, and for each other tool (OMSimulator,
    libcosim, Ecos, fmpy.ssp) the step its master holds the scene's tolerances at, measured in our
    engine (measure=False: the scene's own step, as `cosim export --scene-step`). Returns the
    archive's path."""
    from .platform.run.portable import export_scene
    loaded = scene if isinstance(scene, Scene) else load_scene(scene)
    return export_scene(loaded, ssp=Path(path), measure=measure).files[0]


def export_fmu(scene: str | Path | Scene, path: str | Path, *, fmi: int = 2, model_exchange: bool = False) -> Path:
    """Writes a scene as ONE Co-Simulation FMU (FMI 2.0, or 3.0 with fmi=3; Linux and Windows
    binaries): its FMUs nested and coupled inside as `simulate` couples them, its values and files
    inside, so that any tool that imports an FMU runs the scene (`cosim export SCENE --fmu`; at a
    communication step that is a multiple of the scene's step its outputs are `simulate`'s bit for
    bit); with model_exchange=True as ONE Model Exchange FMU instead (`--fmu FILE --me`: the
    connections carried inside its derivatives, for the importer's solver). Returns the FMU's path."""
    from .platform.run.portable import export_fmu as write
    loaded = scene if isinstance(scene, Scene) else load_scene(scene)
    return write(loaded, Path(path), fmi=fmi, model_exchange=model_exchange).files[0]


def sweep(file: str | Path, *, workers: int | None = None, scheduler: str | None = None,
          out: str | Path = "out", progress: bool = False):
    """Runs a sweep file (a shipped one's name, or a path) on Dask and returns its outcome:
    `.rows` (one dict per point: its values, the reports asked for, status and message) and
    `.files` (the Parquet and CSV tables written to `out`).

    Args:
        workers: worker processes of a local cluster (None: one per core; 0: in this process).
        scheduler: the address of a running Dask scheduler instead ("tcp://host:8786"); the
            workers need only this package installed: the files a sweep reads travel to them.

    Raises:
        SweepError: a bad sweep file (one line naming the file and line).
    """
    from .platform.run.sweep import load_sweep
    if workers is not None and scheduler is not None:
        raise UsageError("sweep: workers start a local cluster, scheduler names a running one: give one of them")
    _whole("sweep", "workers", workers)
    return load_sweep(file).run(Path(out), workers, scheduler, progress)


def advise(scene: str | Path | Scene, tolerance: float, *, effort_tolerance: float = 0.01, probe: float | None = None,
           workers: int | None = None) -> Advice:
    """The cheapest effects, drive fidelity and macro step that keep a scene within `tolerance`
    (largest pose error [m, rad]) and `effort_tolerance` (drive torque or force, a fraction of its
    peak and of its own change in each window: the start-up, each load pulse with the 0.2 s after
    it, steady tracking) against a converged reference, as `cosim advise` finds them; probes of
    `probe` seconds (default 2, and past the first load pulse)."""
    from .platform.advise import advise as find, recommend, text
    for name, number in (("tolerance", tolerance), ("effort_tolerance", effort_tolerance), ("probe", probe)):
        if number is not None and not (isinstance(number, (int, float)) and math.isfinite(number) and number > 0):
            raise UsageError(f"advise: {name} = {number!r} must be a positive number")
    _whole("advise", "workers", workers)
    loaded = scene if isinstance(scene, Scene) else load_scene(scene)
    candidates, info = find(loaded, tolerance, probe, effort_tolerance, workers)
    return Advice(candidates, recommend(candidates, tolerance, effort_tolerance),
                  text(loaded, tolerance, candidates, info))


def _whole(function: str, name: str, count: int | None) -> None:
    """A number of worker processes: None (one per core), 0 (in this process) or more."""
    if count is not None and (isinstance(count, bool) or not isinstance(count, int) or count < 0):
        raise UsageError(f"{function}: {name} = {count!r} must be a whole number >= 0 (0: in this process)")
