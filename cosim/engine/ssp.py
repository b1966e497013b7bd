"""SSP 1.0 in and out (Modelica Association, System Structure and Parameterization).

An archive (.ssp, a zip) holds SystemStructure.ssd (the system: components with their connectors
and units, connections, the default experiment), the FMUs under resources/, and one parameter set
per component as SSV (resources/<component>.ssv, bound to it by a ParameterBinding). What SSP has
no element for, the power bonds and how we run the system (coupling algorithm, extrapolation
order, step control, macro step, recorded outputs), travels in an annotation of the default
experiment (type ANNOTATION); other tools ignore it and run the system with their own algorithm.
A folder with SystemStructure.ssd (an unpacked archive) reads the same way.
A parameter whose value is a file (a `pathlib.Path`, such as a trajectory table) is copied into the
archive as resources/<component>/<file name> and its value written as that relative path; reading
resolves it to the unpacked file again. Tools that run the archive unpacked, from its folder, find
it there too.
"""

from __future__ import annotations

import errno
import math
import tempfile
import zipfile
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Collection, Iterator, Sequence

from fmpy import read_model_description
from lxml import etree

from .archive import unpack
from .carry import carrying
from .errors import SspError
from .fmi import loaded
from .files import replacing
from .structure import Bond, Component, Connection, Experiment, SystemStructure, Value
from .settings import recorded

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
COSIM = "https://github.com/stewart-cosim/ssp-annotation/1.0"
ANNOTATION = "io.github.stewart-cosim.run"
PARAMETER_SET = "parameters"
OSP_ANNOTATION, OSP = "com.opensimulationplatform", "http://opensimulationplatform.com/SSP/OSPAnnotations"
OMS_ANNOTATION, OMS = "org.openmodelica", "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd"
NS = {"ssd": SSD, "ssc": SSC, "ssv": SSV, "cosim": COSIM, "osp": OSP, "oms": OMS}
_SCHEMAS = Path(read_model_description.__code__.co_filename).parent / "ssp" / "schema"


ToolStepped = tuple[str, float, bool]  # a tool, the step measured for it, whether it holds the tolerances there



def not_portable(settings: dict) -> list[str]:
    """What of these run settings other SSP tools do not do (they run their own algorithm)."""
    notes = ["our step control and coupling: OMSimulator runs its fixed-step master (oms-ma) at the step of its "
             "system annotation, ordering outputs by the FMUs' declared dependencies, and stops at the first "
             "fmi2Warning unless the export set fmi.warnings_as_ok; libcosim runs its fixed-step algorithm at the OSP "
             "annotation's base step; Ecos and fmpy.ssp at the step they are given"]
    order = int(settings.get("order", 1))
    if order > 0:
        notes.append(f"input extrapolation of order {order} through fmi2SetRealInputDerivatives (other tools hold "
                     f"inputs over a step: order 0, unless an FMU extrapolates them itself, fmi.extrapolate_inputs)")
    if settings.get("algorithm", "gauss-seidel") == "gauss-seidel":
        notes.append("Gauss-Seidel stepping in the order " + str(settings.get("sequence", "of the components")) +
                     " (libcosim, Ecos and fmpy.ssp step every component from the same time: Jacobi)")
    control = settings.get("step_control", "fixed")
    if float(settings.get("startup_time", 0.0)) > 0.0:
        windows = settings.get("windows", "").replace(":", " to ").split()
        during = f" and from {', '.join(' '.join(windows[k:k + 3]) for k in range(0, len(windows), 3))} s" if windows else ""
        notes.append(f"a finer macro step ({settings.get('startup_step')} s) over the first "
                     f"{settings['startup_time']} s{during}")
    if control == "doubling":
        notes.append("step doubling with rollback through FMU state")
    elif control == "energy":
        notes.append("our energy step control (libcosim's ECCO, from an OSP export, is the nearest)")
    if int(settings.get("initial_sweeps", 20)) > 0:
        notes.append("the consistency sweeps at the start (other tools start from the inputs' start values in the "
                     "parameter sets, fmpy.ssp from 0 over its first step)")
    return notes


def _q(ns: str, tag: str) -> str:
    return f"{{{ns}}}{tag}"


def validate(root: etree._Element, schema: str, where: str) -> None:
    """Validates against the SSP 1.0 schema (as fmpy ships it); raises SspError with the line."""
    xsd = etree.XMLSchema(file=str(_SCHEMAS / schema))
    if not xsd.validate(root):
        error = xsd.error_log[0]
        raise SspError(f"{where}:{error.line}: not valid SSP ({schema}): {error.message}")


def _ssv_value(parent: etree._Element, value: Value, kind: str) -> None:
    element = etree.SubElement(parent, _q(SSV, kind))
    if kind == "Boolean":
        element.set("value", "true" if value else "false")
    elif kind == "Real":
        element.set("value", repr(float(value)))
    else:
        element.set("value", str(int(value)) if kind == "Integer" else str(value))


def file_resource(component: str, path: Path) -> str:
    return f"resources/{component}/{path.name}"


def _parameter_set(component: Component, kinds: dict[str, str]) -> etree._Element:
    # one name for every component's set: tools that apply parameter sets by name (Ecos) take them all
    root = etree.Element(_q(SSV, "ParameterSet"), nsmap={"ssv": SSV}, version="1.0", name=PARAMETER_SET)
    parameters = etree.SubElement(root, _q(SSV, "Parameters"))
    for name, value in component.parameters.items():
        if name not in kinds:
            raise SspError(f"component '{component.name}': {component.fmu.name} has no variable '{name}'")
        parameter = etree.SubElement(parameters, _q(SSV, "Parameter"), name=name)
        if isinstance(value, Path):
            value = file_resource(component.name, value)
        _ssv_value(parameter, value, "Integer" if kinds[name] == "Enumeration" else kinds[name])
    return root


def _decimal(value: float) -> str:
    """A number as xs:decimal writes it (no exponent), exact to 15 significant digits."""
    text = f"{value:.{max(0, 15 - math.floor(math.log10(abs(value))) - 1) if value else 1}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def to_xml(structure: SystemStructure, sources: dict[str, str], tool_steps: Sequence[ToolStepped] = (),
           carried: Collection[str] = ()) -> tuple[etree._Element, dict[str, etree._Element]]:
    """The SSD tree and the SSV tree of each component; `sources` maps components to their FMU's
    path inside the archive; `tool_steps`: (tool, step, within its tolerances) measured for other
    tools (cosim.engine.tools), written where each takes its step (the system's own step where a
    tool has none); `carried`: the components whose FMU carries their values (its String values
    stay out of the SSV, which OMSimulator cannot read: ssv:String)."""
    # the tools' namespaces are declared here: libcosim reads an element's attributes, a namespace
    # declaration among them, as its children
    root = etree.Element(_q(SSD, "SystemStructureDescription"), nsmap={"ssd": SSD, "ssc": SSC, "osp": OSP, "oms": OMS},
                         version="1.0", name=structure.name)
    system = etree.SubElement(root, _q(SSD, "System"), name=structure.name)
    elements = etree.SubElement(system, _q(SSD, "Elements"))
    units: dict[str, dict] = {}
    parameter_sets = {}
    connected = {c.source for c in structure.connections} | {c.target for c in structure.connections}
    shown = set((recorded(structure.settings) or ([], []))[0])  # the recorded outputs: a tool shows them too
    for component in structure.components:
        description = loaded(component.fmu)[0]  # an FMI 3.0 FMU's types by their FMI 2.0 (SSP 1.0) names
        variables = {v.name: v for v in description.modelVariables}
        for unit in description.unitDefinitions:
            base = unit.baseUnit
            exponents = {k: getattr(base, k) for k in ("kg", "m", "s", "A", "K", "mol", "cd", "rad")} if base else {}
            if base and base.factor not in (None, 1, 1.0):
                exponents["factor"] = base.factor
            if base and base.offset not in (None, 0, 0.0):
                exponents["offset"] = base.offset
            units.setdefault(unit.name, {k: v for k, v in exponents.items() if v})
        element = etree.SubElement(elements, _q(SSD, "Component"), name=component.name,
                                   type="application/x-fmu-sharedlibrary", source=sources[component.name])
        connectors = etree.SubElement(element, _q(SSD, "Connectors"))
        for name, variable in variables.items():  # the connected inputs and outputs, and the recorded outputs
            if (component.name, name) not in connected and not (
                    (component.name, name) in shown and variable.causality == "output"):
                continue
            connector = etree.SubElement(connectors, _q(SSD, "Connector"), name=name, kind=variable.causality)
            kind = etree.SubElement(connector, _q(SSC, "Integer" if variable.type == "Enumeration" else variable.type))
            if variable.type == "Real" and (variable.unit or (variable.declaredType and variable.declaredType.unit)):
                kind.set("unit", variable.unit or variable.declaredType.unit)
        kinds = {n: v.type for n, v in variables.items()}
        bound = Component(component.name, component.fmu, {
            n: v for n, v in component.parameters.items() if not (component.name in carried and kinds.get(n) == "String")})
        if bound.parameters:
            bindings = etree.SubElement(element, _q(SSD, "ParameterBindings"))
            etree.SubElement(bindings, _q(SSD, "ParameterBinding"), source=f"resources/{component.name}.ssv")
            parameter_sets[component.name] = _parameter_set(bound, kinds)
    connections = etree.SubElement(system, _q(SSD, "Connections"))
    for c in structure.connections:
        etree.SubElement(connections, _q(SSD, "Connection"), startElement=c.source[0], startConnector=c.source[1],
                         endElement=c.target[0], endConnector=c.target[1])
    used = {u.get("unit") for u in root.iter(_q(SSC, "Real")) if u.get("unit")}
    if used:
        unit_list = etree.SubElement(root, _q(SSD, "Units"))
        for name in sorted(used):
            unit = etree.SubElement(unit_list, _q(SSC, "Unit"), name=name)
            etree.SubElement(unit, _q(SSC, "BaseUnit"), **{k: repr(v) if isinstance(v, float) else str(v)
                                                           for k, v in units.get(name, {}).items()})
    experiment = etree.SubElement(root, _q(SSD, "DefaultExperiment"), startTime=repr(structure.experiment.start),
                                  stopTime=repr(structure.experiment.stop))
    annotations = etree.SubElement(experiment, _q(SSD, "Annotations"))
    annotation = etree.SubElement(annotations, _q(SSC, "Annotation"), type=ANNOTATION)
    run = etree.SubElement(annotation, _q(COSIM, "Run"), nsmap={"cosim": COSIM}, step=repr(structure.experiment.step))
    for name, value in structure.settings.items():
        etree.SubElement(run, _q(COSIM, "Setting"), name=name, value=str(value))
    for bond in structure.bonds:
        etree.SubElement(run, _q(COSIM, "PowerBond"), effort=str(bond.effort), flow=str(bond.flow),
                         **({"slope": str(bond.slope)} if bond.slope else {}))
    set_tool_steps(root, tool_steps, structure.experiment.step)
    return root, parameter_sets


def _child(parent: etree._Element, tag: str, before: Sequence[str] = (), **attributes) -> etree._Element:
    """parent's first `tag` child (with these attributes), made where missing: before the first
    child whose tag is one of `before` (the schema's order), else last."""
    for child in parent.iterchildren(tag):
        if all(child.get(k) == v for k, v in attributes.items()):
            return child
    element = etree.Element(tag, **attributes)
    following = next((c for c in parent.iterchildren() if c.tag in before), None)
    if following is None:
        parent.append(element)
    else:
        following.addprevious(element)
    return element


def set_tool_steps(root: etree._Element, tool_steps: Sequence[ToolStepped], default_step: float) -> None:
    """Writes the step measured for each other tool where that tool takes it: OMSimulator's in the
    system's annotation (oms:FixedStepMaster stepSize: OMSimulator takes a system's type, a weakly
    coupled system run by its fixed-step master, from nothing else; its schema types the numbers as
    xs:decimal), libcosim's in the
    default experiment's OSP annotation (baseStepSize), each tool's in our annotation as
    cosim:ToolStep (replacing any there); `default_step` where a tool has none measured. The
    annotations are found or made (a DefaultExperiment too, where the SSD has none)."""
    steps = {tool: step for tool, step, _ in tool_steps}
    system = root.find("ssd:System", NS)
    annotations = _child(system, _q(SSD, "Annotations"))
    oms = _child(_child(annotations, _q(SSC, "Annotation"), type=OMS_ANNOTATION), _q(OMS, "Annotations"))
    master = _child(_child(oms, _q(OMS, "SimulationInformation")), _q(OMS, "FixedStepMaster"))
    master.attrib.update({"description": "oms-ma", "stepSize": _decimal(steps.get("OMSimulator", default_step)),
                          "absoluteTolerance": master.get("absoluteTolerance", "0.0001"),
                          "relativeTolerance": master.get("relativeTolerance", "0.0001")})
    experiment = root.find("ssd:DefaultExperiment", NS)
    if experiment is None:
        experiment = _child(root, _q(SSD, "DefaultExperiment"), before=(_q(SSD, "Annotations"),), startTime="0.0")
    annotations = _child(experiment, _q(SSD, "Annotations"))
    algorithm = _child(_child(annotations, _q(SSC, "Annotation"), type=OSP_ANNOTATION), _q(OSP, "Algorithm"))
    _child(algorithm, _q(OSP, "FixedStepAlgorithm")).set("baseStepSize", repr(steps.get("libcosim", default_step)))
    annotation = _child(annotations, _q(SSC, "Annotation"), type=ANNOTATION)
    run = annotation.find(_q(COSIM, "Run"))
    if run is None:
        run = etree.SubElement(annotation, _q(COSIM, "Run"), nsmap={"cosim": COSIM}, step=repr(default_step))
    for old in run.findall(_q(COSIM, "ToolStep")):
        run.remove(old)
    for tool, step, within in tool_steps:  # the step measured for each other tool (cosim.engine.tools)
        etree.SubElement(run, _q(COSIM, "ToolStep"), tool=tool, step=repr(step), within=str(bool(within)).lower())


def write_tool_steps(path: Path, tool_steps: Sequence[ToolStepped], default_step: float) -> Path:
    """Writes the steps measured for other tools into the existing archive at `path`
    (set_tool_steps), every other entry kept as it was; the SSD validated first."""
    path = Path(path)
    with zipfile.ZipFile(path) as archive:
        root = etree.fromstring(archive.read("SystemStructure.ssd"))
        set_tool_steps(root, tool_steps, default_step)
        validate(root, "SystemStructureDescription.xsd", "SystemStructure.ssd")
        with replacing(path, "the SSP archive", path.stat().st_size + (1 << 20)) as temporary, \
                zipfile.ZipFile(temporary, "w", zipfile.ZIP_DEFLATED) as out:
            for item in archive.infolist():
                data = archive.read(item)
                if item.filename == "SystemStructure.ssd":
                    data = etree.tostring(root, pretty_print=True, xml_declaration=True, encoding="UTF-8")
                out.writestr(item, data)
    return path


@dataclass(frozen=True)
class StronglyCoupled:
    """A system of Model Exchange FMUs integrated as one by a variable-step solver: how OMSimulator's
    strongly coupled master (oms-sc, CVODE) takes it, its output every `output_step`."""
    relative_tolerance: float
    maximum_step: float
    output_step: float
    name: str = "model_exchange"


def strongly_coupled(root: etree._Element, coupled: StronglyCoupled) -> None:
    """The SSD's system made OMSimulator's strongly coupled system: its components and connections
    moved into a system of their own (`coupled.name`) whose annotation names CVODE and its
    tolerance, inside the top system that OMSimulator's fixed-step master runs at the output step
    (its stepSize, set by set_tool_steps)."""
    top = root.find("ssd:System", NS)
    inner = etree.Element(_q(SSD, "System"), name=coupled.name)
    for tag in ("Elements", "Connections"):
        part = top.find(f"ssd:{tag}", NS)
        if part is not None:
            inner.append(part)
    annotation = etree.SubElement(etree.SubElement(inner, _q(SSD, "Annotations")), _q(SSC, "Annotation"),
                                  type=OMS_ANNOTATION)
    information = etree.SubElement(etree.SubElement(annotation, _q(OMS, "Annotations")), _q(OMS, "SimulationInformation"))
    etree.SubElement(information, _q(OMS, "VariableStepSolver"), description="cvode",
                     relativeTolerance=_decimal(coupled.relative_tolerance), minimumStepSize="1e-12",
                     maximumStepSize=_decimal(coupled.maximum_step), initialStepSize="1e-06")
    elements = etree.Element(_q(SSD, "Elements"))
    elements.append(inner)
    top.insert(0, elements)


def write_ssp(structure: SystemStructure, path: Path, tool_steps: Sequence[ToolStepped] = (),
              coupled: StronglyCoupled | None = None, carry: Collection[str] = ()) -> Path:
    """Writes `structure` as an SSP 1.0 archive at `path` (each FMU file once under resources/);
    the SSD and every SSV are validated against the schemas first. tool_steps: as to_xml's;
    coupled: the system as OMSimulator's strongly coupled one (its FMUs Model Exchange); carry: the
    components whose FMU carries their values too (cosim.engine.carry: an FMU of its own,
    resources/<component>.fmu), for tools that apply no parameter bindings."""
    sources, files = {}, {}
    with tempfile.TemporaryDirectory(prefix="cosim-carry-") as carried:
        for component in structure.components:
            fmu = component.fmu
            if component.name in carry:
                fmu = carrying(component.fmu, component.parameters, Path(carried) / f"{component.name}.fmu")
            inner = f"resources/{fmu.name}"
            if files.get(inner, fmu) != fmu:
                raise SspError(f"two different FMUs named {fmu.name}")
            files[inner], sources[component.name] = fmu, inner
        return _write_archive(structure, Path(path), tool_steps, coupled, sources, files, carry)


def _write_archive(structure: SystemStructure, path: Path, tool_steps: Sequence[ToolStepped],
                   coupled: StronglyCoupled | None, sources: dict[str, str], files: dict[str, Path],
                   carry: Collection[str]) -> Path:
    root, parameter_sets = to_xml(structure, sources, tool_steps, carry)
    if coupled is not None:
        strongly_coupled(root, coupled)
        set_tool_steps(root, [("OMSimulator", coupled.output_step, True)], coupled.output_step)
    validate(root, "SystemStructureDescription.xsd", "SystemStructure.ssd")
    for name, tree in parameter_sets.items():
        validate(tree, "SystemStructureParameterValues.xsd", f"resources/{name}.ssv")
    needed = sum(Path(f).stat().st_size for f in files.values()) + (1 << 20)  # the FMUs stored, the XML besides
    with replacing(path, "the SSP archive", needed) as temporary, \
            zipfile.ZipFile(temporary, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("SystemStructure.ssd", etree.tostring(root, pretty_print=True, xml_declaration=True,
                                                                encoding="UTF-8"))
        for name, tree in parameter_sets.items():
            archive.writestr(f"resources/{name}.ssv", etree.tostring(tree, pretty_print=True, xml_declaration=True,
                                                                      encoding="UTF-8"))
        for inner, fmu in files.items():
            archive.write(fmu, inner)
        for component in structure.components:
            for value in component.parameters.values():
                if isinstance(value, Path) and component.name not in carry:  # (a carrying FMU holds its files)
                    archive.write(value, file_resource(component.name, value))
    return path


def _typed(element: etree._Element, where: str) -> Value:
    kind, text = etree.QName(element).localname, element.get("value")
    try:
        if kind == "Real":
            return float(text)
        if kind in ("Integer", "Enumeration"):
            return int(text)
        if kind == "Boolean":
            if text not in ("true", "false", "1", "0"):
                raise ValueError(f"'{text}' is not true or false")
            return text in ("true", "1")
        if kind == "String":
            return text or ""
    except (TypeError, ValueError) as error:
        raise SspError(f"{where}:{element.sourceline}: {kind} value {text!r}: {error}") from None
    raise SspError(f"{where}:{element.sourceline}: parameter type {kind} is not supported")


def _parse(path: Path, where: str) -> etree._Element:
    try:
        return etree.parse(str(path)).getroot()
    except (OSError, etree.XMLSyntaxError) as error:
        raise SspError(f"{where}: {error}") from None


def _connection(text: str, where: str) -> Connection:
    try:
        source, target = (side.strip() for side in text.split("->"))
        s_component, s_variable = source.split(".", 1)
        t_component, t_variable = target.split(".", 1)
    except ValueError:
        raise SspError(f"{where}: power bond connection '{text}' is not 'a.out -> b.in'") from None
    return Connection((s_component, s_variable), (t_component, t_variable))


def _float(element: etree._Element, attribute: str, default: float, where: str, positive: bool = False) -> float:
    """A number attribute, finite (and positive if asked), or one line naming it."""
    text = element.get(attribute)
    try:
        value = default if text is None else float(text)
    except ValueError:
        value = float("nan")
    if not math.isfinite(value) or (positive and value <= 0):
        raise SspError(f"{where}:{element.sourceline}: {attribute} = {text!r} must be a {'positive ' if positive else ''}"
                       "finite number")
    return value


def _check_record(settings: dict, found: dict[str, dict], run: etree._Element, where: str) -> None:
    """The annotation's record setting names variables of the system's components."""
    from .settings import SettingsError
    element = run.find("cosim:Setting[@name='record']", NS)
    line = element.sourceline if element is not None else run.sourceline
    try:
        chosen = recorded(settings)
    except SettingsError as error:
        raise SspError(f"{where}:{line}: {error}") from None
    for component, variable in (chosen[0] if chosen else []):
        if component not in found:
            raise SspError(f"{where}:{line}: record names component '{component}', which the system does not "
                           f"have{_near(component, found)}")
        if variable not in found[component]:
            raise SspError(f"{where}:{line}: record names '{component}.{variable}', which its FMU does not "
                           f"have{_near(variable, found[component])}")


# an SSD connector's kind -> the FMU causalities it may stand for
CONNECTOR_CAUSALITIES = {"input": {"input"}, "output": {"output"}, "parameter": {"parameter"},
                         "calculatedParameter": {"calculatedParameter"}, "inout": {"input", "output"}}


def _near(name: str, names) -> str:
    import difflib
    near = difflib.get_close_matches(name, list(names), 1)
    return f" (did you mean '{near[0]}'?)" if near else ""


def _check_against_fmus(system: etree._Element, connection_elements: list, folder: Path, where: str) -> dict[str, dict]:
    """SSP's rules and the FMUs' modelDescriptions, before anything is instantiated: each
    declared connector is a variable of its component's FMU with a matching causality; each
    connection joins a declared output connector to a declared input connector of components the
    system has, and each input takes at most one connection."""
    from .checks import variables
    declared: dict[str, dict[str, etree._Element]] = {}
    found: dict[str, dict] = {}
    for element in system.findall("ssd:Elements/ssd:Component", NS):
        name, source = element.get("name"), element.get("source")
        try:
            found[name] = variables(folder / source)
        except OSError as error:
            if error.errno in (errno.ENOSPC, errno.EDQUOT):
                raise SspError(f"{where}:{element.sourceline}: component '{name}': the disk is full: no space left "
                               f"in {tempfile.gettempdir()} to read {source}") from None
            raise SspError(f"{where}:{element.sourceline}: component '{name}': {source} is not an FMU that can be "
                           f"read ({type(error).__name__}: {str(error).splitlines()[0] if str(error) else ''})") from None
        except Exception as error:  # not an FMU, or no modelDescription it can read
            raise SspError(f"{where}:{element.sourceline}: component '{name}': {source} is not an FMU that can be "
                           f"read ({type(error).__name__}: {str(error).splitlines()[0] if str(error) else ''})") from None
        declared[name] = {}
        for connector in element.findall("ssd:Connectors/ssd:Connector", NS):
            variable, kind = connector.get("name"), connector.get("kind")
            if variable not in found[name]:
                raise SspError(f"{where}:{connector.sourceline}: connector '{variable}' of component '{name}': "
                               f"{Path(source).name} has no such variable{_near(variable, found[name])}")
            causality = found[name][variable].causality
            if causality not in CONNECTOR_CAUSALITIES.get(kind, {kind}):
                raise SspError(f"{where}:{connector.sourceline}: connector '{variable}' of component '{name}' is "
                               f"declared {kind}, but {Path(source).name} has it as {causality}")
            declared[name][variable] = connector
    fed: dict[tuple[str, str], int] = {}
    for c in connection_elements:
        for end, component, connector, wanted in (("start", c.get("startElement"), c.get("startConnector"), "output"),
                                                  ("end", c.get("endElement"), c.get("endConnector"), "input")):
            if component not in declared:
                raise SspError(f"{where}:{c.sourceline}: connection {end}s at component '{component}', which the "
                               f"system does not have{_near(str(component), declared)}")
            if connector not in declared[component]:
                hint = (_near(connector, declared[component]) or
                        (f" ({found[component][connector].causality} of its FMU, but not declared as a connector)"
                         if connector in found[component] else ""))
                raise SspError(f"{where}:{c.sourceline}: connection {end}s at '{component}.{connector}', which is no "
                               f"connector of '{component}'{hint}")
            kind = declared[component][connector].get("kind")
            if wanted not in CONNECTOR_CAUSALITIES.get(kind, {kind}):
                raise SspError(f"{where}:{c.sourceline}: connection {end}s at '{component}.{connector}', an {kind} "
                               f"connector: a connection runs from an output to an input")
        target = (c.get("endElement"), c.get("endConnector"))
        if target in fed:
            raise SspError(f"{where}:{c.sourceline}: input '{target[0]}.{target[1]}' takes a second connection "
                           f"(the first at line {fed[target]}): an input takes one")
        fed[target] = c.sourceline
    return found


@contextmanager
def opened(path: str | Path) -> Iterator[SystemStructure]:
    """The system of an SSP archive or SSD, or of one Co-Simulation FMU (cosim.engine.single), for
    the length of the block: an archive's unpacked copy is removed when the block ends, however it
    ends."""
    if Path(path).suffix.lower() == ".fmu":
        from .single import fmu_system
        yield fmu_system(path)
        return
    structure = read_ssp(path)
    try:
        yield structure
    finally:
        if structure.unpacked is not None:
            structure.unpacked.cleanup()


def read_ssp(path: str | Path, extract_to: Path | None = None) -> SystemStructure:
    """The system of an SSP archive (.ssp) or of an SSD file in an unpacked one. An archive is
    unpacked within its limits (cosim.engine.archive) to `extract_to`, or to a temporary folder that the
    returned system holds and that is removed with it (or at exit), and at once when the archive is
    refused. Raises SspError naming the file and line of what is wrong."""
    path = Path(path)
    if path.is_dir():
        path = path / "SystemStructure.ssd"
    if not path.is_file():
        raise SspError(f"{path}: no such file")
    if path.suffix.lower() != ".ssp":
        return _read_ssd(path, str(path), path.parent)
    unpacked = None if extract_to else tempfile.TemporaryDirectory(prefix="cosim-ssp-")
    folder = Path(extract_to or unpacked.name)
    try:
        unpack(path, folder)
        if not (folder / "SystemStructure.ssd").is_file():
            raise SspError(f"{path}: the archive holds no SystemStructure.ssd")
        structure = _read_ssd(folder / "SystemStructure.ssd", f"{path}!SystemStructure.ssd", folder)
    except BaseException:  # a refusal, a bug or Ctrl-C: nothing unpacked stays behind
        if unpacked is not None:
            unpacked.cleanup()
        raise
    structure.unpacked = unpacked  # the unpacked files live as long as the system (and go when it goes)
    return structure


def _read_ssd(ssd: Path, where: str, folder: Path) -> SystemStructure:
    """The system of an SSD whose components' files are found relative to `folder`."""
    root = _parse(ssd, where)
    validate(root, "SystemStructureDescription.xsd", where)
    system = root.find("ssd:System", NS)
    if system.find("ssd:Elements/ssd:System", NS) is not None:
        raise SspError(f"{where}: nested systems are not supported (an export of Model Exchange FMUs as OMSimulator's "
                       "strongly coupled system runs here from its scene: cosim run SCENE --me)")
    components = []
    for element in system.findall("ssd:Elements/ssd:Component", NS):
        source = folder / element.get("source")
        if not source.exists():
            raise SspError(f"{where}:{element.sourceline}: component '{element.get('name')}': "
                           f"{element.get('source')} is not in the archive")
        parameters: dict[str, Value] = {}
        for binding in element.findall("ssd:ParameterBindings/ssd:ParameterBinding", NS):
            prefix = binding.get("prefix", "")
            if binding.get("source"):
                ssv_where = f"{where.rsplit('SystemStructure.ssd', 1)[0]}{binding.get('source')}"
                ssv_root = _parse(folder / binding.get("source"), ssv_where)
                validate(ssv_root, "SystemStructureParameterValues.xsd", ssv_where)
                sets = [ssv_root]
            else:
                ssv_where = where
                sets = binding.findall("ssd:ParameterValues/ssv:ParameterSet", NS)
            for parameter_set in sets:
                for parameter in parameter_set.findall("ssv:Parameters/ssv:Parameter", NS):
                    name = parameter.get("name")
                    if prefix and name.startswith(prefix):
                        name = name[len(prefix):]
                    value = _typed(parameter[0], ssv_where)
                    if isinstance(value, str) and value.startswith("resources/") and (folder / value).is_file():
                        value = folder / value  # a file that travelled with the archive
                    parameters[name] = value
        components.append(Component(element.get("name"), source, parameters))
    connection_elements = system.findall("ssd:Connections/ssd:Connection", NS)
    connections = [Connection((c.get("startElement"), c.get("startConnector")), (c.get("endElement"), c.get("endConnector")))
                   for c in connection_elements]
    found = _check_against_fmus(system, connection_elements, folder, where)
    experiment, settings, bonds = Experiment(), {}, []
    experiment.step_source = "no step in the SSD (neither this project's annotation nor the OSP one): the default"
    default = root.find("ssd:DefaultExperiment", NS)
    if default is not None:
        osp = default.find(f"ssd:Annotations/ssc:Annotation[@type='{OSP_ANNOTATION}']//osp:FixedStepAlgorithm", NS)
        if osp is not None:  # libcosim's base step (its own SSPs carry no other)
            experiment.step = _float(osp, "baseStepSize", experiment.step, where, positive=True)
            experiment.step_source = f"the OSP annotation's FixedStepAlgorithm baseStepSize (line {osp.sourceline})"
        experiment.start = _float(default, "startTime", 0.0, where)
        experiment.stop = _float(default, "stopTime", 1.0, where)
        run = default.find(f"ssd:Annotations/ssc:Annotation[@type='{ANNOTATION}']/cosim:Run", NS)
        if run is not None:
            experiment.step = _float(run, "step", experiment.step, where, positive=True)
            experiment.step_source = "this project's annotation"
            settings = {s.get("name"): s.get("value") for s in run.findall("cosim:Setting", NS)}
            for b in run.findall("cosim:PowerBond", NS):
                effort, flow = (_connection(b.get(k, ""), f"{where}:{b.sourceline}") for k in ("effort", "flow"))
                slope = _connection(b.get("slope"), f"{where}:{b.sourceline}") if b.get("slope") else None
                if any(c is not None and c not in connections for c in (effort, flow, slope)):
                    raise SspError(f"{where}:{b.sourceline}: power bond of connections that the system lacks")
                bonds.append(Bond(effort, flow, slope))
            _check_record(settings, found, run, where)
    names = [c.name for c in components]
    for c in connections:
        for component, _ in (c.source, c.target):
            if component not in names:
                raise SspError(f"{where}: connection {c} names no component '{component}'")
    return SystemStructure(root.get("name") or system.get("name"), components, connections, bonds, experiment,
                           settings)
