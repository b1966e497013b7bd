"""The validation report's key numbers (docs/validation.md, `python -m cosim validate`) as assertions
with the tolerances the report defends. A number that misses because we suspect the paper is a
strict xfail with the reason: documented, not deleted."""

from __future__ import annotations

import numpy as np
import pytest

from cosim.platform.validation import halder, meng, sumnu


@pytest.fixture(scope="module")
def bandwidths():
    return meng.bandwidths()[1]


@pytest.fixture(scope="module")
def table_5_rows():
    return meng.surge_rows(meng.table_5(closed_loop=False)[1]["entries"])


def test_every_dof_has_a_bandwidth_above_10_hz(bandwidths):
    """Meng Fig 6: 'all the bandwidths of the 6 DOFs are above 10 Hz' (measured 10.9-14.6 Hz)."""
    assert all(b > 10.0 for b in bandwidths["bandwidths"].values()), bandwidths["bandwidths"]


@pytest.mark.parametrize("dof,low,high", [("x", 14, 15), ("y", 14, 15), ("z", 11, 12), ("roll", 11, 12),
                                          ("pitch", 11, 12)])
def test_bandwidths_fall_in_the_papers_bands(bandwidths, dof, low, high):
    """Within 0.5 Hz of the paper's band: the frequency grid's log interpolation and the paper's
    reading of its Bode plot are both good to about that."""
    assert low - 0.5 <= bandwidths["bandwidths"][dof] <= high + 0.5


@pytest.mark.xfail(strict=True, reason="yaw: 11.6 Hz against the paper's 14-15 Hz; in our model yaw moves the "
                                       "legs' motor-side inertia as much as roll and pitch (docs/validation.md)")
def test_yaw_bandwidth_is_in_the_papers_band(bandwidths):
    assert 13.5 <= bandwidths["bandwidths"]["yaw"] <= 15.5


ROWS_AS_PRINTED = [0, 1, 2, 5, 6, 7]


def test_table_5_follows_the_peak_reading_of_eq_40(table_5_rows):
    """The paper's Table 5 is closer to the peak reading of Eq 40 than to the peak-to-peak one."""
    paper = table_5_rows["paper"]
    peak = np.abs(table_5_rows[("inverse", "peak")] - paper).mean()
    peak_to_peak = np.abs(table_5_rows[("inverse", "peak-to-peak")] - paper).mean()
    assert peak < 0.5 * peak_to_peak


def test_table_5_ratio_1_within_1_2_points_of_the_paper(table_5_rows):
    """Rows 1-3 and 6-8: Ratio_1 within 1.2 points (measured largest gap 1.1). Ratio_1 grows with
    frequency at equal amplitude (rows 1-3, 4-5, 7-8) as the paper says."""
    ours, paper = table_5_rows[("inverse", "peak")][:, 0], table_5_rows["paper"][:, 0]
    assert np.all(np.abs(ours - paper)[ROWS_AS_PRINTED] <= 1.2), ours
    assert ours[0] < ours[1] < ours[2] and ours[3] < ours[4] and ours[6] < ours[7]


def test_table_5_ratio_2_within_4_points_of_the_paper(table_5_rows):
    """Ratio_2 depends on the actuators' mass distribution the paper does not give: within 4 points
    (measured -0.6 to +3.5)."""
    ours, paper = table_5_rows[("inverse", "peak")][:, 1], table_5_rows["paper"][:, 1]
    assert np.all(np.abs(ours - paper) <= 4.0), ours


@pytest.mark.xfail(strict=True, reason="Table 5 rows 4-5: the paper's Ratio_1 (3.8, 8.2 %) is twice ours (1.9, 3.5 %); "
                                       "at equal acceleration its rows 1 and 5 disagree with each other; we suspect "
                                       "the paper (docs/validation.md)")
def test_table_5_rows_4_and_5_as_printed(table_5_rows):
    ours, paper = table_5_rows[("inverse", "peak")][:, 0], table_5_rows["paper"][:, 0]
    assert np.all(np.abs(ours - paper)[[3, 4]] <= 1.2)


def test_closed_loop_table_5_row_3_equals_the_inverse_model():
    """Row 3 through the whole co-simulation (drives closed, 0.2 ms): within 0.5 point of the
    inverse model's ratios (measured 0.2)."""
    rows = meng.surge_rows(meng.table_5(closed_loop=True, rows=[2])[1]["entries"])
    np.testing.assert_allclose(rows[("closed loop", "peak")], rows[("inverse", "peak")], atol=0.5)


def test_meng_scene_settles_and_shrugs_off_the_impact():
    """Fig 8: the start's torque shocks settle in about 0.15 s (ours within 0.2 s); the impact of
    Eq 36 moves the platform by under 10 um and 10 urad ('do not change at all') and its torque
    shock settles within 0.1 s after the load ends ('a short time')."""
    data = meng.tracking()[1]
    assert data["start_settling"] < 0.2
    assert data["pose_change"][:3].max() < 1e-5 and data["pose_change"][3:].max() < 1e-5
    assert 0.1 < data["impact_peak"] and data["impact_settling"] < 0.1


def test_sumnu_5_2_case_1_meets_every_bound_of_the_thesis():
    errors, bounds = sumnu.case_5_2("I")
    assert np.all(errors <= np.array(bounds)), errors


@pytest.mark.xfail(strict=True, reason="Sumnu 5.2 II: the thesis' 1e-6 rad yaw error at 0.35 rad, 3 rad/s needs a far "
                                       "stiffer loop than our 10 Hz default; its constants are unpublished")
def test_sumnu_5_2_case_2_meets_every_bound_of_the_thesis():
    errors, bounds = sumnu.case_5_2("II")
    assert np.all(errors <= np.array(bounds)), errors


def test_lower_part_inertia_matters_for_the_heavy_set_only():
    """Figs 4.4-4.5: the lower part's inertia changes the light set's peak leg force by under 15 %
    and the heavy set's by over 50 %."""
    data = sumnu.figures_4()[1]
    for figure, low, high in (("4.4", 0.0, 0.15), ("4.5", 0.5, 2.0)):
        _, excluded, included = data[figure]
        change = np.abs(included).max() / np.abs(excluded).max() - 1
        assert low <= change <= high, (figure, change)


def test_halder_platform_needs_more_than_the_papers_gains():
    """Our model of Halder's platform: the payload (centre of mass 0.285 m above the upper joints) is
    an inverted pendulum that k_p = 500 N/m per leg cannot hold (measured: 6x needed); a simple
    estimate of the two stiffnesses (559 against about 280 N m/rad) says the same."""
    assert halder.stability_threshold() >= 2.0


def test_halder_roll_step_reaches_its_demand_at_ten_times_the_gains():
    """At 10x the paper's gains the 15 deg roll step settles within 0.05 deg, and the coupled sway
    and heave stay below 0.1 mm per degree (the feedforward is the exact static inverse)."""
    rows = halder.run_case(halder.ROLL, 1)
    angle, sway, heave = halder.coupled_errors(rows, halder.ROLL, rows["pose.z"][0])
    assert abs(angle - 15.0) < 0.05
    assert abs(sway) / 15 < 0.1 and abs(heave) / 15 < 0.1


@pytest.mark.xfail(strict=True, reason="Halder Case 1: the paper's coupled errors (-3.5 mm/deg sway for roll) need "
                                       "a static mismatch between its inverse and forward models that it does not "
                                       "describe; ours has none (docs/validation.md)")
def test_halder_case_1_coupled_sway_as_the_paper():
    rows = halder.run_case(halder.ROLL, 1)
    _, sway, _ = halder.coupled_errors(rows, halder.ROLL, rows["pose.z"][0])
    assert sway / 15 == pytest.approx(-3.5, abs=1.0)


def test_halder_gains_read_per_millimetre_settle_in_about_a_second():
    """Read per millimetre (1000 x), the paper's gains hold the platform and settle the 15 deg roll
    step within 2 % in about 1 s, as the paper reports (measured 1.005 s at a 0.2 ms step)."""
    assert 0.8 < halder.per_millimetre_settling() < 1.2


def test_halder_stiffness_balance_explains_the_threshold():
    """The linearised static stiffness (PD legs against the loaded legs' geometric stiffness, an
    independent check of the simulated tipping): 385 N per leg; yaw alone needs 2.6x; positive
    definite from 4.6x the paper's gains (an independent linearisation found the same), so of the
    scales the simulation tries (1, 2, 4, 6, 8) the first that holds is 6."""
    balance = halder.stiffness_balance()
    assert balance["leg_force"] == pytest.approx(384.7, abs=0.5)
    assert balance["per_dof"][5] == pytest.approx(2.63, abs=0.05)
    assert balance["threshold"] == pytest.approx(4.56, abs=0.05)
    assert halder.stability_threshold() == 6.0
