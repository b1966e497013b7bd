"""`cosim advise SCENE --tolerance TOL`: the cheapest effects, drive fidelity and macro step that
keep the scene within a tolerance, every candidate measured (cosim.platform.advise)."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import add_cluster, workers


def add(commands) -> argparse.ArgumentParser:
    advise = commands.add_parser("advise", help="recommend the cheapest effects, drive fidelity and step for a tolerance")
    advise.add_argument("scene", type=Path)
    advise.add_argument("--tolerance", type=float, required=True, help="largest pose error [m, rad]")
    advise.add_argument("--effort-tolerance", type=float, default=0.01,
                        help="largest drive torque/force error as a fraction of its peak (default 0.01)")
    advise.add_argument("--probe", type=float, help="probe duration [s] (default 2, and past the first load pulse and "
                        "the 0.2 s after it)")
    advise.add_argument("--keep-gains", action="store_true",
                        help="run reduced models with the scene's drive gains (default: loops designed for each)")
    add_cluster(advise, "the probes", None, scheduler=False)
    advise.add_argument("--out", type=Path, default=Path("out"), help="folder for <scene>_advice.csv (every candidate)")
    return advise


def main(args: argparse.Namespace) -> int:
    from ..platform.advise import advise, text, write_candidates
    from ..platform.scene import load_scene
    scene = load_scene(args.scene)
    candidates, info = advise(scene, args.tolerance, args.probe, args.effort_tolerance,
                              workers(args), redesign=not args.keep_gains)
    print(text(scene, args.tolerance, candidates, info))
    print(f"every candidate: {write_candidates(candidates, args.out / f'{scene.path.stem}_advice.csv')}")
    return 0
