"""The interface Jacobians the drives publish (pmsm_drive's torque_speed_slope, linear_motor's
force_velocity_slope) against finite differences of the FMUs themselves, and the mechanics applying
them: each leg feels effort + slope (flow - the flow its drive was given), inside its own energy
balance."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.engine.artifacts import fmu_path
from cosim.engine.fmi import FmuInstance
from cosim.platform.core import Core, core_library
from test_mechanics_fmu import dll, energy_error, hold_torques, make_mechanics, mechanics_fmu  # noqa: F401 (fixtures)


def effort_change(drive: FmuInstance, flow: str, effort: str, delta: float, step: float, position: str = "") -> float:
    """d effort / d flow by a finite difference over one step from the drive's present state: the
    flow input raised by delta (and held over the step) against it unchanged; `position`, if given,
    the input that is held where it is (given with a zero derivative, as a master that extrapolates
    does, instead of advanced by the flow inside the step)."""
    state = drive.get_state()
    base = drive.get(flow)
    results = []
    for value in (base, base + delta):
        drive.set_state(state)
        drive.set({flow: value})
        if position:
            drive.set_input_derivatives([position], [0.0])
        drive.do_step(step)
        results.append(drive.get(effort))
    drive.set_state(state)
    drive.free_state(state)
    return (results[1] - results[0]) / delta


def settle(drive: FmuInstance, seconds: float, step: float = 1e-3) -> None:
    for _ in range(round(seconds / step)):
        drive.do_step(step)


@pytest.mark.parametrize("inverter", [1, 2])
def test_pmsm_torque_speed_slope_is_the_speed_loops_and_the_back_emfs(make_drive, inverter):
    """Speed mode with a proportional speed loop (Ki = 0, so that only what the slope describes
    acts): a speed input held 0.1 rad/s higher over 2 ms moves the torque by the published slope
    -K_m (Kp_w + K_m / (K_v Kp_c + R)) = -10.52 N m s/rad within 0.3 % (measured 0.11 %: the current
    loop, 0.2 ms, has settled; the back-EMF's push on the current, 0.6 % of the slope, is still
    there). With the PI speed loop the same step also integrates Ki per rad/s over it: the change is
    slope (1 + Ki (h - tau_c) / Kp_w) within 0.3 % (measured 0.17 %), the published slope being the
    loop's instantaneous part."""
    back_emf = 1.5 / (50.7 * 0.6805 + 0.7)
    for ki in (0.0, 580.5):
        drive = make_drive({"inverter.model": inverter, "control.mode": 2, "control.speed_ki": ki,
                            "initial.current_q": 0.0}, name=f"slope_{inverter}_{ki}")
        drive.set({"speed_ff": 20.0, "speed": 19.0})  # 1 rad/s below the reference: 7 A, far from 42 A
        settle(drive, 0.05)
        slope = drive.get("torque_speed_slope")
        assert slope == pytest.approx(-1.5 * (6.97 + back_emf), rel=1e-12)
        measured = effort_change(drive, "speed", "torque", 0.1, 2e-3)
        assert measured == pytest.approx(slope * (1.0 + ki * (2e-3 - 0.2e-3) / 6.97), rel=3e-3)


def test_pmsm_slope_is_the_back_emfs_alone_where_the_current_limit_holds_the_loop(make_drive):
    """A speed error of 100 rad/s asks for 697 A: the 42 A limit holds the speed loop, and the
    published slope is the back-EMF's alone, -K_m^2 / (K_v Kp_c + R) = -0.064 N m s/rad, 0.6 % of the
    free slope; over 2 ms the current loop's integrator has taken back a sixth of it (finite
    difference -0.054: within 20 %)."""
    drive = make_drive({"inverter.model": 2, "control.mode": 2, "initial.current_q": 0.0}, name="limited")
    drive.set({"speed_ff": 100.0, "speed": 0.0})
    settle(drive, 0.01)
    assert drive.get("current_ref.q") == pytest.approx(42.0)
    slope = drive.get("torque_speed_slope")
    assert slope == pytest.approx(-1.5 ** 2 / (50.7 * 0.6805 + 0.7), rel=1e-12)
    assert effort_change(drive, "speed", "torque", 0.1, 2e-3) == pytest.approx(slope, rel=0.2)


@pytest.mark.parametrize("electrical", [False, True])
def test_linear_motor_force_velocity_slope_is_its_damping(electrical):
    """Position mode at rest, the position given with its derivative (so a velocity change does not
    move it within the step), friction and ripple off: a velocity input held 1 mm/s higher over
    1 ms moves the force by the published slope, -(K_d + B_l) = -628.3 N s/m for the ideal force
    source (within 1e-9) and -(K_d + K_f K_e / (Kp_c + R) + B_l) = -645.7 N s/m with the winding
    (within 2 %, measured 1.0 %: its current loop, 0.16 ms, has settled, and its integrator has
    begun to take back the back-EMF's push)."""
    motor = FmuInstance(fmu_path("linear_motor"), "slope")
    try:
        motor.initialize({"effects.electrical": electrical, "effects.friction": False, "effects.ripple": False})
        motor.set({"position_ref": 0.002, "position": 0.0, "velocity": 0.0})
        settle(motor, 0.02)
        slope = motor.get("force_velocity_slope")
        expected = -(628.3 + 0.01) - (44.0 * 26.0 / (62.83 + 3.1) if electrical else 0.0)
        assert slope == pytest.approx(expected, rel=1e-12)
        measured = effort_change(motor, "velocity", "force", 1e-3, 1e-3, position="position")
        assert measured == pytest.approx(slope, rel=2e-2 if electrical else 1e-9)
    finally:
        motor.free()


def test_mechanics_feels_the_slope_against_the_speed_its_drive_saw(make_mechanics, dll):
    """The mechanics with every leg's slope at -10.46 N m s/rad and speed_seen held at 0 while the
    platform moves: its legs feel torque + slope (speed - 0), a damper on each motor shaft, so the
    kinetic energy it gains is smaller than without (the platform is braked), and its energy accounts
    still balance to 1e-6 of the energy that flowed (power.drive is the torque the legs felt)."""
    core = Core(dll)
    hold = hold_torques(dll, core.neutral_pose)
    runs = {}
    for slope in (0.0, -10.46):
        mech = make_mechanics({"solver.method": 2}, name=f"braked_{slope}")
        e0, _ = energy_error(mech)
        inputs = mech.real_group([f"leg[{i}].torque" for i in range(1, 7)] +
                                 [f"leg[{i}].torque_speed_slope" for i in range(1, 7)])
        for k in range(300):
            inputs.write(np.r_[hold + 3.0 * np.sin(2 * np.pi * 2 * k * 1e-3 + np.arange(6)), np.full(6, slope)])
            mech.do_step(1e-3)
        e1, supplied = energy_error(mech)
        flowed = abs(mech.get("energy.drive"))
        assert (e1 - e0) == pytest.approx(supplied, abs=1e-6 * max(flowed, abs(e1 - e0)))
        runs[slope] = mech.get("energy.kinetic")
    assert runs[-10.46] < 0.5 * runs[0.0]
