"""The interactive run report (out/<scene>.html) in headless Chromium (Debian's chromium, which
scripts/test.sh installs): offline (every network request goes to a dead proxy, so a fetch would
show as a console error), no console errors, every plot rendered, a screenshot that is not blank,
and the numbers on the page equal the run's."""

from __future__ import annotations

import html
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

from cosim.engine.artifacts import ROOT
from cosim.platform.run.runner import run_scene
from cosim.platform.scene import load_scene

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
if CHROMIUM is None and os.environ.get("CI"):
    raise RuntimeError("chromium is missing: scripts/test.sh installs Debian's chromium for this test")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="no chromium (scripts/test.sh installs it)")

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--proxy-server=127.0.0.1:9", "--enable-logging=stderr", "--v=0", "--virtual-time-budget=20000"]


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml", {"scene.duration": 3.0})
    result, report = run_scene(scene, out, plots=True)
    return out / "meng_eq35.html", report, result, out


def chromium(page, tmp_path, *arguments) -> subprocess.CompletedProcess:
    return subprocess.run([CHROMIUM, *FLAGS, f"--user-data-dir={tmp_path / 'profile'}", *arguments,
                           page.as_uri()], capture_output=True, text=True, timeout=120)


def test_the_report_loads_offline_without_console_errors_and_renders_every_plot(page, tmp_path):
    path, report, result, _ = page
    text = path.read_text()
    assert not re.search(r'<(script|link|img)[^>]+(src|href)="https?://', text)  # nothing to fetch
    run = chromium(path, tmp_path, "--dump-dom")
    console = [line for line in run.stderr.splitlines() if ":CONSOLE" in line]
    errors = [line for line in console if re.search(r"error|uncaught|failed", line, re.I)]
    assert not errors, errors
    figures = text.count('<section class="plot">')
    assert figures == 6 + 6 + 3  # pose and error per DOF; torque, speed and i_q of the six drives
    assert run.stdout.count('class="plot-container plotly"') == figures + 1  # plotly drew each, and the 3D view
    assert run.stdout.count('class="main-svg"') >= figures


def test_the_screenshot_is_not_blank(page, tmp_path):
    import matplotlib.image
    path, *_ = page
    shot = tmp_path / "shot.png"
    chromium(path, tmp_path, "--window-size=1200,2400", f"--screenshot={shot}")
    pixels = matplotlib.image.imread(shot)[..., :3]
    ink = (pixels.mean(axis=2) < 0.9).mean()
    assert ink > 0.03 and pixels.std() > 0.05, (ink, pixels.std())


def test_the_numbers_on_the_page_are_the_runs(page):
    path, report, result, out = page
    values = {html.unescape(name): html.unescape(value)
              for name, value in re.findall(r'data-name="([^"]*)" data-value="([^"]*)"', path.read_text())}
    assert int(values["macro steps"]) == report.macro_steps == len(result) - 1
    assert float(values["real-time factor"]) == report.real_time_factor
    assert float(values["largest energy residual of a bond in one step [J]"]) == report.largest_energy_residual
    for a, error in zip(("x", "y", "z", "roll", "pitch", "yaw"), report.largest_error):
        unit = "m" if a in "xyz" else "rad"
        assert float(values[f"largest tracking error {a} [{unit}]"]) == float(error)
    bonds = [float(v) for k, v in values.items() if k.startswith("bond ")]
    assert len(bonds) == 6 and max(bonds) == report.largest_energy_residual
    warnings = path.read_text().count("<tr><td>") - 0
    assert f"Warnings and errors from the FMUs ({len(report.warnings)})" in path.read_text()
    assert warnings >= len(report.warnings)
    assert np.isfinite(bonds).all()


def test_a_failed_run_says_where_and_why_it_stopped(tmp_path):
    from cosim.engine.outcome import RunStopped
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml", {"scene.duration": 1.0,
                                                           'mechanics.parameters."limit.hard_stop"': True})
    with pytest.raises(RunStopped):
        run_scene(scene, tmp_path / "out", plots=True)
    page = (tmp_path / "out" / "meng_eq35.html").read_text()
    assert '<div class="failure" data-name="failure"><h2>The run stopped</h2>' in page
    assert "mechanics: fmi2DoStep failed at t = 0.63" in page and "stroke" in page
