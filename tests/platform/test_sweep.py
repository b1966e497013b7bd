"""Sweeps on Dask (cosim.engine.sweep, cosim.platform.run.sweep): the same rows on a cluster as in one
process, bit for bit; a real scheduler and workers started as separate processes; failing points
as rows; a killed worker and an interrupted sweep that lose and repeat nothing; one-line errors
for a bad sweep file."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from cosim.cli import main
from cosim.engine.artifacts import ROOT
from cosim.engine.sweep import Axis, SweepError, grid, latin_hypercube, run_sweep, zipped
from cosim.platform.run.sweep import load_sweep

SCENE = ROOT / "scenes" / "meng_eq35.toml"
# the numerics the studies below count their steps at, whatever the shipped scene's (a sweep file's set)
FIXED = {"coupling.interface_jacobian": False, "coupling.startup_time": 0.1, "coupling.startup_step": 1.25e-4,
         "coupling.edge_time": 0.0}
FIXED_TOML = "set = { " + ", ".join(f'"{k}" = {str(v).lower()}' for k, v in FIXED.items()) + " }"


def sweep_file(folder: Path, axes: str, duration: float = 0.2, extra: str = "", report: str = "") -> Path:
    path = folder / "study.toml"
    path.write_text(f'[sweep]\nscene = "{SCENE}"\nduration = {duration}\n{FIXED_TOML}\n{extra}\n{axes}\n'
                    + (report or '[report]\nvalues = ["tracking_error", "peak_effort", "energy_residual", "steps"]\n'
                                 'outputs = { "pose.z" = ["max", "rms"] }\n'))
    return path


STEP_AND_ORDER = ('[[axis]]\nkey = "scene.step"\nvalues = [5e-4, 1e-3]\n'
                  '[[axis]]\nkey = "coupling.order"\nvalues = [0, 1]\n')


def comparable(rows: list[dict]) -> list[dict]:
    """The rows without their wall times (the only column that may differ between runs)."""
    return [{k: v for k, v in row.items() if k not in ("wall", "real_time_factor")} for row in rows]


def in_process(path: Path, out: Path) -> list[dict]:
    sweep = load_sweep(path)
    return run_sweep(sweep.name, sweep.points, sweep.evaluate, sweep.columns, out, sweep.signature, workers=0,
                     progress=False).rows


def test_points_are_drawn_as_the_file_says():
    a, b = Axis("a", (1, 2, 3)), Axis("b", (10.0, 20.0))
    assert grid([a, b]) == [{"a": x, "b": y} for x in (1, 2, 3) for y in (10.0, 20.0)]
    assert zipped([Axis("a", (1, 2)), Axis("b", (3, 4))]) == [{"a": 1, "b": 3}, {"a": 2, "b": 4}]
    with pytest.raises(SweepError):
        zipped([a, b])
    axes = [Axis("x", between=(0.0, 1.0)), Axis("y", between=(-5.0, 5.0))]
    sample = latin_hypercube(axes, 16, seed=7)
    assert sample == latin_hypercube(axes, 16, seed=7) != latin_hypercube(axes, 16, seed=8)
    for axis in axes:  # each of the 16 equal strata of every axis is hit exactly once
        low, high = axis.between
        strata = sorted(int((p[axis.name] - low) / (high - low) * 16) for p in sample)
        assert strata == list(range(16))


def test_a_sweep_on_a_local_cluster_gives_the_rows_of_the_same_points_run_in_one_process(tmp_path):
    path = sweep_file(tmp_path, STEP_AND_ORDER)
    reference = in_process(path, tmp_path / "here")
    assert main(["sweep", str(path), "--workers", "2", "--out", str(tmp_path / "cluster")]) == 0
    rows = pq.read_table(tmp_path / "cluster" / "study.parquet").to_pylist()
    assert len(rows) == 4 and all(r["status"] == "ok" for r in rows)
    assert comparable(rows) == comparable(reference)  # bit for bit: floats compared exactly
    # the step is the macro step: 0.2 s at 0.5 ms is 400 steps, the first 0.1 s of them at the scene's
    # finer start (an eighth of 1 ms: 4 per 0.5 ms step); and the CSV holds the same table
    assert [r["steps"] for r in rows] == [800 + 200, 800 + 200, 800 + 100, 800 + 100]
    csv = np.genfromtxt(tmp_path / "cluster" / "study.csv", delimiter=",", names=True, dtype=None, encoding=None)
    assert np.array_equal(csv["maxposez"], [r["max.pose.z"] for r in rows])
    # a point's reports are those of the scene run on its own
    from cosim.platform.run.runner import run_scene
    from cosim.platform.scene import load_scene
    result, report = run_scene(load_scene(SCENE, {**FIXED, "scene.duration": 0.2, "scene.step": 1e-3,
                                                  "coupling.order": 1}))
    point = next(r for r in rows if r["scene.step"] == 1e-3 and r["coupling.order"] == 1)
    assert point["tracking_error.z"] == report.largest_error[2]
    assert point["peak_effort[3]"] == np.abs(result["torque[3]"]).max()


def test_failing_points_are_rows_with_their_messages_and_the_sweep_goes_on(tmp_path):
    axes = ('[[axis]]\nkey = "scene.step"\nvalues = [1e-3, 2.5e-3]\n'
            '[[axis]]\nkey = \'drive.parameters."motor.resistance"\'\nvalues = [0.7, -0.7]\n')
    rows = in_process(sweep_file(tmp_path, axes, duration=0.5, report='[report]\nvalues = ["steps"]\n'),
                      tmp_path / "out")
    status = {(r["scene.step"], r["drive.parameters.motor.resistance"]): (r["status"], r["message"]) for r in rows}
    assert status[(1e-3, 0.7)] == ("ok", "")
    assert status[(2.5e-3, 0.7)][0] == "diverged" and "diverged" in status[(2.5e-3, 0.7)][1]
    for step in (1e-3, 2.5e-3):  # a value the FMU's modelDescription refuses: the point's row says why
        kind, message = status[(step, -0.7)]
        assert kind == "failed" and "motor.resistance" in message and "outside" in message, message


def test_a_bad_sweep_file_is_one_line_naming_its_line(tmp_path, capsys):
    cases = {
        '[sweep]\nscene = "SCENE"\nstepp = 1\n[[axis]]\nkey = "scene.step"\nvalues = [1e-3]\n': ":3: 'sweep.stepp'",
        '[sweep]\nscene = "SCENE"\n[[axis]]\nkey = "scene.stepp"\nvalues = [1e-3]\n': ":4: 'axis[1].key' = 'scene.stepp':",
        '[sweep]\nscene = "SCENE"\n[[axis]]\nkey = "scene.step"\n': ":3: 'axis[1]' needs one of",
        '[sweep]\nscene = "SCENE"\n[[axis]]\nkey = "scene.step"\nvalues = ["fast"]\n': ":4: 'axis[1].key' = 'scene.step': with the value 'fast'",
        '[sweep]\nscene = "SCENE"\n[[axis]]\nkey = "x"\nbetween = [0, 1]\n': ":5: 'axis[1].between' = [0, 1]: is for sample",
        '[sweep]\nscene = "nowhere.toml"\n[[axis]]\nkey = "scene.step"\nvalues = [1e-3]\n': ":2: 'sweep.scene'",
        '[sweep]\nscene = "SCENE"\n[[axis]]\nkey = "scene.step"\nvalues = [1e-3]\n[plot]\nreport = "torque"\nx = '
        '"scene.step"\n': ":7: 'plot.report' = 'torque': is not a column",
        '[sweep]\nscene = "SCENE"\n[[axis]]\nkey = "scene.step"\nvalues = [1e-3]\n[report]\noutputs = { "pose.z" = '
        '["median"] }\n': ":7: 'report.outputs'",
        '[sweep]\nscene = "SCENE"\n[[axis]]\nkey = "scene.step"\nvalues = [1e-3]\n[report]\noutputs = { "pose.q" = '
        '["max"] }\n': ":7: 'report.outputs' names 'pose.q', which the run does not record (did you mean",
        '[sweep]\nscene = "SCENE"\nset = 3\n[[axis]]\nkey = "scene.step"\nvalues = [1e-3]\n': ":3: 'sweep.set' = 3: must be a "
        "table",
        '[sweep]\nscene = "SCENE"\nset = { "coupling.order" = 7 }\n[[axis]]\nkey = "scene.step"\nvalues = [1e-3]\n':
        ":3: 'sweep.set': the sweep's target cannot run as it is: 'coupling.order' = 7: must be a whole number in [0, 2]",
    }
    for number, (text, expected) in enumerate(cases.items()):
        path = tmp_path / f"bad{number}.toml"
        path.write_text(text.replace("SCENE", str(SCENE)))
        assert main(["sweep", str(path), "--workers", "0", "--out", str(tmp_path / "out")]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and f"{path}{expected}" in err, (text, err)
    assert not (tmp_path / "out").exists()  # nothing ran, nothing written


def _wait_for_parts(folder: Path, count: int, process: subprocess.Popen, timeout: float = 60.0) -> None:
    start = time.time()
    while len(list(folder.glob("part-*.parquet"))) < count:
        assert process.poll() is None, process.communicate()
        assert time.time() - start < timeout
        time.sleep(0.05)


EIGHT_POINTS = '[[axis]]\nkey = "scene.step"\nvalues = [4e-4, 5e-4, 6e-4, 7e-4, 8e-4, 9e-4, 1e-3, 1.1e-3]\n'


def test_an_interrupted_sweep_resumes_losing_and_repeating_nothing(tmp_path):
    path = sweep_file(tmp_path, EIGHT_POINTS, duration=0.5, extra="points_per_task = 1")
    reference = in_process(path, tmp_path / "reference")
    out = tmp_path / "out"
    command = [sys.executable, "-m", "cosim", "sweep", str(path), "--workers", "0", "--out", str(out)]
    # Ctrl-C's default action in the sweep (a shell that starts a job in the background, as a CI
    # runner may, leaves SIGINT ignored in it and its children)
    process = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    _wait_for_parts(out / "study.parts", 2, process)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130 and "run the same command again" in err, err
    done = len(list((out / "study.parts").glob("part-*.parquet")))
    assert 2 <= done < 8
    again = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    assert f"{done} of 8 points already in" in again.stderr and f"({8 - done} run now, {done} found done)" in again.stdout
    rows = pq.read_table(out / "study.parquet").to_pylist()
    assert comparable(rows) == comparable(reference)  # every point once, none lost, none run twice
    assert len(list((out / "study.parts").glob("part-*.parquet"))) == 8
    csv_rows = (out / "study.csv").read_text().strip().splitlines()
    assert len(csv_rows) == 9  # header and each point once
    # a changed scene duration is another sweep: refused, the old results kept
    path.write_text(path.read_text().replace("duration = 0.5", "duration = 0.4"))
    failed = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert failed.returncode == 2 and "holds the results of another sweep" in failed.stderr
    assert len(list((out / "study.parts").glob("part-*.parquet"))) == 8


@contextmanager
def dask_processes(folder: Path, workers: int, options: tuple[str, ...] = ()):
    """A scheduler and `workers` workers on 127.0.0.1, each its own process started by the `dask`
    command in `folder` (their cache there), as on a cluster; yields the scheduler's address and the
    processes (the scheduler's first)."""
    import json
    dask = str(Path(sys.executable).parent / "dask")
    env = {**os.environ, "PYTHONPATH": str(ROOT), "COSIM_CACHE_DIR": str(folder / "cache")}
    protocol = ["--protocol", "tls"] if options else []
    processes = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", "0", *protocol, "--no-dashboard",
                                   "--scheduler-file", "scheduler.json", *options], cwd=folder, env=env,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        start = time.time()
        while not (folder / "scheduler.json").exists():
            assert time.time() - start < 60, "the scheduler did not start"
            time.sleep(0.1)
        address = json.loads((folder / "scheduler.json").read_text())["address"]
        for _ in range(workers):
            processes.append(subprocess.Popen([dask, "worker", address, "--nthreads", "1", "--nworkers", "1",
                                               "--no-dashboard", "--host", "127.0.0.1", *options], cwd=folder, env=env,
                                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        yield address, processes
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in processes:
            try:
                process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                process.kill()


@pytest.fixture(scope="module")
def dask_cluster(tmp_path_factory):
    """A scheduler and two workers started as separate processes."""
    folder = tmp_path_factory.mktemp("dask")
    with dask_processes(folder, 2) as (address, processes):
        from distributed import Client
        with Client(address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=60)
        yield address, processes, folder / "cache"


def test_a_sweep_on_a_scheduler_and_workers_started_as_separate_processes(tmp_path, dask_cluster):
    address, _, _ = dask_cluster
    path = sweep_file(tmp_path, STEP_AND_ORDER)
    reference = in_process(path, tmp_path / "here")
    result = subprocess.run([sys.executable, "-m", "cosim", "sweep", str(path), "--scheduler", address,
                             "--out", str(tmp_path / "remote")], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert "4 points on 2 Dask workers" in result.stderr
    assert comparable(pq.read_table(tmp_path / "remote" / "study.parquet").to_pylist()) == comparable(reference)


def test_the_files_a_sweep_reads_travel_to_the_workers_by_content(tmp_path, dask_cluster):
    """A scene of the user's with a trajectory table beside it, and an SSP archive: the workers
    (started in another folder) get both by content, each file once into their cache under its
    SHA-256, and run the points bit for bit like this process."""
    import hashlib
    address, _, cache = dask_cluster
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "motion.csv").write_text("time,z\n0,0\n1,0.05\n2,0\n")
    scene = folder / "scene.toml"
    scene.write_text(SCENE.read_text().replace("[trajectory.x]", '[trajectory]\ntable = "motion.csv"\n[trajectory.x]', 1))
    path = sweep_file(tmp_path, '[[axis]]\nkey = "scene.step"\nvalues = [5e-4, 1e-3]\n').read_text()
    (tmp_path / "study.toml").write_text(path.replace(str(SCENE), str(scene)))
    study = tmp_path / "study.toml"
    sweep = load_sweep(study)
    assert sweep.evaluate.files() == [(folder / "motion.csv").resolve()]
    reference = in_process(study, tmp_path / "here")
    remote = run_sweep(sweep.name, sweep.points, sweep.evaluate, sweep.columns, tmp_path / "remote", sweep.signature,
                       scheduler=address, progress=False).rows
    assert all(r["status"] == "ok" for r in remote) and comparable(remote) == comparable(reference)
    for file in (scene, folder / "motion.csv"):
        assert (cache / "blobs" / hashlib.sha256(file.read_bytes()).hexdigest()).exists(), file
    # an SSP system: the archive travels the same way
    ssp = tmp_path / "meng.ssp"
    assert main(["export", str(SCENE), "--ssp", str(ssp)]) == 0
    (tmp_path / "ssp.toml").write_text(f'[sweep]\nsystem = "{ssp}"\nduration = 0.1\n[[axis]]\nkey = "step"\n'
                                       'values = [5e-4, 1e-3]\n')
    sweep = load_sweep(tmp_path / "ssp.toml")
    reference = in_process(tmp_path / "ssp.toml", tmp_path / "ssp_here")
    remote = run_sweep(sweep.name, sweep.points, sweep.evaluate, sweep.columns, tmp_path / "ssp_remote",
                       sweep.signature, scheduler=address, progress=False).rows
    assert all(r["status"] == "ok" for r in remote) and comparable(remote) == comparable(reference)
    assert (cache / "blobs" / hashlib.sha256(ssp.read_bytes()).hexdigest()).exists()


def test_a_worker_killed_mid_sweep_loses_nothing(tmp_path, dask_cluster):
    """SIGKILL to a worker process while the sweep runs: the scheduler gives its tasks to the
    other worker (the nanny restarts the killed one), and every point is a row once, as in one
    process."""
    import psutil
    address, processes, _ = dask_cluster
    path = sweep_file(tmp_path, EIGHT_POINTS, duration=1.0, extra="points_per_task = 1")
    reference = in_process(path, tmp_path / "here")
    out = tmp_path / "remote"
    process = subprocess.Popen([sys.executable, "-m", "cosim", "sweep", str(path), "--scheduler", address,
                                "--out", str(out)], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    _wait_for_parts(out / "study.parts", 1, process)
    victims = psutil.Process(processes[1].pid).children(recursive=True)  # the nanny's worker process
    assert victims
    for victim in victims:
        victim.kill()
    _, err = process.communicate(timeout=300)
    assert process.returncode == 0, err
    rows = pq.read_table(out / "study.parquet").to_pylist()
    assert all(r["status"] == "ok" for r in rows), [r["message"] for r in rows]
    assert comparable(rows) == comparable(reference)


@pytest.mark.parametrize("path", sorted((ROOT / "sweeps").glob("*.toml")), ids=lambda p: p.name)
def test_every_shipped_sweep_file_is_valid(path):
    sweep = load_sweep(path)
    assert sweep.points and sweep.plot is not None
    assert all(set(point) == {a.name for a in sweep.axes} for point in sweep.points)


def test_a_file_planted_in_the_workers_cache_is_replaced_never_run(tmp_path, dask_cluster):
    """Someone else's scene laid beforehand where the sweep's scene goes in the workers' cache
    (under its bundle's name) and under its blob's name: the workers check each file's SHA-256,
    replace both, and the rows are this scene's, bit for bit like this process."""
    from cosim.engine.sweep.bundle import Bundle, digest
    address, _, cache = dask_cluster
    path = sweep_file(tmp_path, '[[axis]]\nkey = "scene.step"\nvalues = [5e-4, 1e-3]\n')
    sweep = load_sweep(path)
    bundle, _ = Bundle.of(Path(sweep.evaluate.path), sweep.evaluate.files())
    foreign = SCENE.read_text().replace("duration = 10.0", "duration = 10.0\nname = \"planted\"").replace(
        "amplitude = 0.3", "amplitude = 0.05")
    planted = [cache / "bundles" / bundle.key / bundle.main, cache / "blobs" / bundle.files[0][1]]
    for place in planted:
        place.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        place.write_text(foreign)
    reference = in_process(path, tmp_path / "here")
    remote = run_sweep(sweep.name, sweep.points, sweep.evaluate, sweep.columns, tmp_path / "remote", sweep.signature,
                       scheduler=address, progress=False).rows
    assert all(r["status"] == "ok" for r in remote) and comparable(remote) == comparable(reference)
    assert all(digest(place.read_bytes()) == bundle.files[0][1] for place in planted)


def test_an_interrupted_local_cluster_sweep_is_one_line(tmp_path):
    """Ctrl-C (SIGINT to the whole process group, as a terminal sends it) during a sweep on a local
    cluster of two workers: one line from the command, no traceback from any worker process."""
    path = sweep_file(tmp_path, EIGHT_POINTS, duration=5.0, extra="points_per_task = 1")
    command = [sys.executable, "-m", "cosim", "sweep", str(path), "--workers", "2", "--out", str(tmp_path / "out")]
    process = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               start_new_session=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    _wait_for_parts(tmp_path / "out" / "study.parts", 1, process, timeout=120)
    os.killpg(process.pid, signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert err.strip().splitlines()[-1].startswith("interrupted: the points finished so far are in"), err


@pytest.fixture(scope="module")
def tls_cluster(tmp_path_factory):
    """A scheduler and a worker on 127.0.0.1 that speak TLS only, with a self-signed certificate
    (openssl) as every party's authority, certificate and key."""
    folder = tmp_path_factory.mktemp("tls")
    subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", "key.pem", "-out", "cert.pem",
                    "-days", "2", "-subj", "/CN=localhost", "-addext", "subjectAltName=IP:127.0.0.1,DNS:localhost"],
                   cwd=folder, check=True, capture_output=True)
    with dask_processes(folder, 1, ("--tls-ca-file", "cert.pem", "--tls-cert", "cert.pem", "--tls-key", "key.pem")) \
            as (address, _):
        yield address, folder


def test_a_sweep_on_a_tls_scheduler(tmp_path, tls_cluster):
    """With the client's certificate options the sweep runs on the TLS cluster bit for bit like
    this process; without them it is one line that says which options it needs."""
    address, folder = tls_cluster
    path = sweep_file(tmp_path, '[[axis]]\nkey = "scene.step"\nvalues = [5e-4, 1e-3]\n')
    reference = in_process(path, tmp_path / "here")
    tls = ["--tls-ca-file", str(folder / "cert.pem"), "--tls-cert", str(folder / "cert.pem"),
           "--tls-key", str(folder / "key.pem")]
    result = subprocess.run([sys.executable, "-m", "cosim", "sweep", str(path), "--scheduler", address, *tls,
                             "--out", str(tmp_path / "remote")], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert "warning" not in result.stderr
    assert comparable(pq.read_table(tmp_path / "remote" / "study.parquet").to_pylist()) == comparable(reference)
    bare = subprocess.run([sys.executable, "-m", "cosim", "sweep", str(path), "--scheduler", address, "--out",
                           str(tmp_path / "bare")], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert bare.returncode == 2 and bare.stderr.count("\n") == 1 and "--tls-ca-file, --tls-cert, --tls-key" in bare.stderr


@pytest.mark.parametrize("address,exposed", [("tls://192.0.2.1:8786", False), ("tcp://127.0.0.1:8786", False),
                                             ("tcp://localhost:8786", False), ("tcp://192.0.2.1:8786", True),
                                             ("192.0.2.1:8786", True), ("tcp://[::1]:8786", False)])
def test_a_scheduler_beyond_this_machine_without_tls_is_named(address, exposed):
    """The first line a sweep prints for an unencrypted scheduler that is not on this machine."""
    from cosim.engine.sweep.dask_run import unprotected
    said = unprotected(address)
    assert (said is not None) == exposed
    if exposed:
        assert address in said and "neither encrypted nor authenticated" in said and "tls://" in said


def test_the_command_lists_the_points_not_ok_with_whole_messages(tmp_path, capsys):
    """Thirteen steps too long for the coupling: the command lists ten of the points not ok,
    each with its message whole (cut only at a word past 400 characters), and says how many more."""
    values = ", ".join(f"{2.4e-3 + k * 1e-4:.4g}" for k in range(13))  # (3.7 ms runs, here)
    axes = f'[[axis]]\nkey = "scene.step"\nvalues = [{values}]\n'
    path = sweep_file(tmp_path, axes, duration=0.5, report='[report]\nvalues = ["steps"]\n')
    assert main(["sweep", str(path), "--workers", "0", "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    rows = pq.read_table(tmp_path / "out" / "study.parquet").to_pylist()
    listed = [line for line in out.splitlines() if line.startswith(("  diverged: ", "  failed: "))]
    assert len(rows) == 13 and all(r["status"] != "ok" for r in rows), [r["status"] for r in rows]
    assert len(listed) == 10 and "  ... and 3 more not ok" in out
    for line, row in zip(listed, rows):
        assert line.startswith(f"  {row['status']}: scene.step={row['scene.step']!r}: ")
        message = row["message"]
        assert line.endswith(message) if len(message) <= 400 else line.endswith(" ...")
