"""Command line:
    python -m cosim run SCENE [--out DIR] [--no-plots] [--duration S]
    python -m cosim validate [--out DIR]      rebuilds DIR/validation.md (default docs/)
    python -m cosim advise SCENE --tolerance TOL [--probe S]   the cheapest model within TOL"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .fmus import ROOT
from .runner import SceneFailed, run_scene
from .scene import SceneError, load_scene


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m cosim", description="Stewart platform co-simulation")
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="run a scene file (see scenes/)")
    run.add_argument("scene", type=Path)
    run.add_argument("--out", type=Path, default=Path("out"), help="folder for CSV, .mat and plots")
    run.add_argument("--no-plots", action="store_true")
    run.add_argument("--duration", type=float, help="override the scene's duration [s]")
    validate = commands.add_parser("validate", help="rebuild the validation report against the papers")
    validate.add_argument("--out", type=Path, default=ROOT / "docs", help="folder of validation.md and figures/ "
                          "(default: this checkout's docs/)")
    advise = commands.add_parser("advise", help="recommend the cheapest effects, drive fidelity and step for a tolerance")
    advise.add_argument("scene", type=Path)
    advise.add_argument("--tolerance", type=float, required=True, help="largest pose error [m, rad]")
    advise.add_argument("--probe", type=float, default=2.0, help="probe duration [s] (default 2)")
    args = parser.parse_args(argv)
    if args.command == "advise":
        from .advise import advise as run_advice, text
        try:
            scene = load_scene(args.scene)
        except SceneError as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
        candidates, info = run_advice(scene, args.tolerance, args.probe)
        print(text(scene, args.tolerance, candidates, info))
        return 0
    if args.command == "validate":
        from .validation.report import build
        print(f"written: {build(args.out)}")
        return 0
    try:
        scene = load_scene(args.scene)
    except SceneError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    if args.duration:
        scene.duration = args.duration
    try:
        _, report = run_scene(scene, args.out, plots=not args.no_plots)
    except SceneError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except SceneFailed as failed:
        print(failed.report.text(), file=sys.stderr)
        print(f"partial results up to t = {failed.report.simulated:g} s written to {args.out}/", file=sys.stderr)
        return 1
    print(report.text())
    print(f"results: {args.out}/{scene.path.stem}.csv, .mat and plots")
    return 0


if __name__ == "__main__":
    sys.exit(main())
