"""`cosim export SCENE --ssp FILE.ssp --osp DIR --fmu FILE.fmu [--me] [--set KEY=VALUE] [--duration S]`:
the scene's whole system (or a variant of it) for other FMI tools, as an SSP 1.0 archive and/or an
OSP configuration (libcosim), each tool's step measured by its master in our engine, and/or as ONE
Co-Simulation FMU with our coupling inside, or (--me) ONE Model Exchange FMU with the connections
inside its derivatives (cosim.platform.run.portable).

`cosim export-check SYSTEM.ssp` (export_check, below): the step each other tool gets for any SSP
system (one of ours, a user's own, a peer's demo), measured as `cosim export` measures a scene's: each tool's master
(cosim.engine.tools) run in our engine at the system's step and each half of it, against the
system's own coupling at a 16th of its step, every recorded output within 2 % of its own range;
the table printed and, unless --dry-run, the steps written into the archive where each tool takes
them."""

from __future__ import annotations

import argparse
from pathlib import Path
from types import SimpleNamespace

from ..engine.errors import UsageError
from .common import unwritable


def add(commands) -> argparse.ArgumentParser:
    export = commands.add_parser("export", help="write a scene as an SSP 1.0 archive (FMUs, parameters, wiring), each "
                                 "other tool's step measured")
    export.add_argument("scene", type=Path)
    export.add_argument("--ssp", type=Path, help="the .ssp file to write")
    export.add_argument("--osp", type=Path, help="a folder for OspSystemStructure.xml and the FMUs (libcosim)")
    export.add_argument("--fmu", type=Path, help="the .fmu file to write: the whole scene as ONE Co-Simulation FMU, "
                        "coupled inside as `cosim run` couples it (any tool that imports an FMU runs it)")
    export.add_argument("--scene-step", action="store_true",
                        help="write the scene's own step for every tool, unmeasured (by default each tool's master is "
                             "run in our engine and the largest step within the tolerances written for it)")
    export.add_argument("--fmi2-warnings", action="store_true",
                        help="the FMUs return fmi2Warning where they log one, as the standard has it (by default "
                             "fmi2OK, so that OMSimulator, which stops at the first, runs to the end)")
    export.add_argument("--warnings-as-ok", action="store_true", help="the default (kept for old command lines)")
    export.add_argument("--fmi", type=int, choices=(2, 3), help="our FMUs as FMI 2.0 (the default) or FMI 3.0 in the "
                        "archive, and the one FMU (--fmu) as FMI 2.0 or 3.0 (scene.fmi)")
    export.add_argument("--me", action="store_true", help="with --fmu: the whole scene as ONE Model Exchange FMU (the "
                        "connections inside its derivatives: any tool's solver integrates the coupled platform); "
                        "with --ssp: the FMUs as Model Exchange in one strongly coupled system (OMSimulator's oms-sc)")
    export.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a key of the scene as `cosim run --set` takes it (step, 'mechanics.parameters.\"platform."
                             "mass\"', ...): the variant exported, the file unchanged")
    export.add_argument("--duration", type=str, help="the exported experiment's stop time [s], instead of the scene's")
    return export


def main(args: argparse.Namespace) -> int:
    from ..platform.run.portable import Exported, export_scene
    from ..platform.scene import load_scene
    if args.ssp is None and args.osp is None and args.fmu is None:
        raise UsageError("export: give --ssp FILE.ssp, --osp DIR, --fmu FILE.fmu or more than one")
    if args.fmu is not None and args.fmu.suffix.lower() != ".fmu":
        raise UsageError(f"export --fmu {args.fmu}: the file an FMU is written to ends in .fmu")
    if args.fmi2_warnings and args.warnings_as_ok:
        raise UsageError("export: --fmi2-warnings and --warnings-as-ok contradict each other: give one")
    for option, folder in (("--ssp", args.ssp.parent if args.ssp else None), ("--osp", args.osp),
                           ("--fmu", args.fmu.parent if args.fmu else None)):
        if folder is not None and (problem := unwritable(folder)):
            raise UsageError(f"{option} {folder}: {problem}")
    from .common import seconds
    from .run import set_values
    overrides, given = set_values(args.set)
    for key, value, label in (("scene.fmi", args.fmi, f"--fmi {args.fmi}"),
                              ("scene.duration", seconds("--duration", args.duration), f"--duration {args.duration}")):
        if value is not None:
            overrides[key], given[key] = value, label
    scene = load_scene(args.scene, overrides, given)
    if args.me and args.fmu is not None:
        if args.osp is not None or args.ssp is not None or args.scene_step:
            raise UsageError("export --fmu FILE --me: the one Model Exchange FMU alone (no --ssp, --osp or "
                             "--scene-step with it)")
        exported = Exported([], [])
    elif args.me:
        if args.osp is not None or args.ssp is None or args.fmi == 3 or args.scene_step:
            raise UsageError("export --me: an SSP archive alone (--ssp), FMI 2.0, no step to measure (libcosim and Ecos "
                             "run no Model Exchange), or the one Model Exchange FMU (--fmu FILE --me)")
        from ..platform.run.portable import export_model_exchange
        exported = export_model_exchange(scene, args.ssp, fmi2_warnings=args.fmi2_warnings)
    elif args.ssp is not None or args.osp is not None:
        exported = export_scene(scene, args.ssp, args.osp, measure=not args.scene_step,
                                fmi2_warnings=args.fmi2_warnings, progress=True)
    else:
        exported = Exported([], [])
    if args.fmu is not None:
        from ..platform.run.portable import export_fmu
        one = export_fmu(scene, args.fmu, fmi=scene.fmi, model_exchange=args.me)
        exported = Exported(exported.files + one.files, exported.lines + one.lines)
    print("\n".join(exported.lines))
    for path in exported.files:
        if path.suffix == ".ssp":
            from ..engine.ssp import ANNOTATION
            print(f"written: {path} (SSP 1.0; our run settings in its annotation '{ANNOTATION}', which other tools "
                  "ignore)")
        elif path.suffix == ".fmu":
            interface = "Model Exchange" if args.me else "Co-Simulation"
            print(f"written: {path} (FMI {scene.fmi}.0 {interface}, the whole scene: `cosim run {path.name}`, fmpy, "
                  "fmusim, OMSimulator and any tool that imports an FMU run it)")
        elif path.suffix == ".lua":
            print(f"written: {path} (OMSimulator's script for it: `OMSimulator {path.name}` in its folder)")
        else:
            print(f"written: {path} and the FMUs beside it (OSP; libcosim runs it with its fixed-step or ECCO algorithm "
                  "and no input derivatives; libcosimpy 0.0.6 loads a file with more than one power bond only once "
                  "its parser is fixed, see cosim.engine.osp)")
    return 0


# ---- cosim export-check: the steps of any SSP system's export ----

def add_check(commands) -> argparse.ArgumentParser:
    check = commands.add_parser("export-check", help="measure the step each other tool gets for an SSP system and "
                                "write it into the archive")
    check.add_argument("system", type=Path, help="an SSP 1.0 archive (.ssp)")
    check.add_argument("--dry-run", action="store_true", help="print the table, leave the archive as it is")
    return check


def main_check(args: argparse.Namespace) -> int:
    from ..engine.outcome import RunStopped
    from ..engine.ssp import read_ssp, write_tool_steps
    from ..engine.tools import FIT_TOLERANCE, FLOOR, SYSTEM_HEADER, TOOL_MASTERS, check_system, fmi3_lines, system_row
    from .common import unwritable
    if args.system.suffix.lower() != ".ssp":
        raise UsageError(f"export-check {args.system}: an SSP archive (.ssp) is needed")
    if not args.dry_run and (problem := unwritable(args.system.parent)):
        raise UsageError(f"export-check {args.system}: {problem}")
    structure = read_ssp(args.system)
    try:
        duration, steps = check_system(structure)
    except RunStopped as failure:
        print(f"error: {args.system}: the system's own coupling at a 16th of its step did not run through the "
              f"probe, so nothing can be measured against it: {failure}")
        return 1
    print(f"the step each tool gets, measured by its master in our engine over the first {duration:g} s against "
          f"the system's own coupling at a 16th of its step ({structure.experiment.step:g} s; every recorded output "
          f"within {FIT_TOLERANCE:.0%} of its own range), halving down to 1/{FLOOR}:")
    print("\n".join([*SYSTEM_HEADER, *(system_row(s) for s in steps)]))
    if len(steps) < len(TOOL_MASTERS):  # a system of FMI 3.0 FMUs
        print("\n".join(fmi3_lines()))
    if not args.dry_run:
        write_tool_steps(args.system, [(s.master.tool, s.step, s.within) for s in steps], structure.experiment.step)
        print(f"written: the steps into {args.system} (OMSimulator's system annotation, the OSP annotation's base "
              f"step, each tool's cosim:ToolStep)")
    return 0


export_check = SimpleNamespace(add=add_check, main=main_check)  # the command, beside `cosim export`
