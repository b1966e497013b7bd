"""The platform in 3D: an animated plotly view of a run for the HTML report, and of a scene's
reference motion alone for `python -m cosim view SCENE`.

What is drawn is the platform the mechanics FMU simulates: its joints, stroke and joint-angle limit
come from the scene's mechanics values through the FMU's own mapping (cosim.platform.core,
the one place the master reads a platform from), so Meng's, Sumnu's and Halder's layouts, and any
geometry a study sets, draw right. Per frame: the base and the platform (its joints joined), the six
legs from lower to upper joint coloured by how much of their stroke they use (red and thick outside
it, dashed past the joint-angle limit), the housing that swings about each lower joint and the motor
it carries (the parts the mechanics models; no motor on Sumnu's linear motors), the reference pose
as a grey ghost, and an external load as an arrow at the platform origin while a pulse acts. Frames are the recorded rows decimated to at
most MAX_FRAMES; play and pause, a time slider, camera presets; in the report a click on any plot
moves the view to that time.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from ...engine.files import write_text
from ..core import Core, mechanics_value
from ..ports import POSE
from .limits import excursion_lines, excursions

MAX_FRAMES = 200
CAMERAS = {"iso": dict(x=1.6, y=-1.6, z=1.1), "front": dict(x=0.0, y=-2.4, z=0.4),
           "side": dict(x=2.4, y=0.0, z=0.4), "top": dict(x=0.0, y=0.0, z=2.6)}
GHOST, BASE, PLATFORM, LOAD = "#9a9a9a", "#34495e", "#2e86c1", "#c0392b"


@dataclass(frozen=True)
class Geometry:
    """The platform drawn: the dynamics core's platform (the mechanics FMU's own mapping of the
    values), its joints, stroke and joint-angle limit, and the parts that swing about each lower
    joint."""
    core: Core
    lower: np.ndarray         # 6 x 3, base frame [m]
    stroke: tuple[float, float]
    joint_limit: float        # [rad]
    housing: float = 0.0      # length of the part that swings about the lower joint (twice its centre of mass) [m]
    motor_at: float | None = None  # the carried motor's centre of mass from the lower joint [m], if it has one

    @classmethod
    def of(cls, values: Mapping[str, object]) -> "Geometry":
        """The platform of these mechanics values (over the FMU's defaults), as the FMU builds it."""
        core = Core(values=values)
        p = core.p
        carries_motor = bool(p.motor_inertia_on) and p.motor_mass > 0
        return cls(core, np.array(p.lower_joint[:]).reshape(6, 3),
                   (float(mechanics_value(values, "limit.leg_length_min")),
                    float(mechanics_value(values, "limit.leg_length_max"))),
                   float(mechanics_value(values, "limit.joint_angle")),
                   2 * p.rotating_com if p.rotating_mass > 0 else 0.0, p.motor_com if carries_motor else None)


@dataclass
class Frames:
    """What the view draws at each frame time: upper joints (actual, reference), leg lengths, stroke
    use, the legs out of stroke or past the joint-angle limit, and the load arrow."""
    time: np.ndarray
    top: np.ndarray            # n x 6 x 3
    ghost: np.ndarray | None   # n x 6 x 3
    length: np.ndarray         # n x 6
    use: np.ndarray            # n x 6: 0 at the shortest, 1 at the longest leg of the stroke
    out_of_stroke: np.ndarray  # n x 6 bool
    past_joint_limit: np.ndarray
    load: np.ndarray           # n x 3: the external force in the base frame [N]
    tilt: np.ndarray | None = None  # n x 6: each leg's larger tilt of its two joints [rad]


def frames(geometry: Geometry, time: np.ndarray, pose: np.ndarray, pose_ref: np.ndarray | None,
           force: np.ndarray | None = None) -> Frames:
    """The frames at these poses (n x 6): the upper joints, the legs' lengths and both joints'
    tilts from the dynamics core (the same kinematics the mechanics FMU integrates)."""
    kinematics = geometry.core.pose_kinematics(pose)
    length = kinematics["length"]
    low, high = geometry.stroke
    tilt = np.maximum(kinematics["lower_angle"], kinematics["upper_angle"])
    return Frames(time, geometry.core.upper_joints_at(pose),
                  None if pose_ref is None else geometry.core.upper_joints_at(pose_ref), length,
                  (length - low) / (high - low), (length < low) | (length > high), tilt > geometry.joint_limit,
                  np.zeros((len(time), 3)) if force is None else force, tilt)


def decimate(time: np.ndarray, most: int = MAX_FRAMES) -> np.ndarray:
    """Indices of at most `most` rows, evenly spaced in time, the first and the last included."""
    if len(time) <= most:
        return np.arange(len(time))
    wanted = np.linspace(time[0], time[-1], most)
    return np.unique(np.clip(np.searchsorted(time, wanted), 0, len(time) - 1))


def _leg_color(use: float, out: bool) -> str:
    if out:
        return "#e60000"
    u = float(np.clip(use, 0.0, 1.0))  # green in the middle of the stroke, amber towards either end
    edge = abs(2 * u - 1)
    return f"rgb({int(40 + 200 * edge)},{int(170 - 40 * edge)},{int(60 - 40 * edge)})"


def _closed(points: np.ndarray) -> dict:
    ring = np.vstack([points, points[:1]])
    return dict(x=np.round(ring[:, 0], 4), y=np.round(ring[:, 1], 4), z=np.round(ring[:, 2], 4))


def _traces(geometry: Geometry, f: Frames, k: int, arrow_scale: float) -> list[dict]:
    """The scatter3d traces of frame k, always in the same order (legs 1-6, platform, ghost, load,
    the housings that swing about the lower joints, the carried motors)."""
    traces = []
    for i in range(6):
        ends = np.vstack([geometry.lower[i], f.top[k, i]])
        traces.append(dict(type="scatter3d", mode="lines", name=f"leg {i + 1}", showlegend=False,
                           x=np.round(ends[:, 0], 4), y=np.round(ends[:, 1], 4), z=np.round(ends[:, 2], 4),
                           line=dict(color=_leg_color(f.use[k, i], bool(f.out_of_stroke[k, i])),
                                     width=12 if f.out_of_stroke[k, i] else 7,
                                     dash="dash" if f.past_joint_limit[k, i] else "solid"),
                           hovertext=f"leg {i + 1}: {f.length[k, i]:.4f} m, {100 * f.use[k, i]:.0f} % of the stroke"
                                     + (" (out of stroke)" if f.out_of_stroke[k, i] else "")
                                     + (" (joint past its limit)" if f.past_joint_limit[k, i] else ""),
                           hoverinfo="text"))
    traces.append(dict(type="scatter3d", mode="lines+markers", name="platform", showlegend=False,
                       line=dict(color=PLATFORM, width=6), marker=dict(size=3, color=PLATFORM),
                       **_closed(f.top[k])))
    ghost = f.ghost[k] if f.ghost is not None else np.full((6, 3), np.nan)
    traces.append(dict(type="scatter3d", mode="lines", name="reference", showlegend=False,
                       line=dict(color=GHOST, width=3, dash="dot"), **_closed(ghost)))
    centre = f.top[k].mean(axis=0)
    tip = centre + arrow_scale * f.load[k] if np.any(f.load[k]) else np.full(3, np.nan)
    traces.append(dict(type="scatter3d", mode="lines+markers", name="load", showlegend=False,
                       x=[centre[0], tip[0]], y=[centre[1], tip[1]], z=[centre[2], tip[2]],
                       line=dict(color=LOAD, width=8), marker=dict(size=[0, 6], color=LOAD)))
    axis = (f.top[k] - geometry.lower) / f.length[k][:, None]
    housing = geometry.lower + axis * np.minimum(geometry.housing, f.length[k])[:, None]
    segments = np.full((18, 3), np.nan)  # lower joint, housing end, gap; per leg
    segments[0::3], segments[1::3] = geometry.lower, housing
    traces.append(dict(type="scatter3d", mode="lines", name="housings", showlegend=False, hoverinfo="skip",
                       x=np.round(segments[:, 0], 4), y=np.round(segments[:, 1], 4), z=np.round(segments[:, 2], 4),
                       line=dict(color="#5d6d7e", width=14)))
    motors = geometry.lower + axis * (geometry.motor_at if geometry.motor_at is not None else np.nan)
    traces.append(dict(type="scatter3d", mode="markers", name="motors", showlegend=False, hoverinfo="skip",
                       x=np.round(motors[:, 0], 4), y=np.round(motors[:, 1], 4), z=np.round(motors[:, 2], 4),
                       marker=dict(size=6, color="#17202a", symbol="square")))
    return traces


def figure(geometry: Geometry, f: Frames, title: str) -> dict:
    """The animated plotly figure (as a plain dict, written without plotly's per-frame validation,
    which costs seconds for 200 frames): the base, then the traces of each frame; a slider, play
    and pause, camera presets."""
    peak = float(np.max(np.linalg.norm(f.load, axis=1), initial=0.0))
    arrow_scale = 0.5 / peak if peak > 0 else 0.0  # the largest load as a 0.5 m arrow
    base = dict(type="scatter3d", mode="lines+markers", name="base", showlegend=False,
                line=dict(color=BASE, width=6), marker=dict(size=3, color=BASE), **_closed(geometry.lower))
    names = [f"{t:.4f}" for t in f.time]
    fig = dict(data=[base, *_traces(geometry, f, 0, arrow_scale)],
               frames=[dict(name=n, data=_traces(geometry, f, k, arrow_scale), traces=list(range(1, 12)))
                       for k, n in enumerate(names)])
    everything = np.vstack([geometry.lower, f.top.reshape(-1, 3)])
    low, high = everything.min(axis=0), everything.max(axis=0)
    span = float(np.max(high - low)) * 0.6 + 0.2
    centre = (low + high) / 2
    axes = {a: dict(range=[centre[k] - span, centre[k] + span], title=dict(text=f"{a} [m]")) for k, a in enumerate("xyz")}
    step = dict(mode="immediate", frame=dict(duration=0, redraw=True), transition=dict(duration=0))
    fig["layout"] = dict(
        title=dict(text=title), height=620, margin=dict(l=0, r=0, t=40, b=0),
        scene=dict(xaxis=axes["x"], yaxis=axes["y"], zaxis=axes["z"], aspectmode="cube",
                   camera=dict(eye=CAMERAS["iso"])),
        updatemenus=[
            dict(type="buttons", direction="left", x=0.0, y=0.0, xanchor="left", yanchor="top", showactive=False,
                 buttons=[dict(label="play", method="animate",
                               args=[None, dict(mode="immediate", fromcurrent=True,
                                                frame=dict(duration=40, redraw=True), transition=dict(duration=0))]),
                          dict(label="pause", method="animate", args=[[None], step])]),
            dict(type="buttons", direction="left", x=1.0, y=1.0, xanchor="right", yanchor="top", showactive=False,
                 buttons=[dict(label=name, method="relayout", args=[{"scene.camera.eye": eye}])
                          for name, eye in CAMERAS.items()])],
        sliders=[dict(active=0, x=0.12, len=0.88, y=0.0, currentvalue=dict(prefix="t = ", suffix=" s"),
                      steps=[dict(label=f"{t:.3g}", method="animate", args=[[n], step])
                             for t, n in zip(f.time, names)])])
    return fig


def run_frames(values: Mapping[str, object], result: np.ndarray, pulses: Sequence = ()) -> tuple[Geometry, Frames]:
    """The frames of a recorded run (its pose and pose_ref columns), decimated, with the loads of
    the scene's pulses (base or platform frame) as arrows."""
    geometry = Geometry.of(values)
    rows = decimate(result["time"])
    time = result["time"][rows]
    pose = np.column_stack([result[f"pose.{a}"][rows] for a in POSE])
    ref = np.column_stack([result[f"pose_ref.{a}"][rows] for a in POSE])
    return geometry, frames(geometry, time, pose, ref, pulse_forces(pulses, time, pose))


def pulse_forces(pulses: Sequence, time: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """The force of the load pulses acting at each time, base frame (a platform-frame pulse turned
    by the pose's orientation)."""
    force = np.zeros((len(time), 3))
    turn = Rotation.from_euler("ZYX", pose[:, [5, 4, 3]])  # R = Rz(yaw) Ry(pitch) Rx(roll), as the mechanics
    for p in pulses:
        if not p.component.startswith("force."):
            continue
        axis = "xyz".index(p.component[-1])
        acting = (time >= p.start) & (time <= p.end)
        local = np.zeros((len(time), 3))
        local[:, axis] = p.value * acting
        force += turn.apply(local) if p.frame == "platform" else local
    return force


def html_div(fig: dict, div_id: str = "platform-view") -> str:
    import plotly.io as pio
    return pio.to_html(fig, full_html=False, include_plotlyjs=False, div_id=div_id, auto_play=False,
                       config=dict(responsive=True), validate=False)


# What the report adds: a click on any 2D plot moves the view to the nearest frame.
SYNC_SCRIPT = """<script>
(function () {
  var view = document.getElementById('platform-view');
  if (!view || !view.layout) return;
  var names = view.layout.sliders[0].steps.map(function (s) { return s.args[0][0]; });
  var times = names.map(parseFloat);
  function show(t) {
    var k = 0;
    for (var i = 1; i < times.length; i++) if (Math.abs(times[i] - t) < Math.abs(times[k] - t)) k = i;
    Plotly.animate(view, [names[k]], {mode: 'immediate', frame: {duration: 0, redraw: true}, transition: {duration: 0}});
    Plotly.relayout(view, {'sliders[0].active': k});
  }
  window.platformView = {show: show, names: names};
  document.querySelectorAll('.plot .js-plotly-plot').forEach(function (plot) {
    plot.on('plotly_click', function (event) { if (event.points.length) show(event.points[0].x); });
  });
})();
</script>"""


def extremes(geometry: Geometry, f: Frames) -> list[str]:
    """Per leg, the shortest and longest it gets against the stroke, then each stretch of time it
    spends past the stroke or the joint-angle limit, with the farthest it went (excursions of the
    reference; `f`: frames at every step of the scene, as a run records them, so that a crossing's
    time is the run's, not a frame's)."""
    low, high = geometry.stroke
    lines = [f"stroke [{low:g}, {high:g}] m, joint-angle limit {np.degrees(geometry.joint_limit):.1f} deg"]
    for i in range(6):
        shortest, longest = f.length[:, i].min(), f.length[:, i].max()
        lines.append(f"leg {i + 1}: {shortest:.4f} to {longest:.4f} m ({100 * f.use[:, i].min():.0f} to "
                     f"{100 * f.use[:, i].max():.0f} % of the stroke)")
    found = excursions(f.time, f.length, f.tilt, geometry.stroke, geometry.joint_limit)
    return lines + excursion_lines(found, subject="the reference past the platform's limits")


def view_samples(duration: float) -> int:
    """How many frames a view of a motion this long shows: one per 20 ms, at most MAX_FRAMES."""
    return max(2, min(MAX_FRAMES, int(duration / 0.02) + 1))


def write_view(scene, values: Mapping[str, object], motion: tuple[np.ndarray, np.ndarray, np.ndarray],
               path, fine: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[object, list[str]]:
    """`python -m cosim view SCENE`: the platform following the scene's reference motion (no
    co-simulation: the pose is the reference; `motion`: times, poses and base-frame load forces at
    view_samples), as a self-contained page; returns its path and the extremes per leg (of `fine`,
    times and poses at the scene's every step, where given; else of the frames)."""
    import html
    from pathlib import Path
    from plotly.offline import get_plotlyjs
    geometry = Geometry.of(values)
    time, pose, force = motion
    f = frames(geometry, time, pose, None, force + pulse_forces([p for p in scene.pulses if p.frame == "platform"],
                                                                 time, pose))
    lines = extremes(geometry, f if fine is None else frames(geometry, fine[0], fine[1], None))
    page = (f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>{html.escape(scene.name)}</title>'
            f'<script>{get_plotlyjs()}</script><style>body{{font-family:sans-serif;margin:1.5em;max-width:1200px}}'
            f'</style></head><body><h1>{html.escape(scene.name)}: the reference motion</h1><p>The platform at the '
            f'pose the scene asks for, before any co-simulation (its trajectory FMU stepped alone).</p><ul>'
            + "".join(f"<li>{html.escape(line)}</li>" for line in lines)
            + f'</ul><section class="view">{html_div(figure(geometry, f, scene.name))}</section></body></html>')
    return write_text(Path(path), page, "the 3D view"), lines
