"""The live view (`cosim view SCENE --live`) in a real browser: headless Chromium (Debian's, as
the report's browser test) opens the page while a paced run streams to it; over the DevTools
protocol the test reads what the page shows during the run: the stream's figures counting
samples, the platform drawn where the run has it and moving, and no page error (every message is
JSON a browser parses: no NaN on the wire)."""

from __future__ import annotations

import asyncio
import json
import os
import shutil
import socket
import subprocess
import threading
import time

import numpy as np
import pytest
from test_live import free_port, scene

import cosim

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
if CHROMIUM is None and os.environ.get("CI"):
    raise RuntimeError("chromium is missing: scripts/test.sh installs Debian's chromium for this test")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="no chromium (scripts/test.sh installs it)")

SHOWN = """(() => {
  const view = document.getElementById('platform-view');
  const platform = ((view && view.data) || []).find(t => t.name === 'platform');
  const figures = {};
  for (const row of document.querySelectorAll('#figures tr'))
    figures[row.querySelector('th').innerText] = row.querySelector('td').innerText;
  return JSON.stringify({figures: figures, x: platform ? Array.from(platform.x).slice(0, 6) : null});
})()"""


def free_tcp_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_the_live_view_shows_the_streamed_platform_moving_in_chromium(tmp_path):
    import tornado.httpclient
    import tornado.websocket

    from cosim.platform.realtime.view import serve
    from cosim.platform.run.compile import scene_values
    path = scene(tmp_path, duration=3.0)
    stream, ports, stop = f"udp://127.0.0.1:{free_port()}", [], threading.Event()
    server = threading.Thread(target=serve, args=(scene_values(cosim.load(path))[0], "live view test", stream, 0),
                              kwargs=dict(ready=ports.append, stop=stop), daemon=True)
    server.start()
    for _ in range(200):
        if ports:
            break
        time.sleep(0.05)
    debugging = free_tcp_port()
    browser = subprocess.Popen([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                                f"--remote-debugging-port={debugging}", f"--user-data-dir={tmp_path / 'profile'}",
                                f"http://127.0.0.1:{ports[0]}/"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    async def watch():
        client = tornado.httpclient.AsyncHTTPClient()
        for _ in range(200):  # the browser's DevTools endpoint, then the page in it
            try:
                pages = json.loads((await client.fetch(f"http://127.0.0.1:{debugging}/json/list")).body)
                page = next(p for p in pages if p.get("type") == "page" and str(ports[0]) in p.get("url", ""))
                break
            except (OSError, StopIteration, tornado.httpclient.HTTPClientError):
                await asyncio.sleep(0.1)
        devtools = await tornado.websocket.websocket_connect(page["webSocketDebuggerUrl"], max_message_size=1 << 26)
        calls, errors = [0], []

        async def call(method, **params):
            calls[0] += 1
            devtools.write_message(json.dumps({"id": calls[0], "method": method, "params": params}))
            while True:
                message = json.loads(await asyncio.wait_for(devtools.read_message(), 10))
                if message.get("method") == "Runtime.exceptionThrown":
                    errors.append(message["params"]["exceptionDetails"])
                elif message.get("method") == "Runtime.consoleAPICalled" and message["params"]["type"] == "error":
                    errors.append(message["params"]["args"])
                if message.get("id") == calls[0]:
                    return message["result"]

        await call("Runtime.enable")
        for _ in range(100):  # the page has loaded and opened its WebSocket
            shown = json.loads((await call("Runtime.evaluate", expression=SHOWN, returnByValue=True))["result"]["value"])
            if shown["figures"]:
                break
            await asyncio.sleep(0.1)
        running = asyncio.ensure_future(asyncio.to_thread(cosim.simulate, path, real_time=1.0, stream=stream))
        snapshots = []
        while not running.done():
            await asyncio.sleep(0.25)
            result = await call("Runtime.evaluate", expression=SHOWN, returnByValue=True)
            snapshots.append(json.loads(result["result"]["value"]))
        await asyncio.sleep(0.5)
        await call("Runtime.evaluate", expression="1")  # the last events
        devtools.close()
        return await running, snapshots, errors

    try:
        run, snapshots, errors = asyncio.run(watch())
    finally:
        browser.terminate()
        browser.wait(10)
        stop.set()
        server.join(5)
    assert not errors, errors
    counted = [int(s["figures"]["samples"]) for s in snapshots if s["figures"].get("samples", "0 ").isdigit()]
    # read while the run went on (a busy 2-core machine draws the 3D view slowly: a few reads suffice)
    assert len(counted) >= 2 and 0 < counted[0] < counted[-1] and counted == sorted(counted)
    drawn = [tuple(s["x"]) for s in snapshots if s["x"] and s["figures"].get("samples", "0 ").isdigit()]
    assert len(set(drawn)) >= 2  # the platform moved on the page
    x = np.array([np.mean(d) for d in drawn])
    assert np.ptp(x) > 0.002  # by the run's sine in x (20 mm)
    assert np.ptp(run["pose.x"]) > 0.03


def test_a_second_run_on_the_stream_has_figures_of_its_own_and_the_page_no_missing_icon():
    """The view's figures start again with a new run (its sequence starts again at 0): samples and
    gaps are the new run's, not added to the last one's; a browser's /favicon.ico is answered (204,
    no content) rather than a 404 in its console."""
    import tornado.httpclient
    from cosim.engine.realtime.datagrams import Sample
    from cosim.platform.realtime.view import Follower, make_app
    from cosim.platform.report.view3d import Geometry
    follower = Follower()
    wall = time.time()
    for k in (0, 1, 2, 5):  # a first run with one gap
        follower.add(Sample(k, k * 1e-3, wall + k * 1e-3, ("pose.z",), np.zeros(1)))
    assert follower.figures()["samples"] == "4" and follower.figures()["gaps in the sequence"] == "1"
    for k in (0, 1):  # the next run
        follower.add(Sample(k, k * 1e-3, wall + 1 + k * 1e-3, ("pose.z",), np.zeros(1)))
    assert follower.figures()["samples"] == "2" and follower.figures()["gaps in the sequence"] == "0"
    app = make_app(Geometry.of({}), follower, "test", "udp://127.0.0.1:9")

    async def fetch() -> int:
        port = free_port_tcp()
        server = app.listen(port, address="127.0.0.1")
        try:
            response = await tornado.httpclient.AsyncHTTPClient().fetch(f"http://127.0.0.1:{port}/favicon.ico")
            return response.code
        finally:
            server.stop()

    assert asyncio.run(fetch()) == 204


def free_port_tcp() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]
