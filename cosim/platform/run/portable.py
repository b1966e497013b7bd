"""A scene's system as other tools get it, and the step each gets: what that tool's master does
with it (cosim.engine.tools: a fixed step, inputs held, no finer start) run in our engine on the
system the export writes, at the scene's step and at each half of it down to FLOOR, over a probe of
the scene (cosim.platform.run.accuracy.probe_duration) against the scene's converged run; the
largest step within the shipped scenes' tolerances (the pose, and the drive efforts per window), or
where none holds the step that came closest, named as such.

What the exported system carries for masters without our coupling (portable_structure): every FMU
extrapolates the inputs its master holds (fmi.extrapolate_inputs, with the reference's exact rate
wired as pose_ref_rate.*), so that a master that holds inputs couples at second order; and every
connected input starts at the value its source has at the start once the outputs are consistent
(our consistency sweeps, written as the input's start value in the parameter sets), so that a
master without such sweeps does not start the drives on a reference they are not at."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...engine.outcome import RunStopped
from ...engine.run import Plan, run
from ...engine.settings import Algorithm, FixedStep
from ...engine.structure import SystemStructure
from ...engine.tools import FLOOR, ToolMaster, ToolStep, fmi3_lines, largest_steps
from ..scene import Scene
from .accuracy import Judgement, converged_twin, judge, probe_duration
from .alone import check_workspace
from .compile import scene_record, scene_structure, scene_values

def row(measured: ToolStep) -> str:
    """A row of the export's table: the tool, its master, the step written, the verdict, the pose
    error, the efforts' worst window against its tolerance, our wall time at that step."""
    j = measured.judgement
    verdict = "within the tolerances" if measured.within else (
        f"none within the tolerances down to 1/{FLOOR} of the scene's step: the closest")
    return (f"| {measured.master.tool} | {measured.master.master} | {measured.step * 1e3:.4g} ms | {verdict} | "
            f"{j.pose_error:.2e} | {j.ratio:.2f} ({j.window}) | {measured.wall:.2f} s |")


HEADER = ["| tool | its master | step written | | pose error [m, rad] | efforts' worst window / tolerance | "
          "our wall at that step |", "|---|---|---|---|---|---|---|"]


def converged(scene: Scene, duration: float) -> np.ndarray:
    """The scene's converged run over `duration`: its converged twin's (converged_twin)."""
    from .runner import run_scene
    twin = converged_twin(scene).changed({"scene.duration": duration})
    return run_scene(twin)[0]


def start_inputs(structure: SystemStructure, step: float) -> dict[tuple[str, str], float]:
    """Every connected input's value at the start once the outputs are consistent with the inputs
    (the engine's fixed-point sweeps, before a step): (component, input) -> its source's output."""
    sources = sorted({c.source for c in structure.connections})
    result, _ = run(Plan(structure, Algorithm("jacobi", 0), FixedStep(step), step, sources, clock="mechanics",
                         divergence=None))
    first = result[0]
    return {c.target: float(first[f"{c.source[0]}.{c.source[1]}"]) for c in structure.connections}


def portable_structure(scene: Scene, fmi2_warnings: bool = False) -> tuple[SystemStructure, list[str]]:
    """The scene's system as the export writes it, and what the export says about it: every FMU
    that can extrapolates the inputs its master holds (fmi.extrapolate_inputs), every connected
    input starts consistent (start_inputs), and unless fmi2_warnings every FMU that can returns
    fmi2OK where it logs a warning (fmi.warnings_as_ok), so that a tool which stops at the first
    fmi2Warning (OMSimulator, at a leg past its stroke) runs on."""
    from ...engine.checks import check_parameters, variables
    structure = scene_structure(scene)
    check_parameters(structure)  # ParameterError before a run on values the FMUs refuse
    check_workspace(scene, scene_values(scene)[0])  # a reference no tool could run, as `cosim run` refuses it
    lines, without = [], {"fmi.extrapolate_inputs": [], "fmi.warnings_as_ok": []}
    switches = ("fmi.extrapolate_inputs", *(() if fmi2_warnings else ("fmi.warnings_as_ok",)))
    for component in structure.components:
        known = variables(component.fmu)
        for switch in switches:
            if switch in known:
                component.parameters[switch] = True
            else:
                without[switch].append(component.name)
    by_name = {c.name: c for c in structure.components}
    for (component, name), value in start_inputs(structure, scene.step).items():
        by_name[component].parameters[name] = value
    lines.append("note: every FMU extrapolates over a step the inputs its master holds (fmi.extrapolate_inputs = "
                 "true: linearly from their last two communication points, the reference with its exact rate "
                 "pose_ref_rate.*), and every connected input starts at its source's consistent value (its start "
                 "value in the parameter sets), so that a master which holds its inputs and makes no consistency "
                 "sweeps couples at second order from a consistent start"
                 + (f"; not {', '.join(without['fmi.extrapolate_inputs'])} (its FMU has no such switch)"
                    if without["fmi.extrapolate_inputs"] else ""))
    if not fmi2_warnings:
        lines.append("note: every FMU returns fmi2OK where it logs a warning (fmi.warnings_as_ok = true), so that a "
                     "tool that stops at the first fmi2Warning (OMSimulator) runs on past a leg out of its stroke; the "
                     "warnings stay in the FMUs' log (--fmi2-warnings keeps the standard's status)"
                     + (f"; not {', '.join(without['fmi.warnings_as_ok'])} (its FMU has no such switch)"
                        if without["fmi.warnings_as_ok"] else ""))
    return structure, lines


def _run(scene: Scene, master: ToolMaster, step: float, duration: float, structure=None) -> tuple[np.ndarray, float]:
    """The exported system (`structure`; portable_structure of the scene where not given) under the
    tool's master at `step` for `duration`: its results (the scene's columns; empty where it fails)
    and the stepping's wall time."""
    plan = Plan(structure or portable_structure(scene)[0], master.algorithm, FixedStep(step), duration,
                *scene_record(scene), clock="mechanics", divergence=None)
    try:
        result, report = run(plan)
    except RunStopped as stopped:
        result, report = stopped.result, stopped.report
    return result, report.wall


_MEASURED: dict[tuple, list[ToolStep]] = {}


def tool_steps(scene: Scene, progress: bool = False) -> list[ToolStep]:
    """Per tool of TOOL_MASTERS, the largest step (the scene's step over a power of two, down to
    FLOOR) at which its master holds the tolerances over a probe of the scene, or the one that came
    closest. Tools with the same master are run once; a scene measured before in this process is
    not measured again. `progress`: each run of the measurement counted as it ends (the command
    line's; cosim.engine.observers.TaskProgress)."""
    from ...engine.observers import TaskProgress
    key = (str(scene.path), scene.text, tuple(sorted((k, repr(v)) for k, v in scene.overrides.items())))
    if key in _MEASURED:
        return _MEASURED[key]
    shown = TaskProgress("export: measuring each tool's step, runs", None) if progress else None
    duration = probe_duration(scene)
    reference = converged(scene, duration)
    if shown is not None:
        shown.advance("the converged reference")
    structure = portable_structure(scene)[0]  # its drives designed once, for every master and step

    def attempt(master: ToolMaster, step: float) -> ToolStep:
        result, wall = _run(scene, master, step, duration, structure)
        if shown is not None:
            shown.advance(f"{master.tool} at {1e3 * step:g} ms")
        return ToolStep(master, step, judge(scene, result, reference), wall)

    _MEASURED[key] = largest_steps(scene.step, attempt, fmi3=scene.fmi == 3)
    if shown is not None:
        shown.finish()
    return _MEASURED[key]


def steps_text(scene: Scene, steps: list[ToolStep]) -> list[str]:
    """The export's table: per tool, its master, the step written and how it does there."""
    return [f"the step each tool gets, measured by its master in our engine over the first "
            f"{probe_duration(scene):g} s against the scene's converged run (pose within 1e-5, efforts within "
            f"their windows' tolerances):", *HEADER, *(row(s) for s in steps)]


@dataclass
class Exported:
    """What an export wrote and what it says about it, line by line."""
    files: list
    lines: list


# CVODE's relative tolerance written for OMSimulator's strongly coupled master: at 1e-8 (our own
# monolithic run's) the master of OMSimulator b3cd458 fails CVODE's error test on the Meng scene at
# 0.26 s (its coupling is carried once per accepted step, not at each evaluation); at 1e-6 it runs
SC_RELATIVE_TOLERANCE = 1e-6


def export_model_exchange(scene: Scene, ssp: Path, fmi2_warnings: bool = False) -> Exported:
    """The scene's system of Model Exchange FMUs as OMSimulator's strongly coupled system (its
    master integrates them as one by CVODE; no coupling, no step to measure), the outputs every
    scene step. UsageError for a component without a Model Exchange FMU (a user's drive)."""
    from ...engine import ParameterError
    from ...engine.monolithic import model_exchange_structure
    from ...engine.ssp import StronglyCoupled, write_ssp
    from .errors import scene_error
    try:
        structure, lines = portable_structure(scene, fmi2_warnings)
    except ParameterError as error:
        raise scene_error(scene, error) from None
    structure = model_exchange_structure(structure)
    coupled = StronglyCoupled(SC_RELATIVE_TOLERANCE, scene.step, scene.step)
    lines = [line for line in lines if "extrapolate" not in line]  # a Co-Simulation step's, not Model Exchange's
    lines.append(f"note: the system as Model Exchange FMUs in one strongly coupled system (OMSimulator's oms-sc: CVODE, "
                 f"relative tolerance {coupled.relative_tolerance:g}, steps up to {coupled.maximum_step:g} s), its "
                 f"outputs every {coupled.output_step:g} s: no coupling, no step to measure")
    archive = write_ssp(structure, ssp, coupled=coupled, carry=carried(structure, lines))
    return Exported([archive, omsimulator_lua(scene, structure, Path(ssp), lines)], lines)


def omsimulator_lua(scene: Scene, structure: SystemStructure, archive: Path, lines: list[str]) -> Path:
    """Beside the archive, OMSimulator's script that records only what the run reports, at the
    scene's output interval (cosim.engine.tools.omsimulator_script); what the export says of it added
    to `lines`."""
    from ...engine.settings import recorded
    from ...engine.tools import omsimulator_bytes_per_second, omsimulator_script
    record = recorded(structure.settings)[0]
    interval = scene.output_interval or scene.step
    script = omsimulator_script(archive, record, interval, scene.duration)
    lines.append(f"note: {script.name}: `OMSimulator {script.name}` in its folder runs the archive recording only "
                 f"the {len(record)} outputs the run reports, every {interval:g} s, into "
                 f"{archive.stem}_omsimulator.csv: about {omsimulator_bytes_per_second(record, interval) / 1e6:.2g} MB "
                 "per simulated second (OMSimulator alone records every signal at every communication point)")
    return script


def carried(structure: SystemStructure, lines: list[str]) -> list[str]:
    """The components whose FMU carries its values in the export (ours: cosim.engine.carry), so that
    a tool that applies no parameter bindings (fmpy's simulate_ssp) or reads no ssv:String
    (OMSimulator) runs the scene; what the export says of it added to `lines`."""
    from ...engine.artifacts import built_here
    ours = [c.name for c in structure.components if built_here(c.fmu)]
    others = [c.name for c in structure.components if c.name not in ours]
    lines.append("note: each of our FMUs carries its component's values as well (resources/start_values.txt, the "
                 "start values of its modelDescription.xml; a file it reads in its resources/), so that a tool that "
                 "applies no parameter bindings (fmpy's simulate_ssp) runs the scene" +
                 (f"; not {', '.join(others)} (a user's FMU: its values are in the SSV alone)" if others else ""))
    return ours


# what the one-FMU exports of a motion-cueing scene say of its guard
GUARDED = ("the cueing's reference held within the platform's envelope by the cueing FMU's own guard, as in "
           "`cosim run`")


def export_fmu(scene: Scene, target: Path, fmi: int = 2, model_exchange: bool = False) -> Exported:
    """The scene as ONE Co-Simulation FMU at `target`, FMI 2.0 or (fmi=3) FMI 3.0
    (cosim.engine.system_fmu): its FMUs nested (our FMI 2.0 ones, the models of the FMI 3.0 ones bit
    for bit), coupled inside by our kernel exactly as `cosim run` couples them, its values, drives'
    design and tables inside; what the export says about it. model_exchange: one Model Exchange FMU
    instead (the same FMUs' states as its own, the connections carried inside its derivatives).
    Raises SceneError for values the FMUs refuse."""
    from ...engine import ParameterError
    from ...engine.settings import SettingsError
    from ...engine.system_fmu import system_binaries, write_system_fmu
    from .compile import compile_scene
    from .errors import scene_error
    from .errors import SceneError
    try:
        compiled = compile_scene(scene.changed({"scene.fmi": 2}) if scene.fmi != 2 else scene)
        check_workspace(scene, compiled.mechanics)  # a reference no tool could run, as `cosim run` refuses it
        plan = compiled.plan
        path = write_system_fmu(plan, target, model_name=scene.name, fmi=fmi, model_exchange=model_exchange,
                                remark=GUARDED if scene.vehicle is not None else "")
    except ParameterError as error:
        raise scene_error(scene, error) from None
    except SettingsError as error:  # what the one FMU cannot carry (a step control that chooses its steps)
        key = f"coupling.{error.setting}" if error.setting else "coupling"
        raise SceneError(f"{scene.document.where(key)}: {error}") from None
    if model_exchange:
        return Exported([path], model_exchange_lines(scene, plan, fmi))
    steps = sorted({h for h in (plan.control.step, plan.control.startup_step if plan.control.startup_time else None)
                    if h})
    lines = [f"note: one FMI {fmi}.0 Co-Simulation FMU ({', '.join(system_binaries(fmi))} binaries) holding the scene's "
             f"{len(plan.structure.components)} FMUs, coupled inside as `cosim run` couples them ({plan.algorithm.kind}, "
             f"extrapolation order {plan.algorithm.order}, steps of {', '.join(f'{h:g}' for h in steps)} s with its finer "
             f"start and edges); at a communication step that is a multiple of {plan.control.step:g} s its outputs are "
             "`cosim run`'s bit for bit" + (f" ({GUARDED})" if scene.vehicle is not None else "") +
             ", a shorter one steps finer inside",
             f"note: its variables: the {len(plan.record)} recorded outputs as the results name them, the inputs no "
             "connection feeds and every parameter as 'component.variable', the scene's values as their starts "
             "(the drives' design and the tables inside)"]
    return Exported([path], lines)


def model_exchange_lines(scene: Scene, plan, fmi: int) -> list[str]:
    """What the one Model Exchange FMU export says of itself."""
    from ...engine.system_fmu import ME_TOLERANCE, system_binaries
    lines = [f"note: one FMI {fmi}.0 Model Exchange FMU ({', '.join(system_binaries(fmi))} binaries) holding the "
             f"scene's {len(plan.structure.components)} FMUs as one ODE: their continuous states its own, every "
             "connection carried inside each evaluation of its derivatives (no coupling delay: the importer's solver "
             "integrates the coupled platform), their time events its own",
             f"note: its default experiment: relative tolerance {ME_TOLERANCE:g} (docs/guide/system-fmu.md: what "
             "it holds against the scene's converged co-simulation), outputs every "
             f"{plan.output_interval or plan.structure.experiment.step:g} s; its variables: the recorded outputs, the "
             "unconnected inputs and parameters (as the Co-Simulation FMU's), and each component's states and their "
             "derivatives as 'component.ode.x[k]'"]
    if scene.vehicle is not None:
        lines.append(f"note: {GUARDED}, its steps time events {scene.step:g} s apart (the scene's step)")
    return lines


def export_scene(scene: Scene, ssp=None, osp=None, measure: bool = True, fmi2_warnings: bool = False,
                 progress: bool = False) -> Exported:
    """The scene's whole system for other tools: an SSP archive at `ssp` and/or an OSP
    configuration in the folder `osp`. measure: each tool's step measured (tool_steps) and written
    where it takes it; otherwise the scene's own step everywhere. Unless fmi2_warnings, every FMU
    that can returns fmi2OK where it logs a warning (fmi.warnings_as_ok), so that a tool which stops
    at the first fmi2Warning (OMSimulator, at a leg past its stroke) runs on. Raises SceneError for
    values the FMUs refuse (the scene's file and line). progress: the measuring's shown as it goes."""
    from ...engine import ParameterError
    from ...engine.osp import write_osp
    from ...engine.ssp import not_portable, write_ssp
    from .errors import scene_error
    files = []
    try:
        structure, lines = portable_structure(scene, fmi2_warnings)
    except ParameterError as error:
        raise scene_error(scene, error) from None
    if scene.fmi == 3:
        lines.append("note: the archive holds our FMUs as FMI 3.0 (no input derivatives: each extrapolates the inputs "
                     "its master holds itself, as above); our engine runs it")
        lines += fmi3_lines()
    steps = tool_steps(scene, progress) if measure else []
    if steps:
        lines += steps_text(scene, steps)
    else:
        lines.append(f"note: every tool gets the scene's own step, {scene.step:g} s, unmeasured (--scene-step)")
    if ssp is not None:
        files.append(write_ssp(structure, ssp, [(s.master.tool, s.step, s.within) for s in steps],
                               carry=carried(structure, lines)))
        files.append(omsimulator_lua(scene, structure, Path(ssp), lines))
    for note in not_portable(structure.settings):
        lines.append(f"note: other tools run this system without {note}")
    if osp is not None:
        libcosim = next((s.step for s in steps if s.master.tool == "libcosim"), None)
        files.append(write_osp(structure, osp, step=libcosim))
    return Exported(files, lines)
