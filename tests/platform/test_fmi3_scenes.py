"""Every shipped scene on our FMI 3.0 FMUs (scene.fmi = 3) at its defaults holds the shipped scenes'
tolerances over its probe against its converged run (the scene on the FMI 2.0 FMUs, the same
models, at a 16th of its step): FMI 3.0 FMUs take no input derivatives, so each extrapolates its
inputs itself (fmi.extrapolate_inputs) and the fixed step is 1/FMI3_REFINE of the scene's.
(On FMI 3.0 FMUs that held their inputs at the step's midpoint, as before, the Meng scene was 1 mm
and 1357 times its efforts' tolerance off at its step, and still 87 times at an eighth of it.)"""

from __future__ import annotations

import pytest

import cosim
from cosim.engine.artifacts import ROOT
from cosim.platform.run.accuracy import judge, probe_duration
from cosim.platform.run.portable import converged
from cosim.platform.run.runner import run_scene
from cosim.platform.scene.reader import FMI3_REFINE

SCENES = sorted(p.stem for p in (ROOT / "scenes").glob("*.toml"))


@pytest.mark.parametrize("name", SCENES)
def test_a_shipped_scene_on_fmi3_fmus_holds_its_tolerances_at_its_defaults(name):
    scene = cosim.load(name, {"scene.fmi": 3})
    assert scene.step == pytest.approx(cosim.load(name).step / FMI3_REFINE, rel=1e-12)
    duration = probe_duration(scene)
    result, report = run_scene(scene.changed({"scene.duration": duration}))
    judgement = judge(scene, result, converged(scene, duration))
    assert judgement.within, judgement
    assert any(remark.startswith("FMI 3.0: the FMUs take no input derivatives") for remark in report.remarks)
