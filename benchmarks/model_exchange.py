"""What Model Exchange costs against co-simulation, per shipped scene over its probe (2 s, past its
first load pulse): the scene co-simulated at its defaults; the scene as ONE Model Exchange FMU
(`cosim export SCENE --fmu FILE --me`: the connections carried inside its derivatives, in C)
integrated by `cosim run --me` (CVODE through fmpy at 1e-8, the loop around it in Python), by
Reference-FMUs' fmusim (CVODE in C) and by fmpy's simulate_fmu (CVODE), the latter two at the
FMU's default tolerance; and OMSimulator's strongly coupled master on the `cosim export --ssp --me`
archive (../shared/peers, where present). Each against the scene's converged co-simulation by the
shipped tolerances: the wall time and real-time factor, the efforts' worst window against its
tolerance (at most 1: within) and the pose's error. Then the Meng scene's whole 10 s, the issue's
goal: RTF >= 10 in fmusim's CVODE. A scene whose drives cannot run as Model Exchange (the switching
inverter) says so.

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


def cell(judgement, wall: float, duration: float | None = None) -> str:
    pace = f" (RTF {duration / wall:.1f})" if duration else ""
    return f"{wall:.2f} s{pace}, {judgement.ratio:.2f} ({judgement.window}), pose {judgement.pose_error:.1e}"


def on_the_grid(table: np.ndarray, step: float) -> np.ndarray:
    """A Model Exchange run's rows at the output points (fmusim and fmpy write a row before and after
    each time event too): the last written at each."""
    ticks = np.round(table["time"] / step)
    on = np.abs(table["time"] - ticks * step) <= 1e-9
    return table[on & np.r_[ticks[1:] != ticks[:-1], True]]


def fmusim_run(fmu: Path, duration: float, step: float, tolerance: float, out: Path) -> tuple[np.ndarray, float]:
    """fmusim's CVODE on the FMU: its rows on the output grid and its wall time."""
    import subprocess
    from peers import fmusim
    start = time.perf_counter()
    done = subprocess.run([str(fmusim()), "--interface-type", "me", "--solver", "cvode", "--tolerance", repr(tolerance),
                           "--stop-time", repr(duration), "--output-interval", repr(step), "--output-file", str(out),
                           str(fmu)], capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(done.stderr.strip().splitlines()[-1] if done.stderr.strip() else "fmusim failed")
    return on_the_grid(np.genfromtxt(out, delimiter=",", names=True, deletechars=""), step), wall


def one_fmu(scene, duration: float, folder: Path, reference: np.ndarray) -> tuple[str, str]:
    """The scene's probe as one Model Exchange FMU in fmusim and in fmpy: their cells."""
    from fmpy import read_model_description, simulate_fmu
    from cosim.platform.run.portable import export_fmu
    fmu = export_fmu(scene, folder / "one.fmu", model_exchange=True).files[0]
    tolerance = float(read_model_description(str(fmu)).defaultExperiment.tolerance)
    try:
        rows, wall = fmusim_run(fmu, duration, scene.step, tolerance, folder / "fmusim.csv")
        fmusim_cell = cell(judge(scene, rows, reference), wall, duration)
    except ImportError:
        fmusim_cell = "(no fmusim here)"
    names = [n for n in reference.dtype.names if n != "time"]
    start = time.perf_counter()
    result = simulate_fmu(str(fmu), fmi_type="ModelExchange", solver="CVode", relative_tolerance=tolerance,
                          stop_time=duration, output_interval=scene.step, output=names)
    fmpy_cell = cell(judge(scene, on_the_grid(result, scene.step), reference), time.perf_counter() - start, duration)
    return fmusim_cell, fmpy_cell


def meng_whole(folder: Path) -> str:
    """The Meng scene's whole run: the one ME FMU in fmusim and fmpy, `cosim run --me`, the
    co-simulation; walls and real-time factors."""
    from fmpy import read_model_description, simulate_fmu
    from cosim.platform.run.portable import export_fmu
    scene = load_scene("meng_eq35")
    fmu = export_fmu(scene, folder / "meng_me.fmu", model_exchange=True).files[0]
    tolerance = float(read_model_description(str(fmu)).defaultExperiment.tolerance)
    _, fmusim_wall = fmusim_run(fmu, scene.duration, scene.step, tolerance, folder / "meng.csv")
    start = time.perf_counter()
    simulate_fmu(str(fmu), fmi_type="ModelExchange", solver="CVode", relative_tolerance=tolerance,
                 stop_time=scene.duration, output_interval=scene.step, output=["pose.z"])
    fmpy_wall = time.perf_counter() - start
    start = time.perf_counter()
    cosim.simulate(scene, model_exchange=True)
    me_wall = time.perf_counter() - start
    start = time.perf_counter()
    cosim.simulate(scene)
    cs_wall = time.perf_counter() - start
    rtf = scene.duration
    return (f"Meng's whole {scene.duration:g} s as one Model Exchange FMU: fmusim's CVODE {fmusim_wall:.2f} s (RTF "
            f"{rtf / fmusim_wall:.1f}; the issue's goal: 10), fmpy's {fmpy_wall:.2f} s (RTF {rtf / fmpy_wall:.1f}), "
            f"both at its tolerance {tolerance:g}; `cosim run --me` (1e-8, the FMU written for the run included) "
            f"{me_wall:.2f} s (RTF {rtf / me_wall:.1f}); the co-simulation {cs_wall:.2f} s (RTF {rtf / cs_wall:.0f}). "
            "Each wall is the whole call: the tool's start, unpacking and instantiation included.")


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
    lines = ["| scene | probe | co-simulation: wall, worst window, pose | `cosim run --me` (one ME FMU, CVODE) | "
             "one ME FMU in fmusim (CVODE) | one ME FMU in fmpy (CVODE) | OMSimulator's strongly coupled master "
             "(CVODE) |", "|---|---|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory() as folder:
        for name in SCENES:
            scene = load_scene(name)
            duration = probe_duration(scene)
            probe = scene.changed({"scene.duration": duration})
            reference = converged(scene, duration)
            start = time.perf_counter()
            cs = cosim.simulate(probe)
            cs_cell = cell(judge(scene, cs.values, reference), time.perf_counter() - start, duration)
            try:
                start = time.perf_counter()
                me = cosim.simulate(probe, model_exchange=True)
                me_cell = cell(judge(scene, me.values, reference), time.perf_counter() - start, duration)
                (Path(folder) / name).mkdir()
                fmusim_cell, fmpy_cell = one_fmu(probe, duration, Path(folder) / name, reference)
                oms_cell = omsimulator(scene, duration, Path(folder) / name)
            except (UsageError, cosim.RunStopped) as refused:
                me_cell = fmusim_cell = fmpy_cell = oms_cell = f"not as Model Exchange: {refused}"
            lines.append(f"| {name} | {duration:g} s | {cs_cell} | {me_cell} | {fmusim_cell} | {fmpy_cell} | "
                         f"{oms_cell} |")
            print(lines[-1], flush=True)
        lines += ["", meng_whole(Path(folder))]
    lines += ["", "Each cell: wall time (real-time factor), the efforts' worst window against its tolerance (at most "
              "1: within) and the pose's largest error [m, rad], against the scene's converged co-simulation (its own "
              "coupling at a 16th of its step). The one ME FMU's walls in fmusim and fmpy are the whole call (the "
              "tool's start, unpacking, instantiation); `cosim run --me`'s include writing the FMU for the run. "
              "OMSimulator b3cd458's strongly coupled master carries the connections once per accepted CVODE step "
              "(docs/guide/engine-background.md)."]
    publish("model_exchange", "python benchmarks/model_exchange.py", lines)


if __name__ == "__main__":
    main()
