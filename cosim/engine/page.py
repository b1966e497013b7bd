"""A system's run as a page and a figure (`cosim run FILE.ssp|FILE.fmu`, where a scene's run has the
platform's report): the run's summary, then every recorded output against time, one plot per
component (its outputs overlaid), as a self-contained HTML page <stem>.html and a PNG
<stem>_outputs.png. Any system: the components and their outputs are the plan's record."""

from __future__ import annotations

import html
from pathlib import Path
from typing import Sequence

import numpy as np

from .files import write_text

MOST_PLOTS = 12  # components drawn, at most (the first ones of the record)


def groups(record: Sequence[tuple[str, str]], names: Sequence[str]) -> dict[str, list[str]]:
    """The recorded columns by component, in the record's order."""
    out: dict[str, list[str]] = {}
    for (component, _), name in zip(record, names):
        out.setdefault(component, []).append(name)
    return dict(list(out.items())[:MOST_PLOTS])


def write_page(result: np.ndarray, summary: str, record: Sequence[tuple[str, str]], folder: Path, stem: str) -> list[Path]:
    """<stem>.html and <stem>_outputs.png in `folder` for a run's results; returns their paths."""
    import plotly.graph_objects as go
    import plotly.io as pio
    from plotly.subplots import make_subplots
    by_component = groups(record, list(result.dtype.names[1:]))
    if not by_component or len(result) < 2:
        return []
    figure = make_subplots(rows=len(by_component), cols=1, shared_xaxes=True, subplot_titles=list(by_component),
                           vertical_spacing=min(0.08, 0.5 / len(by_component)))
    for row, (component, columns) in enumerate(by_component.items(), start=1):
        for name in columns:
            figure.add_trace(go.Scatter(x=result["time"], y=result[name], name=name, mode="lines"), row=row, col=1)
    figure.update_layout(height=280 * len(by_component), showlegend=True)
    figure.update_xaxes(title_text="time [s]", row=len(by_component), col=1)
    lines = "".join(f"<li>{html.escape(line)}</li>" for line in summary.splitlines())
    page = (f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>{html.escape(stem)}</title></head>'
            f'<body style="font-family:sans-serif;margin:1.5em;max-width:1200px"><h1>{html.escape(stem)}</h1>'
            f"<ul>{lines}</ul>{pio.to_html(figure, include_plotlyjs=True, full_html=False)}</body></html>")
    written = [write_text(folder / f"{stem}.html", page, "the run's page")]
    written.append(_png(result, by_component, folder / f"{stem}_outputs.png", stem))
    return written


def _png(result: np.ndarray, by_component: dict[str, list[str]], path: Path, title: str) -> Path:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from .files import write_bytes
    import io
    figure, axes = plt.subplots(len(by_component), 1, sharex=True, figsize=(9, 2.2 * len(by_component) + 0.6),
                                squeeze=False)
    for axis, (component, columns) in zip(axes[:, 0], by_component.items()):
        for name in columns:
            axis.plot(result["time"], result[name], label=name, linewidth=0.9)
        axis.set_ylabel(component)
        if len(columns) <= 8:
            axis.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("time [s]")
    figure.suptitle(title)
    figure.tight_layout()
    buffer = io.BytesIO()
    figure.savefig(buffer, dpi=110)
    plt.close(figure)
    return write_bytes(path, buffer.getvalue(), "the run's figure")
