"""FMUs that carry their component's values (an SSP for tools that apply no parameter bindings:
fmpy's simulate_ssp reads them and sets none, OMSimulator reads no ssv:String).

A carrying copy of an FMU holds the component's parameter values in resources/start_values.txt,
one `name=value` a line, which an FMU built on this project's FMI layer takes at instantiation and
at every reset exactly as fmi2Set* would (fmu/common/fmi2_layer.c), and gives the same values as
the start values of its modelDescription.xml; a file a value names (a vehicle's motion, a table)
travels in the copy's resources/ and the value is `@resources/NAME`, which the FMU resolves against
its own resources folder. Only FMUs that read start_values.txt can carry: the caller says which."""

from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Mapping

from lxml import etree

from .errors import SspError
from .structure import Value

START_VALUES = "resources/start_values.txt"
FMI3_TYPES = ("Float64", "Float32", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64",
              "Boolean", "String", "Enumeration")


def _text(value: Value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def carrying(fmu: Path, values: Mapping[str, Value], target: Path) -> Path:
    """A copy of `fmu` at `target` that carries `values` (by variable name; a Path value's file goes
    into its resources/)."""
    carried, files = {}, {}
    for name, value in values.items():
        if isinstance(value, Path):
            files[f"resources/{value.name}"] = value
            value = f"@resources/{value.name}"
        text = _text(value)
        if "\n" in text or "\r" in text:
            raise SspError(f"{fmu.name}: '{name}' = {text!r}: a value with a line break cannot be carried")
        carried[name] = text
    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as out:
        for entry in source.infolist():
            if entry.filename in (START_VALUES, *files):
                continue
            data = source.read(entry)
            if entry.filename == "modelDescription.xml":
                data = _with_starts(data, carried, fmu.name)
            out.writestr(entry, data)
        out.writestr(START_VALUES, "".join(f"{name}={text}\n" for name, text in carried.items()))
        for inner, path in files.items():
            out.write(path, inner)
    return target


def _with_starts(description: bytes, carried: Mapping[str, str], where: str) -> bytes:
    """The model description with each carried value as its variable's start value."""
    root = etree.fromstring(description)
    found = set()
    if root.get("fmiVersion", "").startswith("2"):
        for variable in root.iterfind("ModelVariables/ScalarVariable"):
            name = variable.get("name")
            if name in carried and len(variable):
                variable[0].set("start", carried[name])
                found.add(name)
    else:
        for variable in root.find("ModelVariables") if root.find("ModelVariables") is not None else ():
            name = variable.get("name")
            if variable.tag not in FMI3_TYPES or name not in carried:
                continue
            if variable.tag == "String":
                for start in variable.findall("Start"):
                    variable.remove(start)
                etree.SubElement(variable, "Start", value=carried[name])
            else:
                variable.set("start", carried[name])
            found.add(name)
    missing = sorted(set(carried) - found)
    if missing:
        raise SspError(f"{where}: no variable '{missing[0]}' to carry a value for")
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8")
