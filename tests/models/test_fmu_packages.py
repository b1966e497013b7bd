"""The FMUs as files: FMI validity, the interface contract and defaults of pmsm_drive, parameter
copies equal to the canonical sets, documentation, a second FMI tool (libcosim), and a rebuild of
every FMU from its sources/."""

from __future__ import annotations

import shutil
import tomllib
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from cosim.platform.scene.parameter_sets import read_parameter_set
from cosim.engine.artifacts import ROOT, fmu_path
from shipped import MODELS

SHARED_PARAMS = ROOT.parent / "shared" / "params" / "meng2010.toml"

# FMU parameter -> (section, key) of params/meng2010.toml
DEFAULTS_FROM_PARAMS = {
    "motor.pole_pairs": ("motor", "pole_pairs"),
    "motor.torque_constant": ("motor", "torque_constant"),
    "motor.inductance_d": ("motor", "inductance_d"),
    "motor.inductance_q": ("motor", "inductance_q"),
    "motor.resistance": ("motor", "resistance"),
    "limit.speed": ("motor", "max_speed"),
    "limit.current": ("motor", "max_current"),
    "inverter.gain": ("inverter", "gain"),
    "inverter.time_constant": ("inverter", "time_constant"),
    "inverter.dc_link_voltage": ("inverter", "dc_link_voltage"),
    "inverter.hysteresis_band": ("inverter", "hysteresis_band"),
    "control.current_kp": ("control", "current_kp"),
    "control.current_ki": ("control", "current_ki"),
    "control.speed_kp": ("control", "speed_kp"),
    "control.speed_ki": ("control", "speed_ki"),
    "control.position_kp": ("control", "position_kp"),
    "control.position_ki": ("control", "position_ki"),
}


def test_interface_contract(pmsm_fmu):
    """The ports and capabilities ../shared/INTERFACES.md promises for pmsm_drive."""
    md = read_model_description(str(pmsm_fmu))
    variables = {v.name: v for v in md.modelVariables}
    expected = {
        "angle_ref": ("input", "rad"), "angle": ("input", "rad"), "speed": ("input", "rad/s"),
        "torque_ff": ("input", "N.m"), "torque": ("output", "N.m"),
        "current.d": ("output", "A"), "current.q": ("output", "A"),
        "voltage.d": ("output", "V"), "voltage.q": ("output", "V"),
        "power.electrical": ("output", "W"), "power.mechanical": ("output", "W"),
    }
    for name, (causality, unit) in expected.items():
        assert name in variables, name
        assert (variables[name].causality, variables[name].unit) == (causality, unit), name
    assert float(variables["torque_ff"].start) == 0.0
    cs = md.coSimulation
    assert cs.modelIdentifier == "pmsm_drive"
    assert cs.canHandleVariableCommunicationStepSize and cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
    assert md.defaultExperiment is not None and float(md.defaultExperiment.stepSize) > 0
    assert all(v.description for v in md.modelVariables)


def test_defaults_equal_the_parameter_set(pmsm_fmu):
    params = read_parameter_set("meng2010")
    variables = {v.name: v for v in read_model_description(str(pmsm_fmu)).modelVariables}
    for name, (section, key) in DEFAULTS_FROM_PARAMS.items():
        assert float(variables[name].start) == pytest.approx(params[section][key], rel=1e-12), name
    # psi_r is derived (K_m / P), never a second copy
    assert params["motor"]["torque_constant"] / params["motor"]["pole_pairs"] == pytest.approx(
        params["motor"]["flux_linkage"], rel=1e-12)


@pytest.mark.skipif(not SHARED_PARAMS.exists(), reason="../shared/params is not beside this checkout")
@pytest.mark.parametrize("name", ["meng2010", "sumnu2015"])
def test_project_parameter_copies_equal_the_canonical_sets(name):
    with open(SHARED_PARAMS.parent / f"{name}.toml", "rb") as f:
        canonical = tomllib.load(f)
    assert read_parameter_set(name) == canonical


FMUS = list(MODELS)


@pytest.mark.parametrize("name", FMUS)
def test_every_fmu_validates_and_is_documented(name):
    path = fmu_path(name)
    assert validate_fmu(str(path)) == []
    with zipfile.ZipFile(path) as z:
        names = set(z.namelist())
        assert {"modelDescription.xml", f"binaries/linux64/{name}.so", "documentation/index.html",
                "sources/model.c", "sources/fmi2_layer.c", "sources/ode.c", "sources/variables.h",
                "sources/model_guid.h"} <= names
        doc = z.read("documentation/index.html").decode()
    md = read_model_description(str(path))
    for v in md.modelVariables:  # every port and parameter, with its unit, is documented
        assert f"<code>{v.name}</code>" in doc, v.name
    assert "<h2>Equations</h2>" in doc or "Eqs 24-26" in doc
    cs = md.coSimulation
    assert cs.canHandleVariableCommunicationStepSize and cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
    assert md.defaultExperiment is not None and all(v.description for v in md.modelVariables)


def test_pmsm_documentation_names_its_equations(pmsm_fmu):
    with zipfile.ZipFile(pmsm_fmu) as z:
        doc = z.read("documentation/index.html").decode()
    for equation in ("Eqs 24-26", "modulus", "hysteresis"):
        assert equation in doc


def test_runs_in_libcosim(pmsm_fmu):
    """The Open Simulation Platform's engine loads, initializes and steps the FMU: torque mode,
    15 N.m commanded at standstill gives 15 N.m once the current loop has settled."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    md = read_model_description(str(pmsm_fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    execution = CosimExecution.from_step_size(step_size=int(1e6))  # 1 ms in ns
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=str(pmsm_fmu), instance_name="leg1"))
    assert execution.integer_initial_value(index, vr["control.mode"], 3)
    assert execution.real_initial_value(index, vr["torque_ff"], 15.0)
    assert execution.simulate_until(target_time=int(0.1e9))
    torque, current_q = observer.last_real_values(index, [vr["torque"], vr["current.q"]])
    assert torque == pytest.approx(15.0, rel=1e-4)
    assert current_q == pytest.approx(10.0, rel=1e-4)


def test_platform_runs_in_libcosim():
    """libcosim runs the mechanics with six linear motors wired as INTERFACES.md says, at 1 ms: the
    Sumnu platform, started at its home pose with zero leg references offset, stays up (the PID
    carries its weight) and ends within 1 mm of home."""
    from libcosimpy import CosimConstants
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    from cosim.platform.scene.parameter_sets import mechanics_start_values

    mech_path, motor_path = fmu_path("mechanics"), fmu_path("linear_motor")
    mech_vr = {v.name: v for v in read_model_description(str(mech_path)).modelVariables}
    motor_vr = {v.name: v.valueReference for v in read_model_description(str(motor_path)).modelVariables}
    execution = CosimExecution.from_step_size(step_size=int(1e6))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    mech = execution.add_local_slave(CosimLocalSlave(fmu_path=str(mech_path), instance_name="mechanics"))
    for name, value in mechanics_start_values("sumnu2015").items():
        v = mech_vr[name]
        if v.type == "Real":
            assert execution.real_initial_value(mech, v.valueReference, float(value))
        elif v.type == "Boolean":
            assert execution.boolean_initial_value(mech, v.valueReference, bool(value))
        else:
            assert execution.integer_initial_value(mech, v.valueReference, int(value))
    for i in range(1, 7):
        motor = execution.add_local_slave(CosimLocalSlave(fmu_path=str(motor_path), instance_name=f"motor{i}"))
        for out, inp in (("length_ref", "position_ref"), ("length", "position"), ("velocity", "velocity")):
            assert execution.connect_real_variables(mech, mech_vr[f"leg[{i}].{out}"].valueReference, motor,
                                                    motor_vr[inp]) == CosimConstants.success
        assert execution.connect_real_variables(motor, motor_vr["force"], mech,
                                                mech_vr[f"leg[{i}].force"].valueReference) == CosimConstants.success
    assert execution.simulate_until(target_time=int(2e9))
    pose = observer.last_real_values(mech, [mech_vr[f"pose.{a}"].valueReference for a in ("x", "y", "z")])
    np.testing.assert_allclose(pose, [-1.5, 0.0, 1.0], atol=1e-3)


@pytest.mark.parametrize("name", FMUS)
def test_rebuilds_from_its_sources(name, tmp_path):
    """sources/ alone rebuilds a binary (fmpy's CMake build) that gives the same results."""
    from fmpy.build import build_platform_binary

    path = fmu_path(name)
    rebuilt = tmp_path / "unzipped"
    with zipfile.ZipFile(path) as z:
        z.extractall(rebuilt)
    shutil.rmtree(rebuilt / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(rebuilt, build_dir=tmp_path / "build")
    assert (rebuilt / "binaries" / "linux64" / f"{name}.so").exists()

    outputs = [v.name for v in read_model_description(str(path)).modelVariables if v.causality == "output"
               and v.type == "Real"][:6]
    settings = dict(stop_time=0.02, output_interval=1e-3, output=outputs)
    original = simulate_fmu(str(path), **settings)
    from_sources = simulate_fmu(str(rebuilt), **settings)
    for output in outputs:
        np.testing.assert_allclose(from_sources[output], original[output], rtol=1e-9, atol=1e-12)


def test_a_whole_scene_runs_in_libcosim():
    """The Meng scene as FMUs and connections only (the trajectory FMU gives the reference and the
    impact): libcosim runs it at 1 ms and its platform ends within 5 mm / 5 mrad of the reference
    and of our master's run (its fixed-step algorithm holds inputs over a step, ours extrapolates,
    so they differ by the coupling error: measured 0.8 mm)."""

    from cosim.platform.run.libcosim import run_in_libcosim
    from cosim.platform.run.runner import run_scene
    from conftest import paper_scene

    scene = paper_scene("meng_eq35", {"scene.duration": 3.0})  # libcosim at the paper's 1 ms
    peer = run_in_libcosim(scene)
    ours, _ = run_scene(scene)
    final = np.array([ours[f"pose.{a}"][-1] for a in ("x", "y", "z", "roll", "pitch", "yaw")])
    np.testing.assert_allclose(peer.pose, peer.pose_ref, atol=5e-3)
    np.testing.assert_allclose(peer.pose, final, atol=5e-3)


@pytest.mark.parametrize("name", FMUS)
def test_an_fmu_binary_needs_libc_and_libm_alone_and_no_newer_glibc_than_2_33(name, tmp_path):
    """What a manylinux wheel and an FMI tool on an older Linux need of an FMU's binary: only the C
    library and libm (nothing to ship beside it), at glibc symbol versions up to 2.33 (the wheel's
    manylinux tag follows the newest symbol any of its binaries uses; scripts/check_wheel.sh repairs
    it with auditwheel)."""
    import re
    import subprocess
    with zipfile.ZipFile(fmu_path(name)) as z:
        binary = tmp_path / f"{name}.so"
        binary.write_bytes(z.read(f"binaries/linux64/{name}.so"))
    headers = subprocess.run(["objdump", "-p", str(binary)], capture_output=True, text=True, check=True).stdout
    needed = set(re.findall(r"NEEDED\s+(\S+)", headers))
    assert needed <= {"libc.so.6", "libm.so.6"}, needed
    symbols = subprocess.run(["objdump", "-T", str(binary)], capture_output=True, text=True, check=True).stdout
    versions = {tuple(map(int, v.split("."))) for v in re.findall(r"GLIBC_([0-9.]+)", symbols)}
    assert versions and max(versions) <= (2, 33), max(versions)
