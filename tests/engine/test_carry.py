"""FMUs that carry their values (cosim.engine.carry, fmu/common/fmi2_layer.c): a carrying copy runs
its component's values in a tool that sets none (fmpy's simulate_fmu), bit for bit as the original
given the same values, FMI 3.0 as FMI 2.0; its model description says them as start values and
stays valid; a file travels in its resources/; a reset takes them again; a folder whose URI is
percent-encoded is found; a carried value the FMU refuses stops its instantiation with the reason."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, instantiate_fmu, read_model_description, simulate_fmu

from cosim.engine.artifacts import ROOT, fmu_path
from cosim.engine.carry import START_VALUES, carrying

VALUES = {"x.sine[1].amplitude": 0.1, "x.sine[1].frequency": 1.5, "z.offset": 1.7, "roll.sine[1].amplitude": 0.05,
          "roll.sine[1].frequency": 0.7}
OUTPUTS = ["pose_ref.x", "pose_ref.z", "pose_ref.roll"]


@pytest.mark.parametrize("fmi", [2, 3])
def test_a_carrying_fmu_runs_its_values_where_nobody_sets_them(tmp_path, fmi):
    original = fmu_path("trajectory", fmi=fmi)
    carried = carrying(original, VALUES, tmp_path / "trajectory.fmu")
    theirs = simulate_fmu(str(carried), stop_time=1.0, step_size=1e-3, output=OUTPUTS)
    given = simulate_fmu(str(original), stop_time=1.0, step_size=1e-3, output=OUTPUTS, start_values=VALUES)
    assert np.ptp(theirs["pose_ref.x"]) > 0.19 and theirs["pose_ref.z"][0] == 1.7
    for name in OUTPUTS:
        assert np.array_equal(theirs[name], given[name]), name
    description = read_model_description(str(carried), validate=True)  # fmpy's validation of the XML
    starts = {v.name: v.start for v in description.modelVariables if v.name in VALUES}
    assert {name: float(text) for name, text in starts.items()} == VALUES


def test_a_file_travels_in_the_fmus_resources(tmp_path):
    drive = ROOT / "examples" / "vehicle" / "drive.csv"
    carried = carrying(fmu_path("cueing"), {"vehicle.file": drive}, tmp_path / "cueing.fmu")
    with zipfile.ZipFile(carried) as archive:
        assert archive.read("resources/drive.csv") == drive.read_bytes()
        assert "vehicle.file=@resources/drive.csv" in archive.read(START_VALUES).decode()
    drive_elsewhere = tmp_path / "moved" / "drive.csv"  # the original file gone from where it was named
    theirs = simulate_fmu(str(carried), stop_time=4.0, step_size=1e-3, output=["pose_ref.x"])
    given = simulate_fmu(str(fmu_path("cueing")), stop_time=4.0, step_size=1e-3, output=["pose_ref.x"],
                         start_values={"vehicle.file": str(drive)})
    assert not drive_elsewhere.exists() and np.ptp(theirs["pose_ref.x"]) > 0.01
    assert np.array_equal(theirs["pose_ref.x"], given["pose_ref.x"])


def test_a_reset_takes_the_carried_values_again_and_a_percent_encoded_folder_is_found(tmp_path):
    carried = carrying(fmu_path("trajectory"), VALUES, tmp_path / "trajectory.fmu")
    folder = tmp_path / "with space, 100% & #"
    unzipped = extract(str(carried), unzipdir=str(folder))
    description = read_model_description(unzipped)
    vr = {v.name: v.valueReference for v in description.modelVariables}
    fmu = instantiate_fmu(unzipped, description)  # its resource URI percent-encodes the folder's name
    try:
        fmu.setReal([vr["z.offset"]], [1.2])
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        assert fmu.getReal([vr["z.offset"]]) == [1.2]
        fmu.reset()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        assert fmu.getReal([vr["z.offset"], vr["x.sine[1].frequency"]]) == [1.7, 1.5]
    finally:
        fmu.freeInstance()  # (and its library)


@pytest.mark.parametrize("line, reason", [("no.such.variable=1", "no variable 'no.such.variable'"),
                                          ("x.sine[1].frequency=-3", "x.sine[1].frequency"),
                                          ("z.offset=one", "z.offset = 'one' not taken"),
                                          ("pose_ref.x=1", "is an output")])
def test_a_carried_value_the_fmu_refuses_stops_its_instantiation(tmp_path, line, reason):
    carried = carrying(fmu_path("trajectory"), {}, tmp_path / "plain.fmu")
    broken = tmp_path / "broken.fmu"
    with zipfile.ZipFile(carried) as source, zipfile.ZipFile(broken, "w") as out:
        for entry in source.infolist():
            out.writestr(entry, f"{line}\n" if entry.filename == START_VALUES else source.read(entry))
    # instantiated by hand, its library freed after: fmpy's simulate_fmu leaves the library of an FMU that
    # failed to instantiate loaded while it deletes its file, whose inode a later FMU's file may then get
    # (and the dynamic loader hands that one the stale library)
    from fmpy.fmi2 import FMU2Slave
    unzipped = extract(str(broken), unzipdir=str(tmp_path / "unzipped"))
    description = read_model_description(unzipped)
    messages = []
    slave = FMU2Slave(guid=description.guid, unzipDirectory=unzipped,
                      modelIdentifier=description.coSimulation.modelIdentifier, instanceName="broken")
    try:
        with pytest.raises(Exception, match="Failed to instantiate"):
            slave.instantiate(loggingOn=True, callbacks=_logging(messages))
    finally:
        slave.freeLibrary()
    assert any(reason in m for m in messages if isinstance(m, str)), messages


def _logging(messages: list):
    """fmpy's FMI 2.0 callbacks with a logger that keeps each message (the callbacks kept alive in
    `messages` too, as its last item)."""
    from fmpy import calloc, free
    from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                           fmi2CallbackLoggerTYPE)

    def log(environment, instance, status, category, message):
        messages.insert(0, message.decode())

    functions = fmi2CallbackFunctions()
    functions.logger = fmi2CallbackLoggerTYPE(log)
    functions.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    functions.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    messages.append(functions)
    return functions


def test_only_the_named_components_carry(tmp_path):
    """The SSP writer carries for the components it is told (ours), each in an FMU of its own."""
    import cosim
    from cosim.engine.ssp import read_ssp
    archive = cosim.export_ssp("meng_eq35", tmp_path / "meng.ssp", measure=False)
    with zipfile.ZipFile(archive) as z:
        fmus = sorted(n for n in z.namelist() if n.endswith(".fmu"))
    structure = read_ssp(archive)
    assert fmus == sorted(f"resources/{c.name}.fmu" for c in structure.components)
    assert Path(structure.component("pmsm3").fmu).name == "pmsm3.fmu"
