"""Design results you can trust (cosim.platform.design): every row about a named design is that
design's on a grid that lacks it, the grid's own step and precision are the ones quoted, verdicts
follow the study's thresholds on both sides, the assumptions' effects are recomputed, the margins
are read as the study says, and no path leaks a numpy warning."""

from __future__ import annotations

import copy
import math
import warnings

import numpy as np
import pyarrow.csv
import pytest

from cosim.cli import main
from cosim.engine.artifacts import ROOT
from cosim.platform.core import Core
from cosim.platform.design import Study, design_map, load_study, platform_values
from cosim.platform.design.answer.assumptions import assumption_rows
from cosim.platform.design.answer.halder import paper_rows
from cosim.platform.design.search.map import along, at, limit_along
from cosim.platform.design.spec.study import Thresholds, allowed, decimals, stubs
from cosim.platform.design.spec.verdicts import SINGULAR, conditioning, near_singular
from cosim.platform.design.search.workspace import singular_distance

STUDY = ROOT / "studies" / "halder_section5.toml"
CHOSEN = {"base_radius": 1.1, "disc_height": 1.4}


@pytest.fixture(scope="module")
def study() -> Study:
    return load_study(STUDY)


def grid(study: Study, row_step: float, column_step: float) -> Study:
    """The study over a grid that holds neither r_b = 1.03 m nor 1.10 m, nor z_p0 = 1.40 m."""
    rows = np.round(1.005 + row_step * np.arange(int(0.2 / row_step) + 1), 10)
    columns = np.round(0.6005 + column_step * np.arange(int(1.0 / column_step) + 1), 10)
    assert not np.isclose(rows, 1.03).any() and not np.isclose(rows, 1.1).any() and not np.isclose(columns, 1.4).any()
    return study.with_axes({"base_radius": rows, "disc_height": columns})


def rows_by_name(rows: list) -> dict:
    return {row.quantity: row for row in rows}


@pytest.fixture(scope="module")
def odd(study):
    """paper_rows on a grid lacking the named designs (0.03 m by 0.0025 m), and its map."""
    part = grid(study, 0.03, 0.0025)
    design = design_map(part)
    return part, design, rows_by_name(paper_rows(design))


def test_every_row_about_the_chosen_design_is_that_design(odd, study):
    """On a grid without (1.10, 1.40): the verdict, the running lengths, the forces and the
    Jacobian are those of the design evaluated at exactly its values (a map of that one point)."""
    part, _, rows = odd
    exact = at(part, CHOSEN)
    s = stubs(part)
    lengths = rows["running lengths there, min / neutral / max"].ours
    assert lengths == " / ".join(f"{1e3 * v:.0f}" for v in (exact.actuated_length_min.min() + s,
                                                             exact.neutral_length[0, 0] + s,
                                                             exact.actuated_length_max.max() + s))
    assert rows["peak leg force there, payload only (Eq 16)"].ours == f"{exact.force_paper.max():.0f}"
    assert rows["the same with the legs' weight, inertia and friction"].ours == f"{exact.force_full.max():.0f}"
    jacobian = rows["leg Jacobian at r_b = 1.10 m, z_p0 = 1.40 m over the motions"].ours
    assert f"condition number {exact.condition.max():.1f}" in jacobian
    # the neutral running length at the paper's design is the paper's 1647 mm (the grid's nearest is not)
    assert lengths.split(" / ")[1] == "1647"


def test_the_highest_admissible_height_is_found_on_the_row_of_the_named_radius(odd):
    part, _, rows = odd
    verdict = rows[f"r_b = 1.10 m, z_p0 = 1.40 m with {part.actuators[1].name}"]
    highest = limit_along(along(part, 1.1), part.actuators[1], "max stroke", "heave")
    assert verdict.ours == "outside: max stroke in heave"
    assert f"is {highest:.4f} m (on the grid's 0.0025 m steps)" in verdict.note
    assert 1.36 < highest < 1.38  # between the 0.01 m grid's 1.37 and the next step


def test_the_papers_points_are_at_the_papers_radius_with_the_grids_step(odd):
    """Points a, b, c along r_b = 1.03 m exactly (the grid's rows skip it), printed to the grid's
    0.0025 m and quoting that step."""
    part, _, rows = odd
    line = along(part, 1.03)
    for label, constraint in (("a", "max stroke"), ("b", "min stroke"), ("c", "joint angle")):
        row = next(r for q, r in rows.items() if q.startswith(f"point {label}:"))
        found = limit_along(line, part.actuators[0], constraint, "sway")
        assert row.ours == f"{found:.4f}"
        assert row.note == "" or "the grid's step is 0.0025 m" in row.note


def test_numbers_print_with_the_precision_of_their_grid(study):
    assert (decimals(0.01), decimals(0.0005), decimals(0.25), decimals(1.0), decimals(0.1 + 0.2)) == (2, 4, 2, 0, 1)
    part = grid(study, 0.03, 0.0025)
    assert (part.decimals("base_radius"), part.decimals("disc_height")) == (3, 4)
    assert (part.step("base_radius"), part.step("disc_height")) == (0.03, 0.0025)


@pytest.mark.parametrize("mode, expected", [("subtract", 830 * (1 - 0.07 - 0.20)),
                                            ("product", 830 * 0.93 * 0.80),
                                            ("divide", 830 / 1.07 / 1.20)])
def test_the_force_margins_read_three_ways(mode, expected, study):
    """The paper's "keeping 7% margin for friction and another 20% for other factors" is 606 N of
    830 N (subtract, the default); the other readings are there to choose and to compare."""
    assert allowed(830.0, (0.07, 0.20), mode) == pytest.approx(expected, rel=1e-12)
    assert study.force_margins_mode == "subtract" and study.allowed_force(study.actuators[1]) == pytest.approx(605.9)


def test_conditioning_verdicts_follow_the_threshold_on_both_sides(study):
    condition = float(at(study, CHOSEN, dynamic=False).condition.max())
    below, above = (copy.copy(study) for _ in range(2))
    below.thresholds, above.thresholds = Thresholds(condition_number=condition * 0.99), Thresholds(condition * 1.01)
    assert conditioning(below, condition).startswith("ill conditioned")
    assert conditioning(above, condition).startswith("well conditioned")
    assert conditioning(study, math.inf).startswith("singular")


def test_a_singular_pose_is_near_by_the_studys_factor_on_both_sides(study):
    """At the chosen design the nearest singular roll lies about 68 deg from the neutral; the motion
    rolls 15 deg: near with a factor above 68/15, not with one below."""
    core = Core(actuators=False, motors=False, friction=False).use_start_values(platform_values(study, CHOSEN))
    distances = singular_distance(core, samples=401)
    ratio = distances["roll"] / study.motion.ranges["roll"]
    for factor, near in ((ratio * 0.99, False), (ratio * 1.01, True)):
        judged = copy.copy(study)
        judged.thresholds = Thresholds(singular_distance_factor=factor)
        assert near_singular(judged, distances)["roll"] is near
    assert not any(near_singular(study, distances).values())


def test_each_assumption_says_what_it_changes_at_the_chosen_design(study):
    """The rows recompute each alternative: the other margin readings' forces, the payload's
    parameter-set inertia (a larger roll force: more inertia to turn), the design height read as
    the centre of mass (the disc 0.2 m lower: shorter legs), the stubs (140 mm between the
    actuated and the running length)."""
    rows = assumption_rows(study)
    assert [r.quantity.split(" (judged")[0] for r in rows] == [
        "assumed: force margins 7% and 20% read as 'subtract'", "assumed: payload",
        "assumed: the design height z_p0 is the disc's (z_q0)", "assumed: the stubs between the joints and the actuator"]
    margins, payload, height, stub = rows
    assert margins.ours == "606" and "product 618 N, divide 646 N" in margins.note
    heavier = copy.copy(study)
    heavier.payload_inertia = (86.54, 86.54, 44.48)
    here, there = at(study, CHOSEN), at(heavier, CHOSEN)
    assert f"{here.force_paper.max():.0f} N (roll)" in payload.note
    assert f"{there.force_paper.max():.0f} N (roll)" in payload.note and there.force_paper.max() > here.force_paper.max()
    lower = at(study, {"base_radius": 1.1, "disc_height": 1.2}, dynamic=False)
    assert f"{1e3 * (lower.neutral_length[0, 0] + 0.14):.0f} mm" in height.note
    assert stub.ours == "140" and "1402 to 1909 mm" in stub.note and "1262 to 1769 mm" in stub.note


def test_a_family_without_stubs_lists_only_its_own_assumptions():
    meng = load_study(ROOT / "studies" / "meng_eq35_platform.toml")
    assert [r.quantity.split(" (")[0] for r in assumption_rows(meng)] == [
        "assumed: force margins 7% and 20% read as 'subtract'", "assumed: payload"]


def test_a_grid_through_a_singular_design_runs_without_a_numpy_warning(tmp_path, capsys):
    """Half pair angles 25-35 deg pass 30 deg, where both joint circles are regular hexagons one
    over the other (singular at the neutral): the map says so (a condition number beyond
    SINGULAR, not admissible), the command exits 0 and no warning escapes."""
    body = STUDY.read_text()
    body = body[:body.index("[axes]")] + ("[axes]\nhalf_pair_angle_deg = {from = 25, to = 35, step = 5}\n"
                                          "disc_height = {from = 1.2, to = 1.4, step = 0.2}\n") + \
        body[body.index("[motion]"):body.index("[workspace]")]
    body = body.replace("chosen = {base_radius = 1.1, disc_height = 1.4}",
                        "chosen = {half_pair_angle_deg = 25, disc_height = 1.4}")
    path = tmp_path / "singular.toml"
    path.write_text(body)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["design", str(path), "--out", str(tmp_path / "out")]) == 0
        design = design_map(load_study(path))
    assert (design.condition[1] > SINGULAR).all() and (design.condition[[0, 2]] < 100).all()
    assert not design.admissible(design.study.actuators[1])[1].any()
    assert "; 2 singular (above 1e+06: not admissible)" in capsys.readouterr().out


def test_the_maps_table_names_actuated_and_running_lengths(tmp_path, study):
    from cosim.platform.design import write
    part = study.with_axes({"base_radius": np.array([1.0, 1.1]), "disc_height": np.array([1.3, 1.4])})
    design = design_map(part)
    write(design, tmp_path, rows=[])
    table = pyarrow.csv.read_csv(tmp_path / f"{STUDY.stem}.csv").to_pydict()
    for end in ("min", "max"):
        running, actuated = np.array(table[f"running_length_{end}"]), np.array(table[f"actuated_length_{end}"])
        assert running - actuated == pytest.approx(stubs(study), abs=1e-12)
    assert "length_min" not in table
