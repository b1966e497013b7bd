"""Command line:
    python -m cosim run SCENE|FILE.ssp|FILE.ssd [--out DIR] [--no-plots] [--duration S] [--set NAME=VALUE]
    python -m cosim export SCENE [--ssp FILE.ssp] [--osp DIR] [--warnings-as-ok]   the scene as an SSP 1.0 archive and/or
                                                                 an OSP configuration (libcosim)
    python -m cosim view SCENE [--out DIR]    the platform following the scene's reference motion, in 3D
    python -m cosim validate [--out DIR]      rebuilds DIR/validation.md (default docs/)
    python -m cosim advise SCENE --tolerance TOL [--probe S]   the cheapest model within TOL
    python -m cosim sweep SWEEP.toml [--workers N] [--scheduler ADDRESS] [--out DIR]   many runs on Dask"""

from __future__ import annotations

import argparse
import math
import traceback
import sys
from pathlib import Path

from .engine.artifacts import INSTALLED, ROOT
from .engine.ssp import ANNOTATION
from .platform.run.runner import SceneFailed, run_scene
from .platform.scene.reader import SceneError, load_scene


def main(argv: list[str] | None = None) -> int:
    """Exit codes: 0 done, 1 the run failed (partial results written), 2 a user error (one line),
    3 a bug in this program (its traceback, and a line that says so)."""
    from .engine import ArtifactMissing
    try:
        return _main(argv)
    except ArtifactMissing as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except Exception:  # anything else is ours to fix, not the user's
        traceback.print_exc()
        print("internal error: the traceback above is a bug in cosim, not a mistake in your input; please "
              "report it with the command you ran", file=sys.stderr)
        return 3


def _main(argv: list[str] | None = None) -> int:
    prog = "cosim" if Path(sys.argv[0]).name == "cosim" else "python -m cosim"  # the console script, or -m
    parser = argparse.ArgumentParser(prog=prog, description="Stewart platform co-simulation")
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="run a scene file (see scenes/) or any SSP system (.ssp, .ssd)")
    run.add_argument("scene", type=Path)
    run.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                     help="an SSP system's run setting (algorithm, order, step_control, step, rtol, atol, ...)")
    run.add_argument("--out", type=Path, default=Path("out"), help="folder for CSV, .mat and plots")
    run.add_argument("--no-plots", action="store_true")
    run.add_argument("--duration", type=str, help="override the scene's duration [s]")
    run.add_argument("--twin", action="store_true", help="a scene's run judged against its converged twin (the scene "
                     "at a 16th of its step throughout), per window: start-up, each load pulse, steady tracking")
    export = commands.add_parser("export", help="write a scene as an SSP 1.0 archive (FMUs, parameters, wiring)")
    export.add_argument("scene", type=Path)
    export.add_argument("--ssp", type=Path, help="the .ssp file to write")
    export.add_argument("--osp", type=Path, help="a folder for OspSystemStructure.xml and the FMUs (libcosim)")
    export.add_argument("--warnings-as-ok", action="store_true",
                        help="every FMU returns fmi2OK where it logs a warning (fmi.warnings_as_ok), for tools that "
                             "stop on fmi2Warning such as OMSimulator; the warnings stay in the log")
    view = commands.add_parser("view", help="the platform following a scene's reference motion, in 3D (no co-simulation)")
    view.add_argument("scene", type=Path)
    view.add_argument("--out", type=Path, default=Path("out"), help="folder for <scene>_view.html")
    validate = commands.add_parser("validate", help="rebuild the validation report against the papers")
    validate.add_argument("--out", type=Path, default=Path("out") if INSTALLED else ROOT / "docs",
                          help="folder of validation.md and figures/ (default: a checkout's docs/; out/ for an "
                          "installed wheel, whose files are not to be written)")
    advise = commands.add_parser("advise", help="recommend the cheapest effects, drive fidelity and step for a tolerance")
    advise.add_argument("scene", type=Path)
    advise.add_argument("--tolerance", type=float, required=True, help="largest pose error [m, rad]")
    advise.add_argument("--effort-tolerance", type=float, default=0.01,
                        help="largest drive torque/force error as a fraction of its peak (default 0.01)")
    advise.add_argument("--probe", type=float, help="probe duration [s] (default 2, and past the first load pulse and "
                        "the 0.2 s after it)")
    advise.add_argument("--keep-gains", action="store_true",
                        help="run reduced models with the scene's drive gains (default: loops designed for each)")
    advise.add_argument("--workers", type=int, help="Dask worker processes for the probes (default: one per core; "
                        "0: in this process)")
    advise.add_argument("--out", type=Path, default=Path("out"), help="folder for <scene>_advice.csv (every candidate)")
    sweep = commands.add_parser("sweep", help="run a scene or SSP system at many points, on Dask (see cosim.platform.run.sweep)")
    sweep.add_argument("sweep", type=Path, help="the sweep file (TOML)")
    sweep.add_argument("--workers", type=int, help="worker processes of a local Dask cluster (default: one per core; "
                       "0: no Dask, in this process)")
    sweep.add_argument("--scheduler", help="address of a running Dask scheduler, e.g. tcp://host:8786")
    sweep.add_argument("--out", type=Path, default=Path("out"), help="folder for <sweep>.parquet, .csv and .png")
    design = commands.add_parser("design", help="which platform carries a motion: a configuration design study "
                                 "(studies/, Halder et al. Section V)")
    design.add_argument("study", help="a study file (TOML) or a shipped study's name, e.g. halder_section5")
    design.add_argument("--workers", type=int, default=0, help="Dask worker processes for the map (default 0: in "
                        "this process)")
    design.add_argument("--scheduler", help="address of a running Dask scheduler, e.g. tcp://host:8786")
    design.add_argument("--out", type=Path, default=Path("out"), help="folder for the figures, the map and the summary")
    copy = commands.add_parser("copy", help="copy a shipped scene, sweep file or study here to edit (no name: "
                               "list them)")
    copy.add_argument("name", nargs="?", help="a shipped scene's or sweep file's name, e.g. meng_eq35")
    copy.add_argument("--to", type=Path, default=Path("."), help="the folder to copy into (default: this one)")
    args = parser.parse_args(argv)
    if args.command == "copy":
        return copy_shipped(args.name, args.to)
    out = getattr(args, "out", None)
    if out is not None and (problem := unwritable(out)):
        print(f"error: --out {out}: {problem}", file=sys.stderr)
        return 2
    if args.command == "sweep":
        return run_sweep_file(args.sweep, args.out, args.workers, args.scheduler)
    if args.command == "design":
        return run_design(args.study, args.out, args.workers, args.scheduler)
    if args.command == "advise":
        from .platform.advise import advise as run_advice, text, write_csv
        try:
            scene = load_scene(args.scene)
        except SceneError as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
        candidates, info = run_advice(scene, args.tolerance, args.probe, args.effort_tolerance, args.workers,
                                      redesign=not args.keep_gains)
        print(text(scene, args.tolerance, candidates, info))
        print(f"every candidate: {write_csv(candidates, args.out / f'{scene.path.stem}_advice.csv')}")
        return 0
    if args.command == "view":
        from .platform.run.runner import scene_error, scene_values
        from .platform.report.view3d import write_view
        try:
            scene = load_scene(args.scene)
            path, lines = write_view(scene, scene_values(scene)[0], args.out / f"{scene.path.stem}_view.html")
        except SceneError as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
        except ValueError as error:  # a platform the scene's values do not build
            mapped = scene_error(scene, error)
            if mapped is None:
                raise
            print(f"error: {mapped}", file=sys.stderr)
            return 2
        print("\n".join(lines))
        print(f"written: {path}")
        return 0
    if args.command == "validate":
        from .platform.validation.report import build
        print(f"written: {build(args.out)}")
        return 0
    duration = None
    if getattr(args, "duration", None) is not None:
        try:
            duration = float(args.duration)
        except ValueError:
            duration = float("nan")
        if not (math.isfinite(duration) and duration > 0):
            print(f"error: --duration {args.duration}: must be a positive finite number of seconds", file=sys.stderr)
            return 2
    if args.command == "export":
        return export_scene(args.scene, args.ssp, args.osp, args.warnings_as_ok)
    if args.scene.suffix.lower() in (".ssp", ".ssd"):
        return run_system(args.scene, args.out, args.set, duration)
    try:
        scene = load_scene(args.scene)
    except SceneError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    if duration is not None:
        scene.duration = duration
    return report(lambda: run_scene(scene, args.out, plots=not args.no_plots, twin=args.twin)[1], (SceneError,),
                  SceneFailed,
                  f"{args.out}/{scene.path.stem}.csv, .mat, .log" + ("" if args.no_plots else
                                                                    f", plots and the report {scene.path.stem}.html"),
                  args.out)


def unwritable(folder: Path) -> str | None:
    """Why results could not be written into `folder`, or None; checked before a run (nothing is
    created here), so that nothing computed is lost at its end."""
    import os
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        return f"cannot write results there ({existing} is not a folder)"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"cannot write results there ({existing} is not writable)"
    return None


def report(run, user_errors: tuple, failure: type, written: str, out: Path) -> int:
    """Runs `run` (which returns a report); prints the report and what was written (exit 0), a
    user error in one line (exit 2), or a failed run's report with its partial results (exit 1)."""
    try:
        outcome = run()
    except user_errors as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except failure as failed:
        print(failed.report.text(), file=sys.stderr)
        print(f"partial results up to t = {failed.report.simulated:g} s written to {out}/", file=sys.stderr)
        return 1
    print(outcome.text())
    print(f"results: {written}")
    return 0


def run_design(study: str, out: Path, workers: int, scheduler: str | None) -> int:
    from .platform.design import StudyError, load_study, parallel_map, report_rows, summary, write
    from .platform.scene.reader import shipped
    if workers < 0:
        print(f"error: --workers {workers}: must be 0 (in this process) or more", file=sys.stderr)
        return 2
    try:
        loaded = load_study(shipped(study, "studies") or study if not Path(study).exists() else study)
    except StudyError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    design = parallel_map(loaded, workers=workers, scheduler=scheduler)
    rows = report_rows(design, workers, scheduler)
    print("\n".join(summary(design, rows)))
    files = write(design, out, rows)
    print("written: " + ", ".join(str(f) for f in files))
    return 0


def copy_shipped(name: str | None, to: Path) -> int:
    """Copies a shipped scene or sweep file into `to` (never over a file), or lists them."""
    import difflib
    import shutil
    from .platform.scene.reader import shipped, shipped_scenes
    kinds = {folder: shipped_scenes(folder) for folder in ("scenes", "sweeps", "studies")}
    if name is None:
        for folder, names in kinds.items():
            print(f"{folder}: {', '.join(names)}")
        return 0
    source = next((found for folder in kinds if (found := shipped(name, folder))), None)
    if source is None:
        near = difflib.get_close_matches(name, [n for names in kinds.values() for n in names], 1)
        print(f"error: {name!r} is not a shipped scene, sweep file or study" + (f" (did you mean {near[0]!r}?)" if near
                                                                         else " (`cosim copy` lists them)"),
              file=sys.stderr)
        return 2
    target = to / source.name
    if target.exists():
        print(f"error: {target} exists; copy elsewhere with --to", file=sys.stderr)
        return 2
    if problem := unwritable(to):
        print(f"error: --to {to}: {problem}", file=sys.stderr)
        return 2
    to.mkdir(parents=True, exist_ok=True)
    shutil.copy(source, target)
    command = {"sweeps": "sweep", "studies": "design"}.get(source.parent.name, "run")
    print(f"copied: {target} (from {source}); run it with `cosim {command} {target}`")
    return 0


def run_sweep_file(path: Path, out: Path, workers: int | None, scheduler: str | None) -> int:
    from .engine.sweep import SweepError, column_name, plot_sweep, run_sweep
    from .platform.run.sweep import load_sweep
    if workers is not None and workers < 0:
        print(f"error: --workers {workers}: must be 0 (no Dask) or more", file=sys.stderr)
        return 2
    try:
        sweep = load_sweep(path)
        outcome = run_sweep(sweep.name, sweep.points, sweep.evaluate, sweep.columns, out, sweep.signature,
                            workers=workers, scheduler=scheduler, points_per_task=sweep.points_per_task,
                            retries=sweep.retries)
    except SweepError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"interrupted: the points finished so far are in {out}/{path.stem}.parts; run the same command again "
              "to run only the others", file=sys.stderr)
        return 130
    kinds = {s: sum(r["status"] == s for r in outcome.rows) for s in ("ok", "diverged", "failed")}
    print(f"{sweep.name}: {len(outcome.rows)} points ({outcome.ran} run now, {outcome.skipped} found done): "
          + ", ".join(f"{n} {s}" for s, n in kinds.items() if n))
    for row in [r for r in outcome.rows if r["status"] != "ok"][:5]:
        print(f"  {row['status']}: {', '.join(f'{a.name}={row[column_name(a.name)]!r}' for a in sweep.axes)}: "
              f"{row['message'][:200]}")
    written = [*outcome.files]
    if sweep.plot is not None:
        written.append(plot_sweep(outcome.rows, sweep.plot, out / f"{sweep.name}.png", sweep.name, sweep.units))
    print("results: " + ", ".join(str(f) for f in written))
    return 0


def export_scene(path: Path, ssp: Path | None, osp: Path | None, warnings_as_ok: bool = False) -> int:
    from .engine.osp import write_osp
    from .engine.ssp import SspError, not_portable, write_ssp
    from .platform.run.runner import scene_structure
    if ssp is None and osp is None:
        print("error: export: give --ssp FILE.ssp, --osp DIR or both", file=sys.stderr)
        return 2
    from .engine import ParameterError
    from .engine.checks import check_parameters
    from .platform.run.runner import scene_error
    try:
        scene = load_scene(path)
        structure = scene_structure(scene)
        if warnings_as_ok:
            for component in structure.components:
                component.parameters["fmi.warnings_as_ok"] = True
            print("note: every FMU returns fmi2OK where it logs a warning (fmi.warnings_as_ok = true): a tool that "
                  "stops on fmi2Warning (OMSimulator) runs on past a leg out of its stroke; the warnings stay in the "
                  "FMUs' log")
        try:
            check_parameters(structure)
        except ParameterError as error:
            raise scene_error(scene, error) from None
        if ssp is not None:
            print(f"written: {write_ssp(structure, ssp)} (SSP 1.0; our run settings in its annotation "
                  f"'{ANNOTATION}', which other tools ignore)")
        for note in not_portable(structure.settings):
            print(f"note: other tools run this system without {note}")
        if osp is not None:
            print(f"written: {write_osp(structure, osp)} and the FMUs beside it (OSP; libcosim runs it with its "
                  f"fixed-step or ECCO algorithm and no input derivatives; libcosimpy 0.0.6 loads a file with "
                  f"more than one power bond only once its parser is fixed, see cosim.engine.osp)")
    except (SceneError, SspError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    return 0


def run_system(path: Path, out: Path, settings: list[str], duration: float | None) -> int:
    from .engine import SettingsError
    from .engine.outcome import RunStopped
    from .engine.command import run_ssp
    from .engine.ssp import SspError
    overrides = {}
    for item in settings:
        if "=" not in item:
            print(f"error: --set {item!r}: expected NAME=VALUE", file=sys.stderr)
            return 2
        name, value = item.split("=", 1)
        overrides[name.strip()] = value.strip()
    return report(lambda: run_ssp(path, out, overrides, duration)[1], (SspError, SettingsError), RunStopped,
                  f"{out}/{path.stem}.csv and .mat", out)


def main_exit() -> None:
    """The `cosim` console script: the same CLI as `python -m cosim`."""
    sys.exit(main())


if __name__ == "__main__":
    main_exit()
