"""`cosim view SCENE`: the platform following the scene's reference motion in 3D, before any
co-simulation (its trajectory FMU stepped alone), as a self-contained page; with `--live ADDRESS`,
the platform of a run streaming there (`cosim run SCENE --real-time --stream ADDRESS`), live in the
browser."""

from __future__ import annotations

import argparse
from pathlib import Path


def add(commands) -> argparse.ArgumentParser:
    view = commands.add_parser("view", help="the platform following a scene's reference motion, in 3D (no co-simulation)")
    view.add_argument("scene", type=Path)
    view.add_argument("--out", type=Path, default=Path("out"), help="folder for <scene>_view.html")
    view.add_argument("--live", metavar="udp://HOST:PORT", help="follow a run's stream (cosim run SCENE --real-time "
                      "--stream udp://HOST:PORT) in the browser until Ctrl-C, served on 127.0.0.1")
    view.add_argument("--port", type=int, default=8765, help="the live view's HTTP port (default 8765)")
    view.add_argument("--factor", type=float, default=1.0, help="the run's real-time factor, for how far it is "
                      "behind the clock (default 1)")
    return view


def main(args: argparse.Namespace) -> int:
    from ..platform.report.view3d import view_samples, write_view
    from ..platform.run.alone import reference_motion
    from ..platform.run.compile import scene_values
    from ..platform.run.errors import scene_error
    from ..platform.scene import load_scene
    scene = load_scene(args.scene)
    if args.live:
        return live(scene, args)
    try:
        motion = reference_motion(scene, view_samples(scene.duration))
        every_step = reference_motion(scene, int(round(scene.duration / scene.step)) + 1)[:2]  # the run's samples
        path, lines = write_view(scene, scene_values(scene)[0], motion, args.out / f"{scene.path.stem}_view.html",
                                 every_step)
    except ValueError as error:  # a platform the scene's values do not build
        mapped = scene_error(scene, error)
        if mapped is None:
            raise
        raise mapped from None
    print("\n".join(lines))
    print(f"written: {path}")
    return 0


def live(scene, args: argparse.Namespace) -> int:
    from ..engine.errors import UsageError
    from ..engine.realtime import address
    from ..platform.realtime.view import serve
    from ..platform.run.compile import run_label, scene_values
    address(args.live, "--live")
    if not 0 <= args.port < 65536 or not args.factor > 0:
        raise UsageError(f"--port {args.port} / --factor {args.factor}: a port 0-65535 and a factor > 0")
    try:
        serve(scene_values(scene)[0], run_label(scene), args.live, args.port, args.factor,
              ready=lambda port: print(f"the live view of {args.live}: http://127.0.0.1:{port}/ (Ctrl-C to end)",
                                       flush=True))
    except OSError as error:
        raise UsageError(f"--port {args.port}: {error.strerror or error}") from None
    return 0
