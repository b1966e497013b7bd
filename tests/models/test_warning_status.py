"""fmi.warnings_as_ok, a parameter of every FMU (fmu/common/fmu_table.h): a step that logs a
warning returns fmi2Warning as FMI 2.0 says, or, for importers that stop on any status but fmi2OK
(OMSimulator stops the Meng scene at 0.636 s, where a leg leaves its stroke), fmi2OK with the
warning still in the log; the export sets it on every component when asked."""

from __future__ import annotations

import zipfile

import pytest
from fmpy import read_model_description

from cosim.cli import main
from cosim.engine.artifacts import ROOT, fmu_path
from shipped import MODELS
from cosim.engine.fmi import FmuInstance
from cosim.platform.ports import POSE

FMUS = list(MODELS)


@pytest.mark.parametrize("name", FMUS)
def test_every_fmu_has_the_parameter_defaulting_to_the_standard(name):
    variables = {v.name: v for v in read_model_description(str(fmu_path(name))).modelVariables}
    v = variables["fmi.warnings_as_ok"]
    assert (v.type, v.causality, v.variability, v.start) == ("Boolean", "parameter", "fixed", "false")


def step_status(warnings_as_ok: bool) -> tuple[int, list[str]]:
    """The status of a mechanics step from a start pose with the legs past their stroke (2.2 m
    high), and the warnings it logged."""
    fmu = FmuInstance(fmu_path("mechanics"), "mechanics")
    try:
        start = {f"initial.pose.{a}": v for a, v in zip(POSE, (0.0, 0.0, 2.2, 0.0, 0.0, 0.0))}
        fmu.initialize({**start, "fmi.warnings_as_ok": warnings_as_ok})
        fmu.messages.clear()
        status = fmu.fmu.fmi2DoStep(fmu.fmu.component, 0.0, 1e-3, 0)  # the status itself, not fmpy's reading
        return status, [m.text for m in fmu.messages if m.status == "warning"]
    finally:
        fmu.free()


def test_a_warning_returns_fmi2warning_or_fmi2ok_and_stays_in_the_log():
    standard, standard_warnings = step_status(False)
    lenient, lenient_warnings = step_status(True)
    assert (standard, lenient) == (1, 0)  # fmi2Warning, fmi2OK
    assert standard_warnings and standard_warnings == lenient_warnings
    assert "outside the stroke" in lenient_warnings[0]


def test_the_export_sets_it_on_every_component_when_asked(tmp_path, capsys):
    archive = tmp_path / "meng.ssp"
    assert main(["export", str(ROOT / "scenes" / "meng_eq35.toml"), "--ssp", str(archive), "--warnings-as-ok"]) == 0
    assert "fmi.warnings_as_ok = true" in capsys.readouterr().out
    with zipfile.ZipFile(archive) as z:
        ssvs = [z.read(n).decode() for n in z.namelist() if n.endswith(".ssv")]
    assert len(ssvs) == 8 and all('name="fmi.warnings_as_ok"' in text for text in ssvs)


@pytest.mark.parametrize("warnings_as_ok, logged", [(False, True), (True, False)])
def test_a_returned_warning_carries_its_reason_with_logging_off(tmp_path, warnings_as_ok, logged):
    """An importer that instantiates with logging off (fmusim's default) and stops at a warning
    still gets the reason; a warning returned as fmi2OK (fmi.warnings_as_ok) stays quiet there."""
    from fmpy import extract
    from fmpy.fmi2 import FMU2Slave, defaultCallbacks, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
    description = read_model_description(str(fmu_path("mechanics")))
    vrs = {v.name: v.valueReference for v in description.modelVariables}
    said = []
    slave = FMU2Slave(guid=description.guid, unzipDirectory=extract(str(fmu_path("mechanics")), str(tmp_path)),
                      modelIdentifier=description.coSimulation.modelIdentifier, instanceName="mechanics")

    def logger(environment, instance, status, category, message):
        said.append((status, message.decode()))
    callbacks = fmi2CallbackFunctions()  # fmpy's, but a logger that records what it is told
    callbacks.logger = fmi2CallbackLoggerTYPE(logger)
    callbacks.allocateMemory, callbacks.freeMemory = defaultCallbacks.allocateMemory, defaultCallbacks.freeMemory
    slave.instantiate(loggingOn=False, callbacks=callbacks)
    slave.setupExperiment(startTime=0.0)
    slave.setReal([vrs["initial.pose.z"]], [2.2])
    slave.setBoolean([vrs["fmi.warnings_as_ok"]], [warnings_as_ok])
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    said.clear()
    status = slave.fmi2DoStep(slave.component, 0.0, 1e-3, 0)
    slave.terminate()
    slave.freeInstance()
    assert status == (0 if warnings_as_ok else 1)
    warnings = [m for s, m in said if s == 1]
    assert bool(warnings) == logged and (not logged or "outside the stroke" in warnings[0])
