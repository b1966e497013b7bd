"""A command loads what it needs and no more: `cosim --help` and a run without plots never import
the plotting, parallel or optimisation libraries (matplotlib, plotly, Dask and its scheduler
tornado, pymoo, pyarrow, pandas, clarabel), which cost a run without them most of its start-up, nor a run
that streams and listens to nothing the networking (socket); `cosim --help` not even the engine's
numerics and FMI (numpy, scipy, fmpy, lxml: the package's names load on first use)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("matplotlib", "plotly", "dask", "distributed", "tornado", "pymoo", "pyarrow", "pandas", "clarabel")
LOADED = """
import json, sys
from cosim.cli import main
try:
    code = main(sys.argv[1:])
except SystemExit as done:  # --help
    code = done.code
print(json.dumps({"code": code, "modules": sorted({m.split(".")[0] for m in sys.modules})}))
"""


@pytest.mark.parametrize("command", [["--help"], ["run", "meng_eq35", "--no-plots", "--duration", "0.02"]],
                         ids=["help", "run --no-plots"])
def test_a_command_imports_only_what_it_needs(tmp_path, command):
    arguments = [*command, *(["--out", str(tmp_path)] if command[0] == "run" else [])]
    done = subprocess.run([sys.executable, "-c", LOADED, *arguments], capture_output=True, text=True, cwd=tmp_path,
                          timeout=300)
    found = json.loads(done.stdout.strip().splitlines()[-1])
    assert found["code"] == 0, done.stderr
    assert "cosim" in found["modules"]
    needless = set(HEAVY) | {"socket"} | ({"numpy", "scipy", "fmpy", "lxml"} if command == ["--help"] else set())
    assert not needless & set(found["modules"]), needless & set(found["modules"])
    assert command == ["--help"] or {"numpy", "fmpy"} <= set(found["modules"])  # a run does load what it needs


def test_a_run_with_plots_loads_the_plotting_it_needs(tmp_path):
    """The other side: a run with plots does load matplotlib (so the check above can fail)."""
    done = subprocess.run([sys.executable, "-c", LOADED, "run", "meng_eq35", "--duration", "0.02", "--out",
                           str(tmp_path)], capture_output=True, text=True, cwd=tmp_path, timeout=300)
    found = json.loads(done.stdout.strip().splitlines()[-1])
    assert found["code"] == 0 and "matplotlib" in found["modules"], done.stderr


def test_a_streaming_run_loads_the_networking_it_needs(tmp_path):
    """And a run that streams its samples does load socket (so the check above can fail)."""
    done = subprocess.run([sys.executable, "-c", LOADED, "run", "meng_eq35", "--no-plots", "--duration", "0.02",
                           "--stream", "udp://127.0.0.1:9", "--out", str(tmp_path)], capture_output=True, text=True,
                          cwd=tmp_path, timeout=300)
    found = json.loads(done.stdout.strip().splitlines()[-1])
    assert found["code"] == 0 and "socket" in found["modules"], done.stderr
