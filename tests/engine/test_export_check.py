"""`cosim export-check SYSTEM.ssp` on a system that is not a platform (the two-mass oscillator of
tests/fmus/, at a step far too long for a plain master): each tool's step is the largest of the
system's step over a power of two at which its master holds every recorded output within 2 % of its
range against the system's converged run (twice it does not), or, where none down to a 64th does,
the closest, marked so; written where each tool takes it, every other entry of the archive byte for
byte as it was; an SSD without annotations or a default experiment gets them, schema-valid; and a
wrong file is one line."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest
from lxml import etree

from cosim.cli import main
from cosim.engine import FixedStep
from cosim.engine.execution import Execution
from cosim.engine.ssp import NS, read_ssp, validate, write_ssp
from cosim.engine.run import recording
from cosim.engine.settings import system_settings
from cosim.engine.tools import CONVERGED, FLOOR, TOOL_MASTERS, check_system, fit
from test_coupling import oscillator

STEP = 0.05  # [s] a plain master's coupling error here is many times the tolerance


@pytest.fixture
def archive(tmp_path):
    structure = oscillator(stop_time=2.0)
    structure.experiment.step = STEP
    return write_ssp(structure, tmp_path / "oscillator.ssp")


def written(path) -> dict:
    with zipfile.ZipFile(path) as z:
        root = etree.fromstring(z.read("SystemStructure.ssd"))
    validate(root, "SystemStructureDescription.xsd", "SystemStructure.ssd")
    return {"OMSimulator": float(root.find(".//oms:FixedStepMaster", NS).get("stepSize")),
            "libcosim": float(root.find(".//osp:FixedStepAlgorithm", NS).get("baseStepSize")),
            "tools": {e.get("tool"): (float(e.get("step")), e.get("within") == "true")
                      for e in root.iterfind(".//cosim:ToolStep", NS)}}


def entries(path) -> dict[str, bytes]:
    with zipfile.ZipFile(path) as z:
        return {name: z.read(name) for name in z.namelist() if name != "SystemStructure.ssd"}


def held(path, tool: str, step: float) -> bool:
    """The tool's master on the archive at `step` against the converged run, as export-check judges."""
    structure = read_ssp(path)
    master = next(m for m in TOOL_MASTERS if m.tool == tool)
    record, names = recording(structure)

    def run(algorithm, h):
        execution = Execution(structure, algorithm, FixedStep(h), record, names, clock="mass")
        try:
            return execution.run(2.0)
        finally:
            execution.free()

    own = system_settings(structure.settings, STEP)[0]
    return fit(run(master.algorithm, step), run(own, STEP / CONVERGED), names).within


def test_each_tool_gets_the_largest_step_its_master_holds_written_where_it_takes_it(archive, capsys):
    before = entries(archive)
    assert main(["export-check", str(archive)]) == 0
    out = capsys.readouterr().out
    assert all(f"| {m.tool} |" in out for m in TOOL_MASTERS)
    found = written(archive)
    assert entries(archive) == before  # the FMUs and parameter sets untouched
    assert set(found["tools"]) == {m.tool for m in TOOL_MASTERS}
    assert found["OMSimulator"] == found["tools"]["OMSimulator"][0]
    assert found["libcosim"] == found["tools"]["libcosim"][0]
    for tool, (step, within) in found["tools"].items():
        assert STEP / FLOOR <= step <= STEP and np.log2(STEP / step) % 1 == 0
        assert held(archive, tool, step) == within
        if within:  # the largest: twice it does not hold
            assert step < STEP and not held(archive, tool, 2 * step)
        else:  # none down to the floor holds
            assert not held(archive, tool, STEP / FLOOR)
    # OMSimulator's master reads the feed-through again and holds; the others start from the
    # coupling FMU's force at its inputs' defaults (no consistency sweep), an error no step removes
    assert found["tools"]["OMSimulator"][1] and not found["tools"]["libcosim"][1]
    assert read_ssp(archive).experiment.step == STEP  # our engine still runs it at its own step


def test_an_ssd_without_annotations_or_a_default_experiment_gets_them(archive, tmp_path):
    with zipfile.ZipFile(archive) as z:
        root = etree.fromstring(z.read("SystemStructure.ssd"))
        for element in [*root.iterfind("ssd:System/ssd:Annotations", NS), *root.iterfind("ssd:DefaultExperiment", NS)]:
            element.getparent().remove(element)
        bare = tmp_path / "bare.ssp"
        with zipfile.ZipFile(bare, "w") as out:
            for item in z.infolist():
                out.writestr(item, etree.tostring(root) if item.filename == "SystemStructure.ssd" else z.read(item))
    assert main(["export-check", str(bare)]) == 0
    found = written(bare)
    assert set(found["tools"]) == {m.tool for m in TOOL_MASTERS}


def test_the_measurement_is_the_engines_own(archive):
    duration, steps = check_system(read_ssp(archive))
    assert duration == 2.0 and [s.master for s in steps] == list(TOOL_MASTERS)


@pytest.mark.parametrize("name,content", [("notes.txt", b"x"), ("broken.ssp", b"not a zip")])
def test_a_wrong_file_is_one_line(tmp_path, capsys, name, content):
    (tmp_path / name).write_bytes(content)
    assert main(["export-check", str(tmp_path / name)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and len(err.strip().splitlines()) == 1 and str(tmp_path / name) in err


def test_for_a_system_of_fmi3_fmus_only_the_tools_that_load_them_are_measured():
    """libcosim (libcosimpy 0.0.6) and fmpy.ssp (0.3.32) do not load FMI 3.0 FMUs: no step is
    measured for them there, and the export says why; every tool is measured for FMI 2.0."""
    from cosim.engine.tools import Fit, ToolStep, fmi3_lines, largest_steps

    def attempt(master, step):
        return ToolStep(master, step, Fit(0.5, "x"), 0.0)

    assert [s.master.tool for s in largest_steps(1e-3, attempt, fmi3=True)] == \
        [m.tool for m in TOOL_MASTERS if m.tool not in ("libcosim", "fmpy.ssp")]
    assert [s.master.tool for s in largest_steps(1e-3, attempt)] == [m.tool for m in TOOL_MASTERS]
    said = fmi3_lines()
    assert len(said) == len(TOOL_MASTERS)
    assert [line.split(": ")[2].split(" ")[0] for line in said if "no step measured" in line] == ["libcosim", "fmpy.ssp"]
