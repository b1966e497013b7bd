"""`cosim run SCENE|FILE.ssp|FILE.ssd|FILE.fmu`: one run through `cosim.simulate`, its report printed and
its results written to --out (CSV, .mat, the FMUs' log; a scene's plots and interactive report). A
Co-Simulation FMU runs alone as a one-component system (cosim.engine.single)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..engine.errors import InputError, UsageError
from .common import report, seconds


def add(commands) -> argparse.ArgumentParser:
    run = commands.add_parser("run", help="run a scene file (see scenes/), any SSP system (.ssp, .ssd) or one Co-Simulation FMU alone (.fmu: its "
                          "start values, its DefaultExperiment, every Real output recorded)")
    run.add_argument("scene", type=Path, help="a scene (a shipped one by name, or its .toml), an SSP system (.ssp, "
                     ".ssd) or one Co-Simulation FMU run alone (.fmu)")
    run.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                     help="a run setting (step, algorithm, order, step_control, rtol, atol, ...) or, for a scene, any of "
                     "its keys as table.key (scene.duration, 'mechanics.parameters.\"platform.mass\"'), its value "
                     "as TOML writes it")
    run.add_argument("--out", type=Path, default=Path("out"), help="folder for CSV, .mat and plots")
    run.add_argument("--no-plots", action="store_true")
    run.add_argument("--duration", type=str, help="override the scene's duration [s]")
    run.add_argument("--fmi", type=int, choices=(2, 3), help="a scene's FMUs as FMI 2.0 (the default) or FMI 3.0 "
                     "(scene.fmi; FMI 3.0 has no input derivatives: at order 1 or 2 each FMU extrapolates its inputs itself, "
                     "at an eighth of the scene's fixed step)")
    run.add_argument("--twin", action="store_true", help="a scene's run judged against its converged twin (the scene "
                     "at a 16th of its step throughout), per window: start-up, each load pulse, steady tracking")
    run.add_argument("--me", action="store_true", help="a scene's FMUs as Model Exchange, integrated as one system by "
                     "one solver (CVODE): no coupling, the reference a co-simulation is judged against")
    run.add_argument("--real-time", nargs="?", const="1", metavar="FACTOR", help="pace the run to the wall clock (each "
                     "macro step at its deadline), FACTOR simulated seconds per wall second (default 1)")
    run.add_argument("--stream", metavar="udp://HOST:PORT[?every=N]", help="send the run's samples live, one datagram "
                     "every N macro steps (layout: cosim stream-layout)")
    run.add_argument("--listen", metavar="udp://HOST:PORT", help="a scene's pose reference taken live from datagrams "
                     "sent here (cosim.realtime.send), held within the platform's motion envelope; binds 127.0.0.1 "
                     "unless a host is named (any other than the loopback needs --listen-key)")
    run.add_argument("--listen-key", metavar="FILE", type=Path, help="a file holding the shared key (16 to 256 bytes) "
                     "that every live datagram is tagged with (HMAC-SHA256)")
    return run


def settings(items: list[str]) -> dict[str, str]:
    """--set NAME=VALUE, each."""
    out = {}
    for item in items:
        if "=" not in item:
            raise UsageError(f"--set {item!r}: expected NAME=VALUE")
        name, value = item.split("=", 1)
        out[name.strip()] = value.strip()
    return out


def set_values(items: list[str]) -> tuple[dict[str, object], dict[str, str]]:
    """--set NAME=VALUE for a scene: the scene keys they set (a run setting's name to its key), each
    value read as TOML writes it (text that is not a TOML value as text), and how each was given
    ('--set step=-1e-3': what an error about it names, not the scene file's line)."""
    import tomllib
    from ..platform.scene.schema import setting_key
    out, given = {}, {}
    for name, text in settings(items).items():
        try:
            value = tomllib.loads(f"value = {text}")["value"]
        except tomllib.TOMLDecodeError:
            value = text
        try:
            key = setting_key(name)
        except InputError as error:
            raise UsageError(f"--set {name}={text}: {error}") from None
        out[key], given[key] = value, f"--set {name}={text}"
    return out, given


def main(args: argparse.Namespace) -> int:
    from ..api import SYSTEM_SUFFIXES, simulate
    from ..platform.scene import load_scene
    duration = seconds("--duration", args.duration)
    factor = seconds("--real-time", args.real_time, "expected a real-time factor > 0 (1: the wall clock's pace)")
    if args.listen_key is not None and not args.listen:
        raise UsageError("--listen-key goes with --listen")
    if args.listen:
        from ..engine.realtime import address, is_loopback
        host = address(args.listen, "--listen")[0]
        if not is_loopback(host) and args.listen_key is not None:
            print(f"listening on {host}: datagrams from other machines that carry the key of {args.listen_key} can "
                  "drive this run's platform", flush=True)
    system = args.scene.suffix.lower() in SYSTEM_SUFFIXES
    stem = args.scene.stem
    written = f"{args.out}/{stem}.csv, .mat, .log" + ("" if args.no_plots else
                                                     f", plots and the report {stem}.html")
    if args.fmi is not None and system:
        raise UsageError(f"--fmi: for a scene; {args.scene.name} names its own FMUs")
    if args.me and system:
        raise UsageError(f"--me: for a scene; {args.scene.name} names its own FMUs")
    if system:  # an SSP's run settings by name (cosim.engine.settings), checked by the engine
        model, given = args.scene, {"settings": settings(args.set) or None}
    else:  # a scene's keys, each error about one naming the option that set it
        overrides, labels = set_values(args.set)
        if args.fmi is not None:
            overrides["scene.fmi"], labels["scene.fmi"] = args.fmi, f"--fmi {args.fmi}"
        model, given = (lambda: load_scene(args.scene, overrides, labels)), {}
    return report(lambda: simulate(model() if callable(model) else model, duration=duration, out=args.out,
                                   plots=not args.no_plots, twin=args.twin, progress=True, advice=True,
                                   real_time=factor, stream=args.stream, listen=args.listen,
                                   listen_key=args.listen_key, model_exchange=args.me, **given).report,
                  written, args.out)
