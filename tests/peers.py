"""The third-party tools of ../shared/peers/ (its README): found beside the checkout, unpacked once
into build/peers/. A user's own clone has none, and a test that needs one says so and is
skipped; CI always has them, and there a missing peer fails the run."""

from __future__ import annotations

import os
import subprocess
import tarfile
from pathlib import Path

import numpy as np
import pytest

from cosim.engine.artifacts import BUILD_DIR, ROOT

PEERS = ROOT.parent / "shared" / "peers"
STRONGLY_COUPLED = "model_exchange"  # cosim.engine.ssp.StronglyCoupled.name: an export --me system's inner system


def _peer(archive_glob: str, suffix: str, binary: str, what: str) -> Path:
    """A peer's binary, its archive unpacked once into build/peers/ (skips the test without it)."""
    archives = sorted(PEERS.glob(archive_glob))
    if not archives:
        if os.environ.get("CI"):
            raise RuntimeError(f"no {what} in {PEERS}: CI always has it")
        pytest.skip(f"no {what} in {PEERS} (../shared/peers beside the checkout)")
    target = BUILD_DIR / "peers" / archives[-1].name.removesuffix(suffix)
    found = target / binary
    if not found.exists():
        target.mkdir(parents=True, exist_ok=True)
        with tarfile.open(archives[-1]) as archive:
            archive.extractall(target, filter="data")
    return found


def omsimulator() -> Path:
    """OMSimulator's command line, unpacked from the peers' archive (skips the test without it)."""
    return _peer("omsimulator-*-linux-x86_64.tar.xz", "-linux-x86_64.tar.xz", "omsimulator/bin/OMSimulator",
                 "OMSimulator")


def fmusim() -> Path:
    """Reference-FMUs' C fmusim (Linux), unpacked from the peers' archive (skips the test without it)."""
    return _peer("fmusim-*-x86_64.tar.xz", "-x86_64.tar.xz", "fmusim/bin/fmusim", "fmusim")


def run_omsimulator(archive: Path, signals: list[str], stop: float, folder: Path) -> dict[str, np.ndarray]:
    """OMSimulator's command line running `archive` (its fixed-step master at the step of the
    archive's annotation) to `stop`, recording `signals` (component.variable): a column each, by
    name, and "time", one row per communication point. Raises AssertionError with its log if it
    reports an error (its exit status is 0 even then)."""
    binary = omsimulator()
    result = folder / "omsimulator.csv"
    lines = [f'model, status = oms_importFile("{archive}")',
             f'oms_setResultFile(model, "{result}", 1000)',
             'oms_removeSignalsFromResults(model, ".*")',
             *[f'oms_addSignalsToResults(model, "^[^.]+\\\\.[^.]+\\\\.([^.]+\\\\.)?{_escaped(s)}$")' for s in signals],
             f"oms_setStopTime(model, {stop!r})",
             "oms_instantiate(model)", "oms_initialize(model)", "oms_simulate(model)", "oms_terminate(model)",
             "oms_delete(model)"]
    script = folder / "run.lua"
    script.write_text("\n".join(lines) + "\n")
    done = subprocess.run([str(binary), str(script)], capture_output=True, text=True, cwd=folder, timeout=1800)
    log = done.stdout + done.stderr
    assert done.returncode == 0 and "error:" not in log, log[-3000:]
    from pyarrow import csv
    table = csv.read_csv(result)
    inner = f"{STRONGLY_COUPLED}."  # a strongly coupled system's components sit one level deeper
    columns = {name.split(".", 2)[2].removeprefix(inner) if name != "time" else name:
               table[name].to_numpy().astype(float) for name in table.column_names}
    time = columns["time"]
    last = np.r_[np.diff(time) > 0, True]  # it writes a point twice (before and after its events): the later one
    return {name: values[last] for name, values in columns.items()}


def _escaped(signal: str) -> str:
    out = ""
    for c in signal:
        out += "\\\\" + c if c in ".[]()" else c
    return out
