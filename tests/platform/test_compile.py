"""A scene is compiled once per run: `cosim run` opens each parameter file it reads once, and the
compiled scene is what the run's system and plan are made of."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

import cosim
from cosim.engine.artifacts import ROOT
from cosim.platform.run.compile import compile_scene, scene_record, scene_values
from cosim.platform.scene import load_scene

# counts, in a fresh process (parameter sets are read once per process), every file opened under
# params/ from the command line's start to its end, through Python's audit hook of `open`
COUNT_OPENS = """
import collections, json, sys
opened = collections.Counter()
def hook(event, args):
    if event == "open" and isinstance(args[0], str) and "/params/" in args[0]:
        opened[args[0].rsplit("/", 1)[1]] += 1
sys.addaudithook(hook)
from cosim.cli import main
code = main(sys.argv[1:])
print(json.dumps({"code": code, "opened": opened}))
"""


@pytest.mark.parametrize("scene, files", [  # each with the envelope's margins (params/envelope.toml)
    ("scenes/meng_eq35.toml", {"meng2010.toml", "envelope.toml"}),
    ("scenes/sumnu_case_1_pmsm.toml", {"sumnu2015.toml", "sumnu2015_pmsm.toml", "envelope.toml"}),  # and a drive set
    ("examples/vehicle/car_drive.toml", {"meng2010.toml", "envelope.toml"}),  # through motion cueing
])
def test_a_run_opens_each_parameter_file_once(tmp_path, scene, files):
    """The whole command, with its plots and interactive report: reading the scene, designing
    the drives, wiring, running, reporting."""
    done = subprocess.run([sys.executable, "-c", COUNT_OPENS, "run", str(ROOT / scene), "--duration", "0.02",
                           "--out", str(tmp_path)], capture_output=True, text=True, cwd=tmp_path, timeout=300)
    found = json.loads(done.stdout.strip().splitlines()[-1])
    assert found["code"] == 0, done.stderr
    assert found["opened"] == {name: 1 for name in files}, found["opened"]


def test_the_plan_is_made_of_the_compiled_scene():
    """The plan runs the compiled system, records what the scene records, and the drives' values
    in the system are the compiled legs' (designed once: a swapped drive, tuning = "auto")."""
    scene = load_scene(ROOT / "scenes" / "sumnu_case_1_pmsm.toml")
    compiled = compile_scene(scene)
    assert compiled.scene.tuning == "auto" and compiled.tuning is not None
    assert compiled.plan.structure is compiled.structure
    assert (list(compiled.plan.record), list(compiled.plan.names)) == tuple(map(list, scene_record(scene)))
    assert compiled.mechanics == scene_values(scene)[0]
    drives = [c for c in compiled.structure.components if c.name.startswith("pmsm")]
    assert len(drives) == 6
    for drive, leg in zip(drives, compiled.legs):
        assert all(drive.parameters[k] == v for k, v in leg.items()), drive.name


def test_every_report_names_what_was_run(tmp_path):
    """The scene's name says six PMSM drives; run on linear motors, the headline, the HTML report's
    title say so (the drive set too; the PNG plots take the same label), and a cueing scene names its
    cueing."""
    from cosim.platform.run.compile import run_label
    run = cosim.simulate("meng_eq35", duration=0.05, overrides={"drive.kind": "linear"}, out=tmp_path, plots=True)
    headline = run.report.text().splitlines()[0]
    assert headline.startswith("Meng 2010: Eq 35 with the impact of Eq 36, six PMSM drives [run: meng2010, linear "
                               "motors (meng2010_linear)]:")
    page = (tmp_path / "meng_eq35.html").read_text()
    assert "<h1>Meng 2010: Eq 35 with the impact of Eq 36, six PMSM drives [run: meng2010, linear motors" in page
    cueing = load_scene(ROOT / "examples" / "vehicle" / "car_drive.toml", {"cueing.algorithm": "mpc"})
    assert run_label(cueing).endswith("[run: meng2010, PMSM drives, mpc cueing of drive.csv]")
    assert "sumnu2015, heavy masses, linear motors" in run_label(load_scene("sumnu_case_1"))
