"""Every shipped scene on our FMI 3.0 FMUs (scene.fmi = 3) runs as on the FMI 2.0 FMUs, bit for
bit, at the scene's own step: FMI 3.0 has no input derivatives, so our FMI 3.0 FMUs take each
input's rate and curvature as inputs of their own (fmi.rate.<input>, fmi.curvature.<input>), which
the master sets where it would call fmi2SetRealInputDerivatives. (Before, FMI 3.0 FMUs that
extrapolated their inputs themselves needed an eighth of the scene's step to hold its tolerances:
8 times the macro steps.)"""

from __future__ import annotations

import numpy as np
import pytest

import cosim
from cosim.engine.artifacts import ROOT
from cosim.platform.run.accuracy import probe_duration
from cosim.platform.run.runner import run_scene

SCENES = sorted(p.stem for p in (ROOT / "scenes").glob("*.toml"))


@pytest.mark.parametrize("name", SCENES)
def test_a_shipped_scene_on_fmi3_fmus_is_its_fmi2_run_bit_for_bit(name):
    fmi2 = cosim.load(name)
    fmi3 = fmi2.changed({"scene.fmi": 3})
    assert fmi3.step == fmi2.step  # the scene's own step: no refinement
    duration = probe_duration(fmi2)
    (ours, report), (theirs, _) = (run_scene(s.changed({"scene.duration": duration})) for s in (fmi3, fmi2))
    assert ours.dtype.names == theirs.dtype.names and len(ours) == len(theirs)
    for column in ours.dtype.names:
        assert np.array_equal(ours[column], theirs[column]), column
    assert fmi2.algorithm.order == 0 or any(r.startswith("FMI 3.0: FMI 3.0 has no input derivatives; the master gives "
                                                         "each input's rate") for r in report.remarks)
