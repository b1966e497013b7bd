"""The platform live in the browser (`cosim view SCENE --live udp://HOST:PORT`): the 3D view of the
run report following a run's stream (cosim.engine.realtime), pushed to the page over a local
WebSocket (tornado's, which Dask already brings).

A thread receives the stream and keeps the newest sample; the server draws it `rate` times a second
(the same traces as the report's view: legs coloured by their stroke, the reference as a ghost)
and sends them with the stream's figures: samples received, gaps in the sequence, how far the run
is behind its first sample's pace (its wall clock against its simulated time, at the run's real-time
factor) and how long a sample takes from the run to this view. Serves 127.0.0.1 only.
"""

from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass, field
from typing import Callable, Mapping

import numpy as np

from ...engine.realtime import Sample, receive
from ..ports import POSE
from ..report.view3d import Geometry, _traces, figure, frames


@dataclass
class Follower:
    """The newest sample of a stream and what the stream did so far."""
    factor: float = 1.0
    latest: Sample | None = None
    received: int = 0
    gaps: int = 0
    behind: list[float] = field(default_factory=list)  # per sample of the last second: behind the first's pace [s]
    delay: list[float] = field(default_factory=list)   # sent to received [s]
    first: tuple[float, float] | None = None           # (simulated time, wall clock) of the first sample

    def add(self, sample: Sample) -> None:
        now = time.time()
        if self.latest is not None and sample.sequence < self.latest.sequence:  # a new run: figures of its own
            self.latest, self.received, self.gaps, self.behind, self.delay, self.first = None, 0, 0, [], [], None
        if self.latest is not None and sample.sequence != self.latest.sequence + 1:
            self.gaps += 1
        if self.first is None:
            self.first = (sample.time, sample.wall)
        self.latest, self.received = sample, self.received + 1
        self.behind = (self.behind + [(sample.wall - self.first[1]) - (sample.time - self.first[0]) / self.factor])[-1000:]
        self.delay = (self.delay + [now - sample.wall])[-1000:]

    def figures(self) -> dict[str, str]:
        if self.latest is None:
            return {"samples": "0 (waiting for the stream)"}
        behind = np.asarray(self.behind)
        return {"simulated time [s]": f"{self.latest.time:.3f}", "samples": f"{self.received}",
                "gaps in the sequence": f"{self.gaps}",
                "behind the clock, now / largest of the last 1000 [ms]": f"{1e3 * behind[-1]:.3f} / {1e3 * behind.max():.3f}",
                "stream to view, median [ms]": f"{1e3 * float(np.median(self.delay)):.3f}"}


def poses(sample: Sample) -> tuple[np.ndarray, np.ndarray]:
    """The pose and its reference a sample carries."""
    return (np.array([sample[f"pose.{a}"] for a in POSE]), np.array([sample[f"pose_ref.{a}"] for a in POSE]))


def traces(geometry: Geometry, sample: Sample) -> list[dict]:
    """The view's traces (after the base) at a sample, as plain JSON (a gap in a trace, NaN, as
    null: JSON has no NaN, and a browser's JSON.parse refuses it)."""
    pose, reference = poses(sample)
    f = frames(geometry, np.array([sample.time]), pose[None], reference[None])
    return _plain(_traces(geometry, f, 0, 0.0))


def _plain(value):
    """`value` with numpy's arrays and numbers as JSON's, every non-finite number as None."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return [_plain(v) for v in value.tolist()]
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        value = value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{title} (live)</title><script>{plotly}</script>
<style>body{{font-family:sans-serif;margin:1.5em;max-width:1200px}} table{{border-collapse:collapse}}
th,td{{border:1px solid #ccc;padding:3px 8px;text-align:left;font-size:0.9em}}</style></head><body>
<h1>{title}: live from {address}</h1><table id="figures"></table>{view}
<script>
var view = document.getElementById('platform-view');
var socket = new WebSocket('ws://' + location.host + '/ws');
socket.onmessage = function (event) {{
  var message = JSON.parse(event.data);
  var rows = '';
  for (var name in message.figures) rows += '<tr><th>' + name + '</th><td>' + message.figures[name] + '</td></tr>';
  document.getElementById('figures').innerHTML = rows;
  if (message.traces) {{
    var data = [view.data[0]].concat(message.traces);
    Plotly.react(view, data, view.layout);
  }}
}};
</script></body></html>"""


def make_app(geometry: Geometry, follower: Follower, title: str, address: str, rate: float = 25.0):
    """The tornado application: the page at /, the traces and figures pushed on /ws."""
    import tornado.web
    import tornado.websocket
    from plotly.offline import get_plotlyjs
    from ..report.view3d import html_div
    neutral = geometry.core.neutral_pose
    still = frames(geometry, np.zeros(1), neutral[None], None)
    fig = figure(geometry, still, title)
    fig["frames"], fig["layout"]["sliders"], fig["layout"]["updatemenus"] = [], [], fig["layout"]["updatemenus"][1:]
    fig["layout"]["uirevision"] = "live"  # the camera stays where the user turned it
    page = PAGE.format(title=title, plotly=get_plotlyjs(), address=address, view=html_div(fig))
    clients: set = set()

    class Page(tornado.web.RequestHandler):
        def get(self):
            self.write(page)

    class Push(tornado.websocket.WebSocketHandler):
        def open(self):
            clients.add(self)

        def on_close(self):
            clients.discard(self)

    shown = {"sequence": None}

    def push():
        if not clients:
            return
        sample = follower.latest
        message = {"figures": follower.figures()}
        if sample is not None and sample.sequence != shown["sequence"]:
            message["traces"] = traces(geometry, sample)
            message["time"] = sample.time
            shown["sequence"] = sample.sequence
        text = json.dumps(message, allow_nan=False)
        for client in list(clients):
            client.write_message(text)

    class NoIcon(tornado.web.RequestHandler):  # a browser's /favicon.ico: none, and no error for it
        def get(self):
            self.set_status(204)

    app = tornado.web.Application([(r"/", Page), (r"/ws", Push), (r"/favicon.ico", NoIcon)])
    app.push, app.period_ms = push, 1000.0 / rate
    return app


def serve(values: Mapping[str, object], title: str, address: str, port: int = 8765, factor: float = 1.0,
          ready: Callable[[int], None] | None = None, stop: threading.Event | None = None) -> None:
    """Serves the live view of the stream at `address` on http://127.0.0.1:port until `stop` is set
    (or forever); `ready(port)` once it listens (port 0: a free one)."""
    import asyncio

    import tornado.ioloop
    from ...engine.errors import UsageError
    follower = Follower(factor)
    ended = stop or threading.Event()
    bound, failed = threading.Event(), []

    def follow():
        try:
            for sample in receive(address, ready=bound.set, until=ended):
                follower.add(sample)
        except OSError as error:  # the address is taken, or not this machine's
            failed.append(error)
            bound.set()

    receiver = threading.Thread(target=follow, daemon=True)
    receiver.start()
    bound.wait(10)
    if failed:
        raise UsageError(f"--live {address}: {failed[0].strerror or failed[0]}")
    geometry = Geometry.of(values)

    async def main():
        app = make_app(geometry, follower, title, address)
        server = app.listen(port, address="127.0.0.1")
        chosen = next(iter(server._sockets.values())).getsockname()[1]
        pusher = tornado.ioloop.PeriodicCallback(app.push, app.period_ms)
        pusher.start()
        if ready is not None:
            ready(chosen)
        while not ended.is_set():
            await asyncio.sleep(0.1)
        pusher.stop()
        server.stop()

    try:
        asyncio.run(main())
    finally:
        ended.set()
        receiver.join(2)
