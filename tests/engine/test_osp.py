"""The OSP configuration (OspSystemStructure.xml) of the oscillator, run by libcosim: its fixed-step
algorithm agrees with our order-0 Jacobi to round-off (both start from consistent outputs), and its
ECCO algorithm, configured from our energy-control settings through the power bond, tracks the
exact solution (measured 1.5e-4 against 1e-2 for the fixed 1 ms step)."""

from __future__ import annotations

import pytest

from cosim.engine import Algorithm, EnergyControl, FixedStep
from cosim.engine.execution import Execution
from cosim.engine.osp import write_osp
from cosim.engine.settings import to_strings
from test_coupling import exact_position_1, oscillator


def libcosim_position(xml, stop: float) -> float:
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_osp_config_file(str(xml))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    assert execution.simulate_until(int(round(stop * 1e9)))
    index = {s.name.decode(): s.index for s in execution.slave_infos()}
    refs = {v.name.decode(): v.reference for v in execution.slave_variables(index["mass"])}
    return observer.last_real_values(index["mass"], [refs["position"]])[0]


def ours(stop: float) -> float:
    execution = Execution(oscillator(stop), Algorithm("jacobi", 0), FixedStep(1e-3), [("mass", "position")])
    try:
        return float(execution.run(stop)["mass.position"][-1])
    finally:
        execution.free()


def test_libcosim_fixed_step_agrees_with_ours_to_round_off(tmp_path):
    system = oscillator(1.0)
    system.settings = to_strings(Algorithm("jacobi", 0), FixedStep(1e-3))
    assert libcosim_position(write_osp(system, tmp_path), 1.0) == pytest.approx(ours(1.0), rel=1e-12)


def test_libcosim_ecco_from_our_configuration_tracks_the_exact_solution(tmp_path):
    system = oscillator(1.0)
    system.settings = to_strings(Algorithm("jacobi", 0), EnergyControl(1e-3, rtol=1e-4, atol=1e-6))
    xml = write_osp(system, tmp_path)
    text = xml.read_text()
    assert "<Algorithm>ecco</Algorithm>" in text and text.count('powerBond="bond1"') == 2
    error = abs(libcosim_position(xml, 1.0) - exact_position_1(1.0))
    assert error < 1e-3
    assert error < 0.1 * abs(ours(1.0) - exact_position_1(1.0))


@pytest.mark.parametrize("control", [EnergyControl(1e-3, rtol=1e-4, atol=1e-6),
                                     EnergyControl(2e-3, rtol=3e-3, atol=1e-5, h_min=1e-5, h_max=5e-2, k_i=0.1,
                                                   k_p=0.3, safety=0.99, change_min=0.25, change_max=1.5)])
def test_the_exported_ecco_configuration_is_the_law_the_kernel_runs(tmp_path, control):
    """One ECCO law: every number of the exported EccoConfiguration is the system's EnergyControl
    field that the kernel uses (before, the export wrote libcosim's 0.99 and [0.2, 1.5] whatever
    the kernel ran)."""
    from lxml import etree
    system = oscillator(1.0)
    system.settings = to_strings(Algorithm("jacobi", 0), control)
    root = etree.parse(str(write_osp(system, tmp_path))).getroot()
    written = {e.tag.split("}")[1]: float(e.text) for e in root.find("{*}EccoConfiguration")}
    assert written == {"SafetyFactor": control.safety, "StepSize": control.step, "MinimumStepSize": control.h_min,
                       "MaximumStepSize": control.h_max, "MinimumChangeRate": control.change_min,
                       "MaximumChangeRate": control.change_max, "ProportionalGain": control.k_p,
                       "IntegralGain": control.k_i, "RelativeTolerance": control.rtol,
                       "AbsoluteTolerance": control.atol}
