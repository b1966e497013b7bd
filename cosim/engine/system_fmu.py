"""A whole system as ONE FMI 2.0 Co-Simulation FMU, coupled inside by the engine's step kernel.

The FMU's binary is the step kernel with an FMI 2.0 layer that nests the system's FMUs
(cosim/engine/kernel/system_fmu.c); `write_system_fmu` adds what it runs: the nested FMUs unzipped
under resources/fmus/, the files the components' values name under resources/files/, and
resources/system.txt, the system as this engine resolves it for `cosim run` (the coupling's
indices read from the kernel's own setup, the fixed-step plan with its finer start and edges,
each component's values). Inside each communication step the FMU takes the plan's steps, so the
importer's step changes the answer no more than stepping finer does; where it is a multiple of
the plan's steps, the FMU's outputs are `cosim run`'s bit for bit.

Its variables: the recorded outputs (by the results' column names), every input no connection
feeds and every Real, Integer and Boolean parameter of the components ('component.variable', the
system's value as its start); each passed on to the nested instance whose it is.
"""

from __future__ import annotations

import hashlib
import shutil
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence
from urllib.parse import quote

from lxml import etree

from .artifacts import LIB_DIR, INSTALLED, BUILD_DIR, library_path
from .execution import Execution, fixed_runs
from .fmi import FmuInstance, loaded
from .run import Plan
from .settings import FixedStep, SettingsError
from .structure import SystemStructure

_KINDS = {"Real": "r", "Integer": "i", "Enumeration": "i", "Boolean": "b", "String": "s"}
_TYPES = {"r": "Real", "i": "Integer", "b": "Boolean"}


class NotExportable(SettingsError):
    """A system the one-FMU export cannot carry (a step control that chooses its steps, Model
    Exchange, an FMI 3.0 component): one line that says which and what to do."""


@dataclass(frozen=True)
class Outer:
    """A variable of the system FMU: its name, causality, variability, the instance and the
    nested variable it passes on to, the type (r, i, b) and its start (None: an output)."""
    name: str
    causality: str
    variability: str
    instance: int
    vr: int
    kind: str
    start: str | None
    description: str = ""
    derivative_of: int | None = None  # a state's derivative: the state's index among the variables


PLATFORMS = {2: ("linux64", "win64"), 3: ("x86_64-linux", "x86_64-windows")}  # each version's folders
# what an importer may set, by the outer variable's causality (system.txt): s settable (an input, a
# parameter: its nested instance says when), n never (an output, a local: the system computes it)
_SETTABLE = {"input": "s", "parameter": "s", "output": "n", "local": "n"}


def system_binaries(fmi: int = 2) -> dict[str, Path]:
    """The system FMU's binaries (FMI 2.0's cosim_system, FMI 3.0's cosim_system3) by the version's
    platform folder: Linux's always, Windows' where the cross build made it (build/win64/, or the
    wheel's lib/)."""
    name = "cosim_system" if fmi == 2 else "cosim_system3"
    linux, windows = PLATFORMS[fmi]
    found = {linux: library_path(f"{name}.so")}
    dll = (LIB_DIR if INSTALLED else BUILD_DIR / "win64") / f"{name}.dll"
    if dll.exists():
        found[windows] = dll
    return found


def _token(text: str) -> str:
    """A text as one whitespace-free token of system.txt: '=' and the text percent-encoded."""
    return "=" + quote(text, safe="@/._-+:{}")


def _number(value: float) -> str:
    return repr(float(value))


def _value_text(kind: str, value) -> str:
    if kind == "r":
        return _number(value)
    if kind == "b":
        return "1" if value else "0"
    if kind == "i":
        return str(int(value))
    return _token(str(value))


def _check(plan: Plan, model_exchange: bool) -> FixedStep:
    if plan.model_exchange:
        raise NotExportable("write_system_fmu takes the system's co-simulation plan (its FMUs as Co-Simulation); "
                            "model_exchange=True makes the FMU Model Exchange", "model_exchange")
    if model_exchange and not isinstance(plan.control, FixedStep):  # the coupling's order is all it takes
        return FixedStep(plan.output_interval or plan.structure.experiment.step)
    if not isinstance(plan.control, FixedStep):
        raise NotExportable("the system FMU steps the run's fixed-step plan inside each communication step: set "
                            "step_control = fixed (a controlled step chooses its steps as it goes)", "step_control")
    return plan.control


def write_system_fmu(plan: Plan, target: Path, model_name: str | None = None, fmi: int = 2,
                     model_exchange: bool = False, remark: str = "") -> Path:
    """`plan`'s system as one Co-Simulation FMU at `target`, FMI 2.0 or (fmi=3) FMI 3.0 over the same
    nested FMI 2.0 FMUs; Linux and, where built, Windows binaries. Its default experiment is the
    plan's (start, stop time, regular step). model_exchange: a Model Exchange FMU instead, the
    nested FMUs' continuous states its own and the connections carried inside its derivatives
    (cosim/engine/kernel/system_me.c); every FMU of the system must offer Model Exchange (ours do,
    through their twins in build/fmus_me/). `remark`: what its description adds (what a tool's user
    should know of it, shown where the tool shows an FMU's description)."""
    control = _check(plan, model_exchange)
    structure = plan.structure
    target = Path(target)
    identifier = "".join(c if c.isalnum() or c == "_" else "_" for c in target.stem) or "system"
    if identifier[0].isdigit():
        identifier = f"system_{identifier}"
    with tempfile.TemporaryDirectory() as stage_name:
        stage = Path(stage_name)
        resources = stage / "resources"
        with Execution(structure, plan.algorithm, control, plan.record, plan.names, clock=plan.clock) as execution:
            for instance in execution.instances.values():
                if instance.fmi3:
                    raise NotExportable(f"{instance.name}: an FMI 3.0 component ({instance.path.name}); the system "
                                        "FMU nests FMI 2.0 FMUs (offered as FMI 2.0 or 3.0): give it FMI 2.0 FMUs",
                                        "fmi")
            folders = _nest_fmus(structure, resources)
            states = _states(structure) if model_exchange else {}
            body, variables = _describe(plan, control, execution, folders, resources, states)
        guid = "{" + str(_uuid(body)) + "}"
        interface = "me" if model_exchange else "cs"
        (resources / "system.txt").write_text(f"cosim-system 1\nguid {guid}\ninterfaces 1 {interface}\n{body}")
        for platform, binary in system_binaries(fmi).items():
            folder = stage / "binaries" / platform
            folder.mkdir(parents=True)
            shutil.copyfile(binary, folder / f"{identifier}{binary.suffix}")
        describe = _model_description if fmi == 2 else _model_description3
        (stage / "modelDescription.xml").write_bytes(
            describe(model_name or structure.name, identifier, guid, plan, variables, model_exchange, remark))
        target.parent.mkdir(parents=True, exist_ok=True)
        partial = target.with_name(target.name + ".partial")
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
            for path in sorted(stage.rglob("*")):
                if path.is_file():
                    archive.write(path, path.relative_to(stage).as_posix())
        partial.replace(target)
    return target


def _uuid(text: str):
    import uuid
    return uuid.UUID(hashlib.md5(text.encode()).hexdigest())


def _nest_fmus(structure: SystemStructure, resources: Path) -> dict[Path, str]:
    """Each FMU file of the system unzipped once under resources/fmus/<folder>/ (its description,
    Linux and Windows binaries and resources); the folder of each."""
    folders: dict[Path, str] = {}
    for component in structure.components:
        path = Path(component.fmu).resolve()
        if path in folders:
            continue
        folder = path.stem
        while folder in folders.values():
            folder += "_"
        folders[path] = folder
        with zipfile.ZipFile(path) as archive:
            for member in archive.namelist():
                top = member.split("/")[0]
                keep = top in ("modelDescription.xml", "resources") or member.startswith(
                    tuple(f"binaries/{platform}/" for platform in PLATFORMS[2]))
                if keep and not member.endswith("/"):
                    archive.extract(member, resources / "fmus" / folder)
    return folders


def _states(structure: SystemStructure) -> dict[str, list[tuple[str, int, str, int]]]:
    """Each component's continuous states as Model Exchange, in its description's order: the
    state's name and value reference, its derivative's name and value reference; NotExportable naming a component whose FMU has no Model Exchange."""
    from .errors import UsageError
    from .monolithic import model_exchange_structure
    try:
        twins = model_exchange_structure(structure)
    except UsageError as error:
        raise NotExportable(f"{error}: the Model Exchange FMU needs every component as Model Exchange",
                            "model_exchange") from None
    return {component.name: [(d.variable.derivative.name, d.variable.derivative.valueReference, d.variable.name,
                              d.variable.valueReference) for d in loaded(component.fmu)[0].derivatives]
            for component in twins.components}


def _describe(plan: Plan, control: FixedStep, execution: Execution, folders: dict[Path, str], resources: Path,
              states: dict[str, list[tuple[str, int, str, int]]]) -> tuple[str, list[Outer]]:
    """system.txt (after its interfaces line) and the outer variables, from the live execution: the
    kernel's own setup (what `cosim run` steps) and the instances' descriptions; `states`, each
    component's continuous states where the FMU is Model Exchange."""
    structure, kernel, coupling = plan.structure, execution.kernel, execution.coupling
    names = coupling.names
    fmu_list = list(folders)
    lines = [f"start {_number(structure.experiment.start)}",
             f"algorithm {kernel.setup.gauss_seidel} {kernel.setup.order} {plan.algorithm.initial_sweeps} "
             f"{int(plan.algorithm.zero_start)}",
             f"clock {kernel.clock}"]
    runs = fixed_runs(control, structure.experiment.start, plan.stop_time)
    lines.append(f"plan {len(runs)} " + " ".join(f"{_number(h)} {n}" for h, n in runs))
    lines.append(f"step {_number(control.step)}")
    lines.append(f"fmus {len(fmu_list)}")
    for path in fmu_list:
        description = loaded(path)[0]
        lines.append(f"{folders[path]} {description.coSimulation.modelIdentifier} {_token(description.guid)}")
    lines.append(f"instances {len(names)}")
    by_name = {c.name: c for c in structure.components}
    for k, name in enumerate(names):
        c, instance = kernel._instances[k], execution.instances[name]
        component = by_name[name]
        lines.append(f"instance {_token(name)} {fmu_list.index(Path(component.fmu).resolve())}")
        lines.append(f" outputs {c.n_outputs} " + " ".join(str(c.output_vrs[i]) for i in range(c.n_outputs)))
        lines.append(f" inputs {c.n_inputs} " + " ".join(
            f"{c.input_vrs[i]} {c.feed_source[i]} {c.feed_index[i]}" for i in range(c.n_inputs)))
        lines.append(f" flags {c.rate_order} {c.interpolating} {c.extrapolating}")
        lines.append(f" states {len(states.get(name, ()))}")
        values = []
        for variable, value in component.parameters.items():
            kind = _KINDS.get(instance.variables[variable].type) if variable in instance.variables else None
            if kind is None:
                raise NotExportable(f"{name}: '{variable}' is no variable the system FMU can set", "parameters")
            if isinstance(value, Path):
                files = resources / "files" / name
                files.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(value, files / value.name)
                value = f"@resources/files/{name}/{value.name}"
            values.append(f"  {kind} {instance.vr(variable)} {_value_text(kind, value)}")
        lines.append(f" values {len(values)}")
        lines += values
    lines.append(f"sequence {len(names)} " + " ".join(str(int(v)) for v in kernel.sequence))
    lines.append(f"stages {len(names)} " + " ".join(str(int(v)) for v in kernel.stage_end))
    bonds = [kernel.bonds[b] for b in range(kernel.n_bonds)]
    lines.append(f"bonds {len(bonds)} " + " ".join(
        f"{p.instance} {p.index}" for b in bonds for p in (b.effort_out, b.effort_in, b.flow_out, b.flow_in, b.slope_in)))
    feeds = [kernel.feeds[f] for f in range(len(kernel.feedthrough_plan))]
    lines.append(f"feeds {len(feeds)} " + " ".join(f"{f.instance} {f.first} {f.n_inputs} {f.n_outputs}" for f in feeds))
    lines.append(f"feed_indices {len(kernel.feed_indices)} " + " ".join(str(int(v)) for v in kernel.feed_indices))
    variables = _outer_variables(plan, execution, kernel.index, states)  # by the kernel's own instance indices
    lines.append(f"variables {len(variables)}")
    lines += [f"{v.instance} {v.kind} {v.vr} {_SETTABLE[v.causality]}" for v in variables]
    lines.append("end")
    return "\n".join(lines) + "\n", variables


def _outer_variables(plan: Plan, execution: Execution, index: dict[str, int],
                     states: dict[str, list[tuple[str, int, str, int]]]) -> list[Outer]:
    """The recorded outputs, then per component its inputs that no connection feeds and its
    parameters (not the FMI layer's own fmi.* switches), with the system's values as starts; then
    (Model Exchange) each component's continuous states and their derivatives."""
    structure = plan.structure
    names = list(plan.names) if plan.names is not None else [f"{c}.{v}" for c, v in plan.record]
    variables = [Outer(n, "output", "continuous", index[c], execution.instances[c].vr(v), "r", None)
                 for n, (c, v) in zip(names, plan.record)]
    connected = {c.target for c in structure.connections}
    for component in structure.components:
        instance: FmuInstance = execution.instances[component.name]
        for v in instance.model_description.modelVariables:
            kind = _KINDS.get(v.type)
            if kind not in _TYPES or v.name.startswith("fmi."):
                continue
            if v.causality == "input" and (component.name, v.name) not in connected and kind == "r":
                causality, variability = "input", "continuous"
            elif v.causality == "parameter":
                causality, variability = "parameter", v.variability or "fixed"
            else:
                continue
            start = component.parameters.get(v.name, v.start)
            if start is None or isinstance(start, Path):
                continue
            text = _number(start) if kind == "r" else ("true" if str(start).lower() in ("true", "1") else "false") \
                if kind == "b" else str(int(start))
            variables.append(Outer(f"{component.name}.{v.name}", causality, variability, index[component.name],
                                   v.valueReference, kind, text, v.description or ""))
    for name, parts in states.items():
        for state, state_vr, derivative, derivative_vr in parts:
            variables.append(Outer(f"{name}.{state}", "local", "continuous", index[name], state_vr, "r", None,
                                   f"{name}'s continuous state {state}"))
        first = len(variables) - len(parts)
        for k, (state, state_vr, derivative, derivative_vr) in enumerate(parts):
            variables.append(Outer(f"der({name}.{state})", "local", "continuous", index[name], derivative_vr, "r",
                                   None, f"the time derivative of {name}.{state}", derivative_of=first + k))
    return variables


def _description(model_name: str, model_exchange: bool, remark: str) -> str:
    how = ("as one ODE, the connections carried inside its derivatives" if model_exchange
           else "coupled inside by the cosim engine")
    return f"{model_name}: the whole system as one FMU, {how}" + (f"; {remark}" if remark else "")


def _model_description(model_name: str, identifier: str, guid: str, plan: Plan, variables: Sequence[Outer],
                       model_exchange: bool = False, remark: str = "") -> bytes:
    root = etree.Element("fmiModelDescription", fmiVersion="2.0", modelName=model_name, guid=guid,
                         description=_description(model_name, model_exchange, remark),
                         generationTool="cosim (stewart platform co-simulation)",
                         variableNamingConvention="flat", numberOfEventIndicators="0")
    if model_exchange:
        etree.SubElement(root, "ModelExchange", modelIdentifier=identifier, completedIntegratorStepNotNeeded="false",
                         canBeInstantiatedOnlyOncePerProcess="false", canNotUseMemoryManagementFunctions="true",
                         canGetAndSetFMUstate="false", canSerializeFMUstate="false")
    else:
        etree.SubElement(root, "CoSimulation", modelIdentifier=identifier,
                         canHandleVariableCommunicationStepSize="true", canBeInstantiatedOnlyOncePerProcess="false",
                         canNotUseMemoryManagementFunctions="true", canGetAndSetFMUstate="false",
                         canSerializeFMUstate="false")
    categories = etree.SubElement(root, "LogCategories")
    for name in ("logStatusWarning", "logStatusError", "logAll"):
        etree.SubElement(categories, "Category", name=name)
    start = plan.structure.experiment.start
    etree.SubElement(root, "DefaultExperiment", startTime=repr(start), stopTime=repr(float(plan.stop_time)),
                     stepSize=repr(_output_step(plan, model_exchange)),
                     **({"tolerance": repr(ME_TOLERANCE)} if model_exchange else {}))
    model_variables = etree.SubElement(root, "ModelVariables")
    for vr, v in enumerate(variables):
        attributes = dict(name=v.name, valueReference=str(vr), causality=v.causality, variability=v.variability)
        if v.description:
            attributes["description"] = v.description
        if v.causality == "parameter":
            attributes["initial"] = "exact"
        element = etree.SubElement(model_variables, "ScalarVariable", **attributes)
        typed = etree.SubElement(element, _TYPES[v.kind])
        if v.start is not None:
            typed.set("start", v.start)
        if v.derivative_of is not None:
            typed.set("derivative", str(v.derivative_of + 1))
    structure = etree.SubElement(root, "ModelStructure")
    outputs = etree.SubElement(structure, "Outputs")
    for vr, v in enumerate(variables):
        if v.causality == "output":
            etree.SubElement(outputs, "Unknown", index=str(vr + 1))
    if model_exchange:
        derivatives = etree.SubElement(structure, "Derivatives")
        for vr, v in enumerate(variables):
            if v.derivative_of is not None:
                etree.SubElement(derivatives, "Unknown", index=str(vr + 1))
    unknowns = etree.SubElement(structure, "InitialUnknowns")
    for vr, v in enumerate(variables):  # outputs, states and derivatives: all calculated (FMI 2.0, 2.2.8)
        if v.causality == "output" or (v.causality == "local" and model_exchange):
            etree.SubElement(unknowns, "Unknown", index=str(vr + 1))
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)


_TYPES3 = {"r": "Float64", "i": "Int32", "b": "Boolean"}
ME_TOLERANCE = 1e-6  # the Model Exchange FMU's default experiment's relative tolerance (docs/guide/system-fmu.md)


def _output_step(plan: Plan, model_exchange: bool) -> float:
    """The default experiment's step: the Co-Simulation's communication step (the plan's step), or
    where the importer's solver steps itself, the plan's output interval."""
    if model_exchange:
        return plan.output_interval or plan.structure.experiment.step
    return plan.control.step


def _model_description3(model_name: str, identifier: str, guid: str, plan: Plan, variables: Sequence[Outer],
                        model_exchange: bool = False, remark: str = "") -> bytes:
    """FMI 3.0's description of the same variables (the same value references), and the independent
    variable `time` after them."""
    root = etree.Element("fmiModelDescription", fmiVersion="3.0", modelName=model_name, instantiationToken=guid,
                         description=_description(model_name, model_exchange, remark),
                         generationTool="cosim (stewart platform co-simulation)", variableNamingConvention="flat")
    if model_exchange:
        etree.SubElement(root, "ModelExchange", modelIdentifier=identifier, canGetAndSetFMUState="false",
                         canSerializeFMUState="false", needsCompletedIntegratorStep="true")
    else:
        etree.SubElement(root, "CoSimulation", modelIdentifier=identifier,
                         canHandleVariableCommunicationStepSize="true", canGetAndSetFMUState="false",
                         canSerializeFMUState="false", hasEventMode="false", providesIntermediateUpdate="false",
                         canReturnEarlyAfterIntermediateUpdate="false")
    categories = etree.SubElement(root, "LogCategories")
    for name in ("logStatusWarning", "logStatusError", "logAll"):
        etree.SubElement(categories, "Category", name=name)
    etree.SubElement(root, "DefaultExperiment", startTime=repr(plan.structure.experiment.start),
                     stopTime=repr(float(plan.stop_time)), stepSize=repr(_output_step(plan, model_exchange)),
                     **({"tolerance": repr(ME_TOLERANCE)} if model_exchange else {}))
    model_variables = etree.SubElement(root, "ModelVariables")
    etree.SubElement(model_variables, "Float64", name="time", valueReference=str(len(variables)),
                     causality="independent", variability="continuous", description="the simulation time")
    for vr, v in enumerate(variables):
        attributes = dict(name=v.name, valueReference=str(vr), causality=v.causality, variability=v.variability)
        if v.description:
            attributes["description"] = v.description
        if v.start is not None:
            attributes["start"] = v.start
        if v.derivative_of is not None:
            attributes["derivative"] = str(v.derivative_of)  # the state's value reference
        etree.SubElement(model_variables, _TYPES3[v.kind], **attributes)
    structure = etree.SubElement(root, "ModelStructure")
    for vr, v in enumerate(variables):
        if v.causality == "output":
            etree.SubElement(structure, "Output", valueReference=str(vr))
    for vr, v in enumerate(variables):
        if v.derivative_of is not None:
            etree.SubElement(structure, "ContinuousStateDerivative", valueReference=str(vr))
    for vr, v in enumerate(variables):  # outputs, states and derivatives: all calculated
        if v.causality == "output" or (v.causality == "local" and model_exchange):
            etree.SubElement(structure, "InitialUnknown", valueReference=str(vr))
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)
