"""The step an exported scene hands each other tool (cosim.platform.run.portable, `cosim export`):
per shipped scene, each tool's master (cosim.engine.tools) run in our engine on the exported system
(every FMU extrapolating the inputs its master holds, every connected input starting consistent) at
the scene's step and each half of it down to a 64th, over the scene's probe, against its converged
run; the largest step within the shipped scenes' tolerances, or the closest. Written as block
`export` of docs/benchmarks.md, quoted by docs/guide/engine.md.

With --fmu, the one-FMU export instead (`cosim export SCENE --fmu`, cosim.engine.system_fmu): per
shipped scene and importer step, fmpy's simulate_fmu running the FMU over the scene's probe, judged
against the scene's converged run (the pose error, the efforts' worst window against its
tolerance), and its wall time beside `cosim run`'s of the same probe (each the best of three, in
one run). Block `export_fmu`, quoted by docs/guide/system-fmu.md.

    python benchmarks/export.py [--fmu] [--write]
"""

from __future__ import annotations

import sys
import time
import uuid
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import publish  # noqa: E402
from cosim.engine.artifacts import ROOT  # noqa: E402
from cosim.engine.tools import TOOL_MASTERS  # noqa: E402
from cosim.platform.run.portable import FLOOR, steps_text, tool_steps  # noqa: E402
from cosim.platform.scene import load_scene  # noqa: E402

SCENES = sorted(p.stem for p in (ROOT / "scenes").glob("*.toml"))
DETAILED = "meng_eq35"  # the scene whose table is shown whole, as the export prints it


IMPORTER_STEPS = (5e-4, 1e-3, 2e-3, 5e-3, 1e-2)


def best_wall(run, repeats: int = 3) -> tuple[float, object]:
    """The shortest of `repeats` wall times of run() and its last result."""
    walls, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = run()
        walls.append(time.perf_counter() - start)
    return min(walls), result


def container_fmu(scene, step: float, folder: Path) -> Path:
    """FMPy's container FMU (fmpy.container_fmu) of the scene's FMUs as its system wires them, each
    carrying its component's values (cosim.engine.carry), its fixed internal step `step`: the way a
    user builds one block from eight FMUs with the field's tool. Its outputs are the scene's
    recorded columns, by their names."""
    from fmpy import read_model_description
    from fmpy.container_fmu import Configuration
    from fmpy.container_fmu.cli import create_container_fmu
    from fmpy.container_fmu.config import Component, Connection
    from fmpy.model_description import CoSimulation, DefaultExperiment, ModelDescription, ModelVariable, Unknown
    from cosim.engine.carry import carrying
    from cosim.platform.run.compile import compile_scene
    plan = compile_scene(scene).plan
    components, by_name, described = [], {}, {}
    for c in plan.structure.components:
        copy = carrying(Path(c.fmu), {k: v for k, v in c.parameters.items()}, folder / f"{c.name}.fmu")
        described[c.name] = read_model_description(str(copy))
        by_name[c.name] = Component(name=c.name, filename=copy, modelDescription=described[c.name])
        components.append(by_name[c.name])

    def variable(component: str, name: str):  # by FMI 3.0's type name, as the container's configuration takes it
        import attrs
        found = next(v for v in described[component].modelVariables if v.name == name)
        return attrs.evolve(found, type="Float64") if found.type == "Real" else found

    connections = [Connection(startElement=by_name[c.source[0]], startConnectors=[variable(*c.source)],
                              endElement=by_name[c.target[0]], endConnectors=[variable(*c.target)])
                   for c in plan.structure.connections]
    names = list(plan.names) if plan.names is not None else [f"{c}.{v}" for c, v in plan.record]
    outputs = [ModelVariable(type="Float64", variability="continuous", name=n, causality="output", valueReference=k)
               for k, n in enumerate(names)]
    time_variable = ModelVariable(type="Float64", variability="continuous", name="time", causality="independent",
                                  valueReference=len(names))
    description = ModelDescription(fmiVersion="3.0", modelName=f"{scene.path.stem}_container",
                                   instantiationToken="{" + str(uuid.uuid4()) + "}",
                                   coSimulation=CoSimulation(modelIdentifier="container_fmu",
                                                             fixedInternalStepSize=step),
                                   defaultExperiment=DefaultExperiment(stopTime=str(scene.duration), stepSize=str(step)),
                                   modelVariables=[time_variable, *outputs],
                                   outputs=[Unknown(variable=v) for v in outputs])
    mappings = {v: [(by_name[c], variable(c, name))] for v, (c, name) in zip(outputs, plan.record)}
    configuration = Configuration(parallelDoStep=False, modelDescription=description, components=components,
                                  connections=connections, variableMappings=mappings)
    target = folder / f"{scene.path.stem}_container_{step:g}.fmu"
    stage = folder / "container_stage"
    stage.mkdir(exist_ok=True)
    create_container_fmu(configuration, stage, target)
    return target


def one_fmu() -> None:
    import tempfile
    from fmpy import simulate_fmu
    from cosim.platform.run.accuracy import judge, probe_duration
    from cosim.platform.run.portable import converged, export_fmu
    from cosim.platform.run.runner import run_scene
    rows = ["| scene | importer step | the FMU: pose error [m, rad] | its efforts' worst window / tolerance | "
            "its wall in fmpy | FMPy's container: pose error | its efforts / tolerance | its wall | `cosim run` |",
            "|---|---|---|---|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory() as folder:
        for name in SCENES:
            scene = load_scene(name)
            scene = scene.changed({"scene.duration": probe_duration(scene)})
            fmu = export_fmu(scene, Path(folder) / f"{name}.fmu").files[0]
            reference = converged(scene, scene.duration)
            ours, _ = best_wall(lambda: run_scene(scene))
            for step in IMPORTER_STEPS:
                cells = []
                for built in (fmu, container_fmu(scene, step, Path(folder))):
                    try:
                        wall, result = best_wall(lambda: simulate_fmu(str(built), stop_time=scene.duration,
                                                                       step_size=step, output_interval=step))
                    except Exception as error:  # an FMU that fails in fmpy: the table says so
                        cells += ["failed", str(error).splitlines()[0][:60], "-"]
                        continue
                    verdict = judge(scene, result, reference)
                    ratio = "diverged" if not np.isfinite(verdict.ratio) else f"{verdict.ratio:.2f} ({verdict.window})"
                    cells += [f"{verdict.pose_error:.1e}", ratio, f"{wall:.2f} s (RTF {scene.duration / wall:.0f})"]
                rows.append(f"| {name} | {step * 1e3:g} ms | {' | '.join(cells)} | {ours:.2f} s (RTF "
                            f"{scene.duration / ours:.0f}) |")
                print(rows[-1], file=sys.stderr)
        whole = load_scene(DETAILED)  # the paper's scene over its whole duration: the stepping, not the set-up
        fmu = export_fmu(whole, Path(folder) / "whole.fmu").files[0]
        ours, _ = best_wall(lambda: run_scene(whole))
        set_up, _ = best_wall(lambda: simulate_fmu(str(fmu), stop_time=whole.step, step_size=whole.step))
        walls = {step: best_wall(lambda: simulate_fmu(str(fmu), stop_time=whole.duration, step_size=step,
                                                      output_interval=step))[0] for step in (1e-3, 1e-2)}
    whole_line = (f"Over {DETAILED}'s whole {whole.duration:g} s: the FMU in fmpy {walls[1e-3]:.2f} s at 1 ms (RTF "
                  f"{whole.duration / walls[1e-3]:.0f}) and {walls[1e-2]:.2f} s at 10 ms (RTF "
                  f"{whole.duration / walls[1e-2]:.0f}), `cosim run` {ours:.2f} s (RTF {whole.duration / ours:.0f}); of "
                  f"each fmpy call {set_up:.2f} s is its unpacking and instantiation (a run of one step), which the "
                  "probes above carry too. The FMU's stepping is `cosim run`'s kernel; what fmpy adds is its call "
                  "per communication point and the outputs it reads there.")
    lines = ["Per shipped scene, its one-FMU export (FMI 2.0) and FMPy's container FMU of the same FMUs (each "
             "carrying its component's values, wired as the scene; its fixed internal step the importer's, inputs "
             "held) run by fmpy's simulate_fmu at each importer step over the scene's probe, every output recorded at "
             "every communication point, judged against the scene's converged run (pose within 1e-5 and efforts' "
             "ratio at most 1: within the tolerances); walls the best of three in one run, beside `cosim run` of the "
             "same probe at the scene's own plan (the FMU's coupling: at a multiple of the scene's step its outputs "
             "bit for bit). The machine otherwise idle:", "", *rows, "", whole_line]
    publish("export_fmu", "python benchmarks/export.py --fmu", lines)


def main() -> None:
    if "--fmu" in sys.argv:
        one_fmu()
        return
    tools = [m.tool for m in TOOL_MASTERS]
    summary = [f"| scene | its step | {' | '.join(tools)} | measured in |", "|---|---|" + "---|" * len(tools) + "---|"]
    detailed = []
    for name in SCENES:
        scene = load_scene(name)
        start = time.perf_counter()
        steps = tool_steps(scene)
        took = time.perf_counter() - start
        cells = [f"{s.step * 1e3:.4g} ms ({s.judgement.ratio:.2f})" if s.within else
                 f"none; closest {s.step * 1e3:.4g} ms ({s.judgement.ratio:.2f}, pose {s.judgement.pose_error:.1e})"
                 for s in steps]
        summary.append(f"| {name} | {scene.step * 1e3:g} ms | {' | '.join(cells)} | {took:.0f} s |")
        if name == DETAILED:
            text = steps_text(scene, steps)
            detailed = [f"**{name}**, the export's own table: {text[0]}", "", *text[1:]]
    lines = [f"Per shipped scene and tool, the step written (the largest within the tolerances, halving down "
             f"to 1/{FLOOR} of the scene's) and, in brackets, the efforts' worst window against its tolerance "
             f"there (at most 1: within); 'none': no step down to 1/{FLOOR} holds, the closest is written:", "",
             *summary, "", *detailed]
    publish("export", "python benchmarks/export.py", lines)


if __name__ == "__main__":
    main()
