"""`cosim design STUDY`: which platform carries a motion, a configuration design study (studies/,
after Halder et al. Section V): the map, its figures and table, the summary."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import add_cluster, security, workers


def add(commands) -> argparse.ArgumentParser:
    design = commands.add_parser("design", help="which platform carries a motion: a configuration design study "
                                 "(studies/, Halder et al. Section V)")
    design.add_argument("study", help="a study file (TOML) or a shipped study's name, e.g. halder_section5")
    add_cluster(design, "the map", 0)
    design.add_argument("--out", type=Path, default=Path("out"), help="folder for the figures, the map and the summary")
    return design


def main(args: argparse.Namespace) -> int:
    from ..platform.design import load_study, parallel_map, report_rows, summary, write
    from ..platform.design.search.pareto import study_front
    from ..platform.scene import shipped
    count = workers(args)
    study = load_study(shipped(args.study, "studies") or args.study if not Path(args.study).exists() else args.study)
    with security(args):
        design = parallel_map(study, workers=count, scheduler=args.scheduler)
        front = study_front(study, count, args.scheduler)
        rows = report_rows(design, count, args.scheduler, front)
    print("\n".join(summary(design, rows)))
    files = write(design, args.out, rows, front)
    print("written: " + ", ".join(str(f) for f in files))
    return 0
