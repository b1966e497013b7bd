"""What Model Exchange costs against co-simulation, per shipped scene over its probe (2 s, past its
first load pulse): the scene co-simulated at its defaults, our monolithic run of its Model Exchange
FMUs (`cosim run --me`: CVODE through fmpy, the coupled right-hand side evaluated in Python) and
OMSimulator's strongly coupled master on the `cosim export --me` archive (../shared/peers, where
present), each against the scene's converged co-simulation by the shipped tolerances: the wall
time and the efforts' worst window against its tolerance (at most 1: within) with the pose's error.
A scene whose drives cannot run as Model Exchange (the switching inverter) says so.

    python benchmarks/model_exchange.py            # prints the table
    python benchmarks/model_exchange.py --write    # and writes it into docs/benchmarks.md
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from common import publish  # noqa: E402
import cosim  # noqa: E402
from cosim.engine.artifacts import ROOT  # noqa: E402
from cosim.engine.errors import UsageError  # noqa: E402
from cosim.platform.run.accuracy import judge, probe_duration  # noqa: E402
from cosim.platform.run.compile import scene_record  # noqa: E402
from cosim.platform.run.portable import converged, export_model_exchange  # noqa: E402
from cosim.platform.scene import load_scene  # noqa: E402

SCENES = sorted(p.stem for p in (ROOT / "scenes").glob("*.toml"))


def cell(judgement, wall: float) -> str:
    return f"{wall:.1f} s, {judgement.ratio:.2f} ({judgement.window}), pose {judgement.pose_error:.1e}"


def omsimulator(scene, duration: float, folder: Path) -> str:
    try:
        from peers import omsimulator as binary, run_omsimulator
        binary()
    except BaseException:  # the peer is absent (a user's clone): say so
        return "(no OMSimulator here)"
    archive = folder / f"{scene.path.stem}.ssp"
    export_model_exchange(scene, archive)
    record, names = scene_record(scene)
    start = time.perf_counter()
    try:
        columns = run_omsimulator(archive, [f"{c}.{v}" for c, v in record], duration, folder)
    except AssertionError as failed:
        return "fails: " + next((line for line in str(failed).splitlines() if "error" in line.lower()), "an error")
    wall = time.perf_counter() - start
    rows = np.zeros(len(columns["time"]), dtype=[("time", float), *[(n, float) for n in names]])
    rows["time"] = columns["time"]
    for (c, v), n in zip(record, names):
        rows[n] = columns[f"{c}.{v}"]
    return cell(judge(scene, rows, converged(scene, duration)), wall)


def main() -> None:
    lines = ["| scene | probe | co-simulation: wall, worst window, pose | Model Exchange in our engine (CVODE) | "
             "OMSimulator's strongly coupled master (CVODE) |", "|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory() as folder:
        for name in SCENES:
            scene = load_scene(name)
            duration = probe_duration(scene)
            probe = scene.changed({"scene.duration": duration})
            reference = converged(scene, duration)
            start = time.perf_counter()
            cs = cosim.simulate(probe)
            cs_cell = cell(judge(scene, cs.values, reference),
                           time.perf_counter() - start)
            try:
                start = time.perf_counter()
                me = cosim.simulate(probe, model_exchange=True)
                me_cell = cell(judge(scene, me.values, reference),
                               time.perf_counter() - start)
                oms_cell = omsimulator(scene, duration, Path(folder) / name)
            except (UsageError, cosim.RunStopped) as refused:
                me_cell = oms_cell = f"not as Model Exchange: {refused}"
            lines.append(f"| {name} | {duration:g} s | {cs_cell} | {me_cell} | {oms_cell} |")
            print(lines[-1], flush=True)
    lines += ["", "Each cell: wall time, the efforts' worst window against its tolerance (at most 1: within) and "
              "the pose's largest error [m, rad], against the scene's converged co-simulation (its own coupling at a "
              "16th of its step). OMSimulator b3cd458's strongly coupled master carries the connections once per "
              "accepted CVODE step (docs/guide/engine.md)."]
    publish("model_exchange", "python benchmarks/model_exchange.py", lines)


if __name__ == "__main__":
    main()
