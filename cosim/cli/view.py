"""`cosim view SCENE`: the platform following the scene's reference motion in 3D, before any
co-simulation (its trajectory FMU stepped alone), as a self-contained page."""

from __future__ import annotations

import argparse
from pathlib import Path


def add(commands) -> argparse.ArgumentParser:
    view = commands.add_parser("view", help="the platform following a scene's reference motion, in 3D (no co-simulation)")
    view.add_argument("scene", type=Path)
    view.add_argument("--out", type=Path, default=Path("out"), help="folder for <scene>_view.html")
    return view


def main(args: argparse.Namespace) -> int:
    from ..platform.report.view3d import write_view
    from ..platform.run.compile import scene_values
    from ..platform.run.errors import scene_error
    from ..platform.scene import load_scene
    scene = load_scene(args.scene)
    try:
        path, lines = write_view(scene, scene_values(scene)[0], args.out / f"{scene.path.stem}_view.html")
    except ValueError as error:  # a platform the scene's values do not build
        mapped = scene_error(scene, error)
        if mapped is None:
            raise
        raise mapped from None
    print("\n".join(lines))
    print(f"written: {path}")
    return 0
