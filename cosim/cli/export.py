"""`cosim export SCENE --ssp FILE.ssp --osp DIR`: the scene's whole system for other FMI tools, as an
SSP 1.0 archive and/or an OSP configuration (libcosim)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..engine.errors import UsageError
from ..engine.ssp import ANNOTATION
from .common import unwritable


def add(commands) -> argparse.ArgumentParser:
    export = commands.add_parser("export", help="write a scene as an SSP 1.0 archive (FMUs, parameters, wiring)")
    export.add_argument("scene", type=Path)
    export.add_argument("--ssp", type=Path, help="the .ssp file to write")
    export.add_argument("--osp", type=Path, help="a folder for OspSystemStructure.xml and the FMUs (libcosim)")
    export.add_argument("--warnings-as-ok", action="store_true",
                        help="every FMU returns fmi2OK where it logs a warning (fmi.warnings_as_ok), for tools that "
                             "stop on fmi2Warning such as OMSimulator; the warnings stay in the log")
    return export


def main(args: argparse.Namespace) -> int:
    from ..engine import ParameterError
    from ..engine.checks import check_parameters
    from ..engine.osp import write_osp
    from ..engine.ssp import not_portable, write_ssp
    from ..platform.run.compile import scene_structure
    from ..platform.run.errors import scene_error
    from ..platform.scene import load_scene
    if args.ssp is None and args.osp is None:
        raise UsageError("export: give --ssp FILE.ssp, --osp DIR or both")
    for option, folder in (("--ssp", args.ssp.parent if args.ssp else None), ("--osp", args.osp)):
        if folder is not None and (problem := unwritable(folder)):
            raise UsageError(f"{option} {folder}: {problem}")
    scene = load_scene(args.scene)
    structure = scene_structure(scene)
    if args.warnings_as_ok:
        for component in structure.components:
            component.parameters["fmi.warnings_as_ok"] = True
        print("note: every FMU returns fmi2OK where it logs a warning (fmi.warnings_as_ok = true): a tool that "
              "stops on fmi2Warning (OMSimulator) runs on past a leg out of its stroke; the warnings stay in the "
              "FMUs' log")
    try:
        check_parameters(structure)
    except ParameterError as error:
        raise scene_error(scene, error) from None
    if args.ssp is not None:
        print(f"written: {write_ssp(structure, args.ssp)} (SSP 1.0; our run settings in its annotation "
              f"'{ANNOTATION}', which other tools ignore)")
    for note in not_portable(structure.settings):
        print(f"note: other tools run this system without {note}")
    if args.osp is not None:
        print(f"written: {write_osp(structure, args.osp)} and the FMUs beside it (OSP; libcosim runs it with its "
              f"fixed-step or ECCO algorithm and no input derivatives; libcosimpy 0.0.6 loads a file with "
              f"more than one power bond only once its parser is fixed, see cosim.engine.osp)")
    return 0
