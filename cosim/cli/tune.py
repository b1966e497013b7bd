"""`cosim tune SCENE`: a scene's motion cueing tuned to feel most like its vehicle within the
platform's limits (cosim.platform.design.cueing): the search on Dask, the best and the scene's own
confirmed by co-simulation, the tuned scene written beside the summary."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..engine.errors import UsageError
from .common import add_cluster, security, workers


def add(commands) -> argparse.ArgumentParser:
    tune = commands.add_parser("tune", help="tune a vehicle scene's motion cueing: perceived error least within the "
                               "platform's stroke, joint and current limits")
    tune.add_argument("scene", type=Path, help="a scene with a [motion] vehicle (its [cueing.tune] says what to search)")
    tune.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                      help="any of the scene's keys as table.key, its value as TOML writes it, over the file (as for "
                      "cosim run): a variant tuned without writing it; the tuned scene carries it")
    add_cluster(tune, "the search", None)
    tune.add_argument("--out", type=Path, default=Path("out"), help="folder for <scene>_tuned.toml and "
                      "<scene>_tuning.txt")
    return tune


def main(args: argparse.Namespace) -> int:
    from ..engine.files import write_text
    from ..platform.design.cueing import tune, write_tuned
    from ..platform.scene import load_scene
    from .run import set_values
    scene = load_scene(args.scene, *set_values(args.set))
    if scene.vehicle is None:
        raise UsageError(f"{args.scene}: has no [motion] vehicle: motion cueing tunes a vehicle's motion")
    iterations, population, seed = scene.cueing_search
    with security(args):
        tuning = tune(scene, workers=workers(args), scheduler=args.scheduler, seed=seed, iterations=iterations,
                      population=population, progress=True, judge=scene.cueing_judge)
    lines = tuning.lines()
    print("\n".join(lines))
    written = [write_tuned(scene, tuning, args.out),
               write_text(args.out / f"{scene.path.stem}_tuning.txt", "\n".join(lines) + "\n", "the tuning's summary")]
    print("written: " + ", ".join(str(f) for f in written))
    return 0
