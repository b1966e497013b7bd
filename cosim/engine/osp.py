"""The Open Simulation Platform's configuration (OspSystemStructure.xml, the form libcosim users
expect): simulators with their initial values, variable connections with the power bonds named
(each bond is its flow and its effort connection under one `powerBond` name), the base step, the
algorithm (`ecco` when the system's step control is energy control, `fixedStep` otherwise) and an
ECCO configuration: the system's energy control (cosim.engine.settings.EnergyControl, the law our
kernel runs, whose docstring says where libcosim's differs), or for a fixed-step system, which
libcosim then runs at its fixed step, that law at rtol 1e-4 and h_min 1e-5.
The FMUs are copied beside the XML.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from lxml import etree

from .files import replacing, write_bytes
from .settings import EnergyControl, system_settings
from .fmi import loaded
from .structure import SystemStructure

OSP = "http://opensimulationplatform.com/MSMI/OSPSystemStructure"


def _element(parent, tag: str, text: str | None = None, **attributes) -> etree._Element:
    element = etree.SubElement(parent, f"{{{OSP}}}{tag}", **attributes)
    if text is not None:
        element.text = text
    return element


def to_osp_xml(structure: SystemStructure, power_bonds: bool = True, step: float | None = None) -> etree._Element:
    _, control = system_settings(structure.settings, structure.experiment.step)
    ecco = control if isinstance(control, EnergyControl) else EnergyControl(structure.experiment.step, rtol=1e-4,
                                                                            atol=1e-4, h_min=1e-5)
    root = etree.Element(f"{{{OSP}}}OspSystemStructure", nsmap={None: OSP}, version="0.1")
    _element(root, "StartTime", repr(structure.experiment.start))
    _element(root, "BaseStepSize", repr(step or structure.experiment.step))
    _element(root, "Algorithm", "ecco" if isinstance(control, EnergyControl) else "fixedStep")
    simulators = _element(root, "Simulators")
    for component in structure.components:
        simulator = _element(simulators, "Simulator", name=component.name, source=component.fmu.name)
        if component.parameters:
            kinds = {v.name: v.type for v in loaded(component.fmu)[0].modelVariables}
            values = _element(simulator, "InitialValues")
            for name, value in component.parameters.items():
                kind = "Integer" if kinds[name] == "Enumeration" else kinds[name]
                text = ("true" if value else "false") if kind == "Boolean" else \
                    repr(float(value)) if kind == "Real" else str(int(value)) if kind == "Integer" else str(value)
                _element(_element(values, "InitialValue", variable=name), kind, value=text)
    connections = _element(root, "Connections")
    bond_of = {}
    for k, bond in enumerate(structure.bonds if power_bonds else [], start=1):
        bond_of[bond.flow] = bond_of[bond.effort] = f"bond{k}"
    for c in structure.connections:
        attributes = {"powerBond": bond_of[c]} if c in bond_of else {}
        connection = _element(connections, "VariableConnection", **attributes)
        # libcosim's convention for a bond's connections (its quarter-truck examples): the source
        # variable marked "input", the target "output"
        _element(connection, "Variable", simulator=c.source[0], name=c.source[1],
                 **({"causality": "input"} if attributes else {}))
        _element(connection, "Variable", simulator=c.target[0], name=c.target[1],
                 **({"causality": "output"} if attributes else {}))
    configuration = _element(root, "EccoConfiguration")
    for tag, value in (("SafetyFactor", ecco.safety), ("StepSize", ecco.step), ("MinimumStepSize", ecco.h_min),
                       ("MaximumStepSize", ecco.h_max), ("MinimumChangeRate", ecco.change_min),
                       ("MaximumChangeRate", ecco.change_max), ("ProportionalGain", ecco.k_p),
                       ("IntegralGain", ecco.k_i), ("RelativeTolerance", ecco.rtol), ("AbsoluteTolerance", ecco.atol)):
        _element(configuration, tag, repr(float(value)))
    return root


def write_osp(structure: SystemStructure, folder: Path, power_bonds: bool = True, step: float | None = None) -> Path:
    """Writes folder/OspSystemStructure.xml and the FMUs beside it; returns the XML's path.
    power_bonds=False leaves the bonds out (a fixed-step run does not use them; libcosimpy 0.0.6
    refuses a file with more than one bond, a bug of its configuration parser fixed upstream).
    step: libcosim's base step (default the system's)."""
    folder = Path(folder)
    for fmu in dict.fromkeys(c.fmu for c in structure.components):
        with replacing(folder / fmu.name, "an FMU of the OSP configuration", fmu.stat().st_size) as temporary:
            shutil.copyfile(fmu, temporary)
    return write_bytes(folder / "OspSystemStructure.xml", etree.tostring(
        to_osp_xml(structure, power_bonds, step), pretty_print=True, xml_declaration=True, encoding="UTF-8"),
        "the OSP configuration")
