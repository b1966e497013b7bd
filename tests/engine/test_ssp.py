"""SSP 1.0 in and out on the oscillator alone: the archive is schema-valid, reads back into the same
system, runs bit for bit like the system it came from, and a broken archive is one clear error."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest
from lxml import etree

from cosim.engine import Algorithm, Execution, FixedStep
from cosim.engine.command import run_ssp
from cosim.engine.settings import to_strings
from cosim.engine.ssp import SspError, read_ssp, validate, write_ssp
from test_coupling import oscillator


@pytest.fixture(params=[False, True], ids=["plain", "interface-jacobian"])
def archive(tmp_path, request):
    """The oscillator, plain and with the coupling FMU's interface Jacobian (an FMU's outputs wired
    back to its own inputs, and the bond's slope in the annotation)."""
    system = oscillator(0.5, interface_jacobian=request.param)
    system.components[0].parameters = {"mass": 2.0}
    system.settings = to_strings(Algorithm("gauss-seidel", 1, ("coupling", "mass")), FixedStep(1e-3))
    return system, write_ssp(system, tmp_path / "oscillator.ssp")


def test_archive_is_schema_valid_and_reads_back(archive):
    system, path = archive
    with zipfile.ZipFile(path) as z:
        assert {"SystemStructure.ssd", "resources/mass.ssv", "resources/oscillator_mass.fmu",
                "resources/oscillator_coupling.fmu"} <= set(z.namelist())
        validate(etree.fromstring(z.read("SystemStructure.ssd")), "SystemStructureDescription.xsd", "ssd")
        validate(etree.fromstring(z.read("resources/mass.ssv")), "SystemStructureParameterValues.xsd", "ssv")
    back = read_ssp(path)
    assert [c.name for c in back.components] == ["mass", "coupling"]
    assert back.components[0].parameters == {"mass": 2.0}
    assert back.connections == system.connections and back.bonds == system.bonds
    assert back.experiment == system.experiment and back.settings == system.settings


def test_ssp_run_equals_the_system_run_bit_for_bit(archive, tmp_path):
    system, path = archive
    execution = Execution(system, Algorithm("gauss-seidel", 1, ("coupling", "mass")), FixedStep(1e-3),
                          [("mass", "position"), ("coupling", "force")])
    try:
        direct = execution.run(0.5)
    finally:
        execution.free()
    result, report = run_ssp(path, tmp_path / "out")
    assert np.array_equal(result["mass.position"], direct["mass.position"])
    assert np.array_equal(result["coupling.force"], direct["coupling.force"])
    assert (tmp_path / "out" / "oscillator.csv").exists() and report.macro_steps == 500


@pytest.mark.parametrize("damage,message", [
    (lambda ssd: ssd.replace(b'kind="input"', b'kind="sideways"'), "SystemStructure.ssd:"),
    (lambda ssd: ssd.replace(b'source="resources/oscillator_mass.fmu"', b'source="resources/nothing.fmu"'),
     "resources/nothing.fmu is not in the archive"),
    (lambda ssd: ssd[:200], "SystemStructure.ssd"),
])
def test_a_broken_archive_is_one_clear_error(archive, tmp_path, damage, message):
    _, path = archive
    broken = tmp_path / "broken.ssp"
    with zipfile.ZipFile(path) as source, zipfile.ZipFile(broken, "w") as target:
        for name in source.namelist():
            data = source.read(name)
            target.writestr(name, damage(data) if name == "SystemStructure.ssd" else data)
    with pytest.raises(SspError, match=message):
        read_ssp(broken)


def test_not_an_archive(tmp_path):
    (tmp_path / "x.ssp").write_text("hello")
    with pytest.raises(SspError, match="not an SSP archive"):
        read_ssp(tmp_path / "x.ssp")
