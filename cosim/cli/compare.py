"""`cosim compare RUN_A RUN_B [...]`: runs side by side (output folders of `cosim run`, or their
results CSVs): per column, the largest difference of each run from the first over the whole run and
per window of time (the start-up, each load pulse of `--scene` with the time after it, the steady
tracking), each against the first run's own change there, printed and written as compare.csv; the
columns' curves overlaid in compare.html."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..engine.errors import UsageError

# the columns compared unless --columns says: the pose and, per leg, the drives' efforts and currents
DEFAULT_COLUMNS = (*(f"pose.{a}" for a in ("x", "y", "z", "roll", "pitch", "yaw")),
                   *(f"{q}[{i}]" for q in ("torque", "force", "current.q", "current") for i in range(1, 7)))


def add(commands) -> argparse.ArgumentParser:
    compare = commands.add_parser("compare", help="two or more runs side by side: each one's largest differences from "
                                  "the first per column and per window of time, and their curves overlaid")
    compare.add_argument("runs", type=Path, nargs="+", metavar="RUN",
                         help="an output folder of `cosim run` or its results CSV; the first is the reference")
    compare.add_argument("--columns", nargs="+", metavar="COLUMN", help="the columns compared (default: the pose and "
                         "the drives' efforts and currents that every run has)")
    compare.add_argument("--scene", help="the scene the runs are of: its load pulses make windows of their own "
                         "(default: the start-up and the steady tracking)")
    compare.add_argument("--out", type=Path, default=Path("out"), help="folder for compare.csv and compare.html")
    compare.add_argument("--no-plots", action="store_true")
    return compare


def main(args: argparse.Namespace) -> int:
    from ..engine.results import read_results
    from ..platform.run.accuracy import compare, windows
    if len(args.runs) < 2:
        raise UsageError("compare: give two runs or more (output folders or results CSVs); the first is the reference")
    runs: dict[str, object] = {}
    for path in args.runs:
        label = path.stem if path.suffix.lower() == ".csv" else path.name
        label = label if label not in runs else f"{label} ({len(runs) + 1})"
        runs[label] = read_results(path)
    (reference_label, reference), *others = runs.items()
    columns = list(args.columns or [c for c in DEFAULT_COLUMNS if all(c in r.dtype.names for r in runs.values())])
    if not columns:
        columns = [c for c in reference.dtype.names[1:] if all(c in r.dtype.names for r in runs.values())]
    for label, run in runs.items():
        missing = [c for c in columns if c not in run.dtype.names]
        if missing:
            import difflib
            near = difflib.get_close_matches(missing[0], run.dtype.names, 1)
            raise UsageError(f"--columns: run {label} has no column {missing[0]!r}"
                             + (f" (did you mean {near[0]!r}?)" if near else ""))
    if not columns:
        raise UsageError(f"compare: the runs have no column in common but time ({', '.join(runs)})")
    pulses = ()
    if args.scene:
        from ..platform.scene import load_scene
        pulses = load_scene(args.scene).pulses
    spans = windows(float(reference["time"][-1]), pulses)
    rows = compare(reference, dict(others), columns, spans)
    for label, _ in others:
        print(f"{label} against {reference_label} (the reference): the largest difference, where, and of the "
              "reference's own change there")
        for column in columns:
            mine = [r for r in rows if r.run == label and r.column == column]
            whole, parts = mine[0], mine[1:]
            print(f"  {column}: {whole.difference:.3g} at t = {whole.at:.4g} s ({100 * whole.relative:.3g} %)"
                  + "".join(f"; {r.window} {r.difference:.3g} ({100 * r.relative:.3g} %)" for r in parts))
    args.out.mkdir(parents=True, exist_ok=True)
    written = [write_table(rows, args.out / "compare.csv")]
    if not args.no_plots:
        written.append(write_plots(runs, columns, args.out / "compare.html"))
    print("written: " + ", ".join(str(p) for p in written))
    return 0


def write_table(rows, path: Path) -> Path:
    import csv
    import io
    from ..engine.files import write_text
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(["run", "column", "window", "difference", "at", "reference_change", "relative"])
    for r in rows:
        writer.writerow([r.run, r.column, r.window, repr(r.difference), repr(r.at), repr(r.change), repr(r.relative)])
    return write_text(path, text.getvalue(), "the comparison")


def write_plots(runs: dict, columns: list[str], path: Path) -> Path:
    """The columns' curves, one plot each, every run overlaid: a self-contained page."""
    import plotly.graph_objects as go
    import plotly.io as pio
    from plotly.subplots import make_subplots
    from ..engine.files import write_text
    figure = make_subplots(rows=len(columns), cols=1, shared_xaxes=True, subplot_titles=columns,
                           vertical_spacing=min(0.08, 0.5 / max(1, len(columns))))
    for k, (label, run) in enumerate(runs.items()):
        for row, column in enumerate(columns, start=1):
            figure.add_trace(go.Scatter(x=run["time"], y=run[column], name=label, legendgroup=label,
                                        showlegend=row == 1, line=dict(dash="solid" if k == 0 else "dash")),
                             row=row, col=1)
    figure.update_layout(height=260 * len(columns), title="the runs overlaid (the first solid: the reference)")
    figure.update_xaxes(title_text="time [s]", row=len(columns), col=1)
    return write_text(path, pio.to_html(figure, include_plotlyjs=True, full_html=True), "the comparison's plots")
