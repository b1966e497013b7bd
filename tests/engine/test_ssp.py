"""SSP 1.0 in and out on the oscillator alone: the archive is schema-valid, reads back into the same
system, runs bit for bit like the system it came from, and a broken archive is one clear error."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest
from lxml import etree

from cosim.engine import Algorithm, FixedStep
from cosim.engine.execution import Execution
from cosim.engine.run import run_system
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
    result, report = run_system(read_ssp(path), out=tmp_path / "out", source=str(path))
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


@pytest.mark.parametrize("damage", ["compression", "crc", "truncated"])
def test_an_archive_that_cannot_be_unpacked_is_one_clear_error(archive, tmp_path, damage):
    """A zip whose entries cannot be unpacked: a compression method zipfile lacks (its
    NotImplementedError), a wrong checksum, a cut-off deflate stream, each one line naming the file."""
    import struct
    _, path = archive
    data = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as z:
        info = z.getinfo("SystemStructure.ssd")
    header = info.header_offset
    if damage == "compression":  # method 99 in both the local and the central header
        data[header + 8:header + 10] = struct.pack("<H", 99)
        central = data.find(b"PK\x01\x02")
        while central >= 0 and struct.unpack("<I", data[central + 42:central + 46])[0] != header:
            central = data.find(b"PK\x01\x02", central + 4)
        data[central + 10:central + 12] = struct.pack("<H", 99)
    else:
        start = header + 30 + len(info.filename.encode()) + len(info.extra)
        if damage == "crc":
            data[start] ^= 0xFF
        else:
            data[start + 1:start + info.compress_size] = bytes(info.compress_size - 1)
    broken = tmp_path / "broken.ssp"
    broken.write_bytes(bytes(data))
    with pytest.raises(SspError) as error:
        read_ssp(broken)
    assert str(error.value).startswith(f"{broken}: ") and "\n" not in str(error.value)


def test_not_an_archive(tmp_path):
    (tmp_path / "x.ssp").write_text("hello")
    with pytest.raises(SspError, match="not an SSP archive"):
        read_ssp(tmp_path / "x.ssp")


def _without_our_annotation(archive: Path, folder: Path, annotation: str = "") -> Path:
    """The archive's SSD unpacked, this project's run annotation replaced by `annotation`."""
    import re
    with zipfile.ZipFile(archive) as z:
        z.extractall(folder)
    ssd = folder / "SystemStructure.ssd"
    text = re.sub(r"<ssd:Annotations>.*?</ssd:Annotations>", annotation, ssd.read_text(), flags=re.S)
    ssd.write_text(text)
    return ssd


def test_a_step_only_in_the_osp_annotation_is_the_step_taken_and_said(archive, tmp_path):
    """libcosim's own SSPs carry their step only in the OSP annotation (FixedStepAlgorithm
    baseStepSize): the run takes it and says where it came from; with no step anywhere, the run
    says it took the default."""
    _, path = archive
    osp = ('<ssd:Annotations><ssc:Annotation type="com.opensimulationplatform"><osp:Algorithm '
           'xmlns:osp="http://opensimulationplatform.com/SSP/OSPAnnotations"><osp:FixedStepAlgorithm '
           'baseStepSize="2e-3"/></osp:Algorithm></ssc:Annotation></ssd:Annotations>')
    ssd = _without_our_annotation(path, tmp_path / "osp", osp)
    _, report = run_system(read_ssp(ssd), source=str(ssd))
    assert report.macro_steps == 250  # 0.5 s at 2 ms
    assert "macro step 0.002 s: the OSP annotation's FixedStepAlgorithm baseStepSize" in report.text()
    bare = _without_our_annotation(path, tmp_path / "bare")
    _, report = run_system(read_ssp(bare), source=str(bare))
    assert report.macro_steps == 500 and "macro step 0.001 s: no step in the SSD" in report.text()
    _, ours = run_system(read_ssp(path), source=str(path))
    assert "macro step" not in ours.text().split("\n", 2)[-1]  # our own annotation's step needs no word


def test_the_export_carries_the_annotations_other_tools_need(archive):
    """OMSimulator takes the system's type only from its own annotation on ssd:System (its
    command-line tool aborts without it): a FixedStepMaster 'oms-ma' whose four attributes its
    published schema requires, as xs:decimal (digits, no exponent), at the system's step;
    libcosim's base step in the OSP annotation of the default experiment. The archive stays valid
    SSP, and our own annotation's step is the one read back."""
    import re
    system, path = archive
    with zipfile.ZipFile(path) as z:
        root = etree.fromstring(z.read("SystemStructure.ssd"))
    validate(root, "SystemStructureDescription.xsd", "ssd")
    ns = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
          "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
          "oms": "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd",
          "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations"}
    master = root.findall("ssd:System/ssd:Annotations/ssc:Annotation[@type='org.openmodelica']/oms:Annotations/"
                          "oms:SimulationInformation/oms:FixedStepMaster", ns)
    assert len(master) == 1 and master[0].get("description") == "oms-ma"
    for attribute in ("stepSize", "absoluteTolerance", "relativeTolerance"):
        assert re.fullmatch(r"[0-9]+(\.[0-9]+)?", master[0].get(attribute)), attribute
    assert float(master[0].get("stepSize")) == system.experiment.step
    base = root.find("ssd:DefaultExperiment/ssd:Annotations/ssc:Annotation[@type='com.opensimulationplatform']/"
                     "osp:Algorithm/osp:FixedStepAlgorithm", ns)
    assert float(base.get("baseStepSize")) == system.experiment.step
    assert read_ssp(path).experiment.step_source == "this project's annotation"
