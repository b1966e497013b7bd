"""The documentation site builds with warnings as errors (mkdocs --strict: every link between the
pages resolves, the README's links into docs/ included, and the API reference is generated from
the docstrings of cosim.api)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_the_site_builds_clean_with_the_api_reference(tmp_path):
    mkdocs = Path(sys.executable).parent / "mkdocs"
    run = subprocess.run([str(mkdocs), "build", "--strict", "-d", str(tmp_path / "site")], cwd=ROOT,
                         capture_output=True, text=True, timeout=300, env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert run.returncode == 0, run.stderr
    api = (tmp_path / "site" / "api" / "index.html").read_text()
    for name in ("simulate", "export_ssp", "sweep", "advise", "RunStopped"):
        assert name in api, name
    home = (tmp_path / "site" / "index.html").read_text()
    assert "In Python" in home and 'href="guide/scenes/"' in home  # the README, its links made the site's
