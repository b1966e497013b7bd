"""A scene is compiled once per run: `cosim run` opens each parameter file it reads once, and the
compiled scene is what the run's system and plan are made of."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

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
