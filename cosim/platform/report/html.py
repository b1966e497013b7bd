"""The interactive run report, out/<scene>.html: one self-contained file that works offline (plotly's
JavaScript is embedded, nothing is fetched): the scene, the run summary, zoomable plots of every
recorded output, the FMUs' warnings, and for a failed run where and why it stopped.

Every number in the summary is also in the page's `data-value` attributes, so a test can check the
page against the run.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from ..ports import POSE
from ...engine.files import write_text
from .plots import units
from .view3d import SYNC_SCRIPT as VIEW_SYNC

BUCKETS = 700  # per trace: each bucket's first, smallest and largest point (every peak and shock kept)


def _decimated(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """At most 3 BUCKETS points of (t, y) that keep every bucket's extremes (the CSV has every row)."""
    n = len(t)
    if n <= 3 * BUCKETS:
        return t, y
    edges = np.linspace(0, n, BUCKETS + 1).astype(int)
    keep = [edges[:-1], [n - 1]]
    for a, b in zip(edges[:-1], edges[1:]):
        if b > a:
            keep.append([a + int(np.argmin(y[a:b])), a + int(np.argmax(y[a:b]))])
    index = np.unique(np.concatenate([np.asarray(k, dtype=int) for k in keep]))
    return t[index], y[index]


def _trace(t, y, name, **line):
    import plotly.graph_objects as go
    x, v = _decimated(t, np.asarray(y))
    return go.Scatter(x=x, y=v, name=name, mode="lines", line=line or None)


def _figures(result: np.ndarray, units: dict[str, str]) -> list[tuple[str, object]]:
    """(title, plotly figure) of every recorded output: pose against reference per DOF, each drive
    quantity for the six legs, each other output alone; units by variable name, as the FMUs
    declare them (cosim.platform.report.plots.units)."""

    def axis(name: str) -> str:
        unit = units.get(name.split("[")[0])
        return f"{name} [{unit}]" if unit else name

    import plotly.graph_objects as go
    rows = result
    t = rows["time"]
    names = list(result.dtype.names[1:])
    figures, used = [], set()
    for a in POSE:
        if f"pose.{a}" in names:
            fig = go.Figure([_trace(t, rows[f"pose_ref.{a}"], "reference", dash="dash"),
                             _trace(t, rows[f"pose.{a}"], "actual")])
            fig.update_layout(yaxis_title=axis(f"pose.{a}"))
            figures.append((f"pose {a}", fig))
            error = go.Figure([_trace(t, 1e3 * (rows[f"pose.{a}"] - rows[f"pose_ref.{a}"]), "error")])
            error.update_layout(yaxis_title=f"{a} error [{'mm' if a in 'xyz' else 'mrad'}]")
            figures.append((f"tracking error {a}", error))
            used |= {f"pose.{a}", f"pose_ref.{a}"}
    per_leg = sorted({n.split("[")[0] for n in names if n.endswith(("[1]", "[2]", "[3]", "[4]", "[5]", "[6]"))
                      and not n.startswith("leg")})
    for quantity in per_leg:
        legs = [n for n in names if n.startswith(f"{quantity}[")]
        fig = go.Figure([_trace(t, rows[n], f"leg {n.split('[')[1].rstrip(']')}") for n in legs])
        fig.update_layout(yaxis_title=axis(quantity))
        figures.append((f"drive {quantity}", fig))
        used |= set(legs)
    for name in names:
        if name not in used:
            fig = go.Figure([_trace(t, rows[name], name)])
            fig.update_layout(yaxis_title=axis(name))
            figures.append((name, fig))
    for _, fig in figures:
        fig.update_layout(height=320, margin=dict(l=60, r=20, t=30, b=40), xaxis_title="time [s]",
                          template="plotly_white")
    return figures


def _table(rows: list[tuple[str, str, str]]) -> str:
    """(label, shown text, exact value) rows as an HTML table with data-value attributes."""
    cells = "".join(f'<tr><th>{html.escape(label)}</th><td data-name="{html.escape(label)}" '
                    f'data-value="{html.escape(value)}">{html.escape(shown)}</td></tr>' for label, shown, value in rows)
    return f"<table>{cells}</table>"


def write_report(path: Path, scene, result: np.ndarray, report, messages, bond_residuals: dict[str, float],
                 mechanics_values: dict | None = None) -> Path:
    """Writes the report of a run (`report`: the platform's RunReport; `messages`: (instance,
    LogMessage) of everything the FMUs logged; `mechanics_values`: the platform's, for the 3D view)."""
    import plotly.io as pio
    from plotly.offline import get_plotlyjs
    bonds = [(f"bond {name} [J]", f"{value:.3e}", repr(value)) for name, value in bond_residuals.items()]
    warnings = [(m.time, instance, m.text) for instance, m in messages if m.status in ("warning", "error", "fatal")]
    figures = _figures(result, units(scene.drive))
    plots = "\n".join(f'<section class="plot"><h3>{html.escape(title)}</h3>'
                      f'{pio.to_html(fig, full_html=False, include_plotlyjs=False, config=dict(responsive=True))}'
                      f'</section>' for title, fig in figures)
    failure = (f'<div class="failure" data-name="failure"><h2>The run stopped</h2><p>{html.escape(report.failure)}</p>'
               f'</div>') if report.failure else ""
    view = _view(scene, result, report, mechanics_values) if mechanics_values is not None and len(result) > 1 else ""
    warning_rows = "".join(f"<tr><td>{t:.6g}</td><td>{html.escape(i)}</td><td>{html.escape(text)}</td></tr>"
                           for t, i, text in warnings)
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{html.escape(report.scene)}</title>
<script>{get_plotlyjs()}</script>
<style>body{{font-family:sans-serif;margin:1.5em;max-width:1200px}} table{{border-collapse:collapse;margin:0.5em 0}}
th,td{{border:1px solid #ccc;padding:3px 8px;text-align:left;font-size:0.9em}} .failure{{background:#fee;
border:1px solid #c00;padding:0.5em 1em}} .plot{{margin-top:1em}} h3{{margin:0.3em 0;font-size:1em}}</style>
</head><body>
<h1>{html.escape(report.scene)}</h1>
{failure}
{view}
<h2>Scene</h2>{_table(_scene_rows(scene))}
<h2>Run</h2>{_table(_summary_rows(report))}
{_pacing(report.pacing) if report.pacing is not None else ""}
{_perception(report.perceived) if getattr(report, "perceived", None) is not None else ""}
<h2>Power bonds: largest energy residual in one step</h2>{_table(bonds)}
<h2>Warnings and errors from the FMUs ({len(warnings)})</h2>
<table class="warnings"><tr><th>step start [s]</th><th>instance</th><th>message</th></tr>{warning_rows}</table>
<h2>Every recorded output ({len(figures)} plots; drag to zoom, double-click to reset)</h2>
{plots}
{VIEW_SYNC if view else ""}
</body></html>
"""
    return write_text(path, page, "the interactive report")


def _summary_rows(report) -> list[tuple[str, str, str]]:
    """The run's numbers: steps, times, energy residual, tracking error, the twin's windows."""
    rows = [
        ("macro steps", f"{report.macro_steps}", repr(report.macro_steps)),
        ("rejected steps", f"{report.rejected_steps}", repr(report.rejected_steps)),
        ("step control", report.step_control, report.step_control),
        ("simulated [s]", f"{report.simulated:g}", repr(report.simulated)),
        ("wall time [s]", f"{report.wall:.3f}", repr(report.wall)),
        ("real-time factor", f"{report.real_time_factor:.1f}", repr(report.real_time_factor)),
        ("master share of wall time", f"{100 * report.master_share:.0f} %", repr(report.master_share)),
        ("largest energy residual of a bond in one step [J]", f"{report.largest_energy_residual:.3e}",
         repr(report.largest_energy_residual)),
    ]
    rows += [(f"largest tracking error {a} [{'m' if a in 'xyz' else 'rad'}]", f"{e:.3e}", repr(float(e)))
             for a, e in zip(POSE, report.largest_error)]
    rows += [(f"against the converged twin, {name}: pose [m, rad] / efforts / of their change",
              f"{pose:.1e} / {effort:.1e} / {100 * relative:.2f} %", repr(relative))
             for name, pose, effort, relative in report.windows]
    return rows


def _pacing(pacing) -> str:
    """A real-time run's figures (cosim.engine.realtime.Pacing): lateness, overruns, the stream and
    the live input, and the lateness histogram."""
    import plotly.graph_objects as go
    import plotly.io as pio
    rows = [(line.split(":")[0], line, line) for line in pacing.lines()]
    if pacing.factor is not None and len(pacing.lateness):
        p50, p99, largest = pacing.percentiles()
        rows = [("lateness of a step's start p50 / p99 / largest [ms]", f"{1e3 * p50:.3f} / {1e3 * p99:.3f} / "
                 f"{1e3 * largest:.3f}", repr((p50, p99, largest))),
                ("steps that overran their deadline", f"{pacing.overruns} of {len(pacing.finish)}",
                 repr(pacing.overruns)), *rows[1:]]
        counts, edges = pacing.histogram(40)
        figure = go.Figure(go.Bar(x=1e3 * 0.5 * (edges[:-1] + edges[1:]), y=counts, name="steps"))
        figure.update_layout(height=260, margin=dict(l=50, r=20, t=10, b=40), xaxis_title="lateness [ms]",
                             yaxis_title="steps", yaxis_type="log")
        histogram = pio.to_html(figure, full_html=False, include_plotlyjs=False, config=dict(responsive=True))
    else:
        histogram = ""
    return (f'<h2>Real time: paced at {pacing.factor:g} x the wall clock</h2>' if pacing.factor is not None
            else "<h2>Real time</h2>") + _table(rows) + histogram


def _perception(perceived) -> str:
    """A cueing run judged by perception (cosim.platform.perception): per channel the rms error,
    correlation and cues by kind (spurious, sign error, missing), and the vehicle's motion against
    what the occupant perceives of it and of the platform's."""
    import plotly.graph_objects as go
    import plotly.io as pio
    from ..perception import CHANNELS, UNITS, perceived_error, quality
    channels = quality(perceived)
    rows = [(f"{q.channel} [{q.unit}]: rms error / the vehicle's / correlation / spurious, sign error, missing cues [s]",
             f"{q.rms_error:.3g} / {q.rms_vehicle:.3g} / "
             f"{'constant' if np.isnan(q.correlation) else f'{q.correlation:.2f}'} / "
             f"{q.spurious_time:.2f}, {q.sign_error_time:.2f}, {q.missing_time:.2f}",
             repr(q.rms_error)) for q in channels]
    total = perceived_error(channels)
    rows.append(("perceived error (rms per channel past its threshold, in thresholds, summed)", f"{total:.3f}",
                 repr(total)))
    t, plots = perceived.times, []
    for c, (channel, unit) in enumerate(zip(CHANNELS, UNITS)):
        figure = go.Figure([_trace(t, perceived.vehicle[:, c], "vehicle", color="#999"),
                            _trace(t, perceived.vehicle_perceived[:, c], "perceived in the vehicle", dash="dash",
                                   color="black"),
                            _trace(t, perceived.platform_perceived[:, c], "perceived on the platform")])
        figure.update_layout(height=300, margin=dict(l=60, r=20, t=30, b=40), xaxis_title="time [s]",
                             yaxis_title=f"{channel}{' - g' if c == 2 else ''} [{unit}]", template="plotly_white")
        plots.append(f'<section class="plot"><h3>perceived {html.escape(channel)}</h3>'
                     f'{pio.to_html(figure, full_html=False, include_plotlyjs=False, config=dict(responsive=True))}'
                     f'</section>')
    return ('<h2>Motion cueing: what the occupant feels (otoliths and semicircular canals, the vehicle against the '
            'platform at the head)</h2>' + _table(rows) + "\n".join(plots))


def _scene_rows(scene) -> list[tuple[str, str, str]]:
    """The scene: its file, drives (a user's FMU on its legs), platform, coupling, step, duration."""
    own: dict[str, list[str]] = {}  # a user's drive FMU: the legs it drives
    for leg in range(1, 7):
        if scene.leg_fmu(leg):
            own.setdefault(scene.leg_fmu(leg).name, []).append(str(leg))
    drive = scene.drive + "".join(f", {name} on legs {' '.join(legs)}" for name, legs in own.items())
    return [("scene file", str(scene.path), str(scene.path)), ("drive", drive, scene.drive),
            ("parameter set", scene.parameter_set, scene.parameter_set),
            ("coupling", f"{scene.algorithm.kind}, order {scene.algorithm.order}"
             + (", the drives' interface Jacobians" if scene.interface_jacobian else ""),
             f"{scene.algorithm.kind} {scene.algorithm.order}"),
            ("macro step [s]", f"{scene.step:g}", repr(scene.step)),
            ("duration [s]", f"{scene.duration:g}", repr(scene.duration))]


def _view(scene, result: np.ndarray, report, mechanics_values: dict) -> str:
    """The platform in 3D over the run, with what its legs did."""
    from . import view3d
    geometry, frames = view3d.run_frames(mechanics_values, result, scene.pulses)
    out = frames.out_of_stroke.any(axis=0)
    return (f'<h2>The platform ({len(frames.time)} frames; play, drag the slider, or click a plot to go to its '
            f'time)</h2><p>Legs coloured by the stroke they use, red where they leave it'
            f'{" (legs " + ", ".join(str(i + 1) for i in np.flatnonzero(out)) + ")" if out.any() else ""}, dashed '
            f'where a joint passes its angle limit; the reference pose in grey.</p>'
            f'<section class="view">{view3d.html_div(view3d.figure(geometry, frames, report.scene))}</section>')
