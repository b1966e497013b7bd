"""The platform in 3D (cosim.platform.report.view3d): drawn from the platform the mechanics FMU builds,
so every layout draws right; legs marked out of stroke exactly when the mechanics' log says they
leave it; and in headless Chromium (offline, WebGL through the software renderer) the slider puts
the platform at the pose the results hold at that time, read back from what was drawn."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from cosim.cli import main
from cosim.engine.artifacts import ROOT
from cosim.platform.report import view3d
from cosim.platform.scene.parameter_sets import mechanics_start_values, scene_mechanics
from cosim.platform.core import Core
from cosim.platform.ports import POSE
from cosim.platform.run.compile import scene_values
from cosim.platform.run.runner import run_scene
from cosim.platform.scene import load_scene
from test_html_report import CHROMIUM, chromium


@pytest.mark.parametrize("parameter_set", ["meng2010", "sumnu2015", "halder2013"])
def test_every_layout_draws_the_platform_the_fmu_simulates(parameter_set):
    """The drawn legs (lower joint to the drawn upper joint) at random poses around the neutral
    one are as long as the dynamics core's legs there (the FMU's own mapping; its lengths and the
    drawn joints come from two of its functions): Meng's radii and spacings, Sumnu's and Halder's
    explicit joints."""
    values = scene_mechanics(parameter_set) if parameter_set != "halder2013" else mechanics_start_values(parameter_set)
    geometry, core = view3d.Geometry.of(values), Core().use_start_values(values)
    rng = np.random.default_rng(3)
    poses = core.neutral_pose + rng.uniform(-1, 1, (20, 6)) * [0.05, 0.05, 0.05, 0.05, 0.05, 0.05]
    drawn = view3d.frames(geometry, np.arange(20.0), poses, None)
    np.testing.assert_allclose(np.linalg.norm(drawn.top - geometry.lower, axis=2), [core.leg_lengths(p) for p in poses],
                               rtol=1e-12)
    np.testing.assert_allclose(drawn.length, [core.leg_lengths(p) for p in poses], rtol=1e-12)


@pytest.fixture(scope="module")
def meng_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("view")
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml", {"scene.duration": 3.0})
    result, report = run_scene(scene, out, plots=True)
    return scene, result, report, out


def test_legs_are_out_of_stroke_exactly_when_the_log_says(meng_run):
    """At every recorded row, a leg is marked out of stroke where its length (from the recorded
    pose) is outside the stroke; the first row marked is the step at whose end the mechanics
    logged that the leg left it."""
    scene, result, _, out = meng_run
    geometry = view3d.Geometry.of(scene_values(scene)[0])
    pose = np.column_stack([result[f"pose.{a}"] for a in POSE])
    marked = view3d.frames(geometry, result["time"], pose, None).out_of_stroke
    logged = {}
    for line in (out / "meng_eq35.log").read_text().splitlines():
        found = re.search(r"t = ([0-9.]+) s: leg (\d) length [0-9.]+ m is outside the stroke", line)
        if found:
            logged.setdefault(int(found.group(2)), float(found.group(1)))
    assert logged  # Eq 35 takes legs past the stroke within 3 s
    for leg, t in logged.items():
        assert result["time"][np.argmax(marked[:, leg - 1])] == pytest.approx(t, abs=1e-9), leg
    for leg in set(range(1, 7)) - set(logged):
        assert not marked[:, leg - 1].any()


PROBE = """<pre id="probe"></pre><script>
window.addEventListener('load', function () {
  var view = document.getElementById('platform-view');
  window.platformView.show(%(t)r);
  setTimeout(function () {
    var d = view.data;
    document.getElementById('probe').textContent = JSON.stringify({
      platform: [d[7].x, d[7].y, d[7].z], legs: [1, 2, 3, 4, 5, 6].map(function (k) { return d[k].line.color; }),
      frames: view._transitionData._frames.length});
  }, 500);
});
</script></body>"""


@pytest.mark.skipif(CHROMIUM is None, reason="no chromium (scripts/test.sh installs it)")
def test_the_slider_puts_the_platform_at_the_recorded_pose(meng_run, tmp_path):
    scene, result, _, out = meng_run
    t = 2.5
    page = tmp_path / "probe.html"
    page.write_text((out / "meng_eq35.html").read_text().replace("</body>", PROBE % {"t": t}, 1))
    run = chromium(page, tmp_path, "--dump-dom", "--enable-unsafe-swiftshader")
    drawn = json.loads(re.search(r'<pre id="probe">(.*?)</pre>', run.stdout, re.S).group(1).replace("&quot;", '"'))
    geometry, frames = view3d.run_frames(scene_values(scene)[0], result, scene.pulses)
    k = int(np.argmin(np.abs(frames.time - t)))
    expected = np.vstack([frames.top[k], frames.top[k][:1]])
    np.testing.assert_allclose(np.array(drawn["platform"]).T, expected, atol=1e-4)  # drawn to 0.1 mm
    red = [color == "#e60000" for color in drawn["legs"]]
    assert red == frames.out_of_stroke[k].tolist()
    assert drawn["frames"] == len(frames.time) <= view3d.MAX_FRAMES
    console = [line for line in run.stderr.splitlines() if ":CONSOLE" in line]
    assert not [line for line in console if re.search(r"error|uncaught|failed", line, re.I)], console


def test_view_shows_the_reference_motion_without_a_co_simulation(tmp_path, capsys):
    """`python -m cosim view SCENE`: a self-contained page and, per leg, the range of its length
    against the stroke (Eq 35 takes legs past Meng's 2.2 m)."""
    assert main(["view", str(ROOT / "scenes" / "meng_eq35.toml"), "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "stroke [1.535, 2.2] m" in out and re.search(r"leg 4: [0-9.]+ to 2\.2\d+ m ", out)
    assert re.search(r"leg 4 past the stroke's top from t = [0-9.]+ to [0-9.]+ s \([0-9.]+ s\), at most 2\.2\d+ m", out)
    text = (tmp_path / "meng_eq35_view.html").read_text()
    assert 'id="platform-view"' in text and not re.search(r'<(script|link|img)[^>]+(src|href)="https?://', text)
    assert main(["view", str(ROOT / "scenes" / "sumnu_case_1.toml"), "--out", str(tmp_path)]) == 0


def test_view_refuses_a_step_longer_than_the_scene_in_one_line(tmp_path, capsys):
    """A macro step longer than the scene's duration runs nothing: `view` refuses it at the key's
    line as `run` does, one line, exit 2 (CI's input fuzzer found view's ZeroDivisionError)."""
    scene = tmp_path / "scene.toml"
    scene.write_text((ROOT / "scenes" / "meng_eq35.toml").read_text().replace("step = 1e-3", "step = 1e300", 1))
    assert "step = 1e300" in scene.read_text()
    assert main(["view", str(scene), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'scene.step' = 1e+300: is longer than the scene's duration" in err, err
    assert err.startswith(f"error: {scene}:")
