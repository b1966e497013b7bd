"""The platform in real time, on the loopback: a paced run keeps to the wall clock; a client
receives every streamed sample, equal to the recorded ones bit for bit; a pose sent to a listening
run drives the platform from the next macro step within the scene's limits; bad packets are
counted by kind and refused; a silent sender brings the platform back to neutral. Bounds on wall
time are generous (a shared 2-core machine): they check that the run is paced, not how well."""

from __future__ import annotations

import socket
import struct
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import cosim
from cosim.cli import main
from cosim.engine.errors import UsageError
from cosim.engine.realtime import REFERENCE, Sender, receive
from cosim.platform.core import Core

# Meng's platform in a scene of the tests' own: fixed 1 ms steps, no finer start, a slow sine in
# x (the shipped scenes' numerics may change)
SCENE = """[scene]
name = "real-time test"
duration = {duration}
step = 1e-3

[drive]
kind = "pmsm"

[coupling]
algorithm = "gauss-seidel"
order = 1

[trajectory.x]
sines = [{{amplitude = 0.02, frequency = 0.5}}]
[trajectory.z]
offset = "neutral"

[live]
velocity_max = 0.2
acceleration_max = 2.0
watchdog = {watchdog}
"""
H = 1e-3


def scene(tmp_path: Path, duration: float = 0.3, watchdog: float = 0.5) -> Path:
    path = tmp_path / "realtime.toml"
    path.write_text(SCENE.format(duration=duration, watchdog=watchdog))
    return path


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_a_paced_run_keeps_to_the_wall_clock_and_says_how_late_its_steps_were(tmp_path):
    path = scene(tmp_path, duration=0.4)
    fast = cosim.simulate(path)
    paced = cosim.simulate(path, real_time=1.0, out=tmp_path / "out", plots=True)
    pacing = paced.report.pacing
    assert len(pacing.lateness) == len(paced["time"]) - 2  # every step after the first (the clock starts then)
    # never ahead of the clock: the stepping cannot end before its last deadline (0.399 s after the clock started)
    assert paced.report.wall >= 0.4 - 2 * H
    assert paced.report.wall < 0.4 + 1.0  # and it never silently slows down
    assert fast.report.wall < 0.5 * paced.report.wall
    assert np.all(pacing.lateness >= 0.0)
    for name in ("pose.x", "torque[1]", "current.q[6]"):  # the clock changes no number
        assert np.array_equal(paced[name], fast[name])
    text = paced.report.text()
    assert "paced at 1 x the wall clock: lateness of a step's start p50" in text and "overran" in text
    assert "of the wall time stepping (the rest waiting for deadlines)" in text
    assert 0 < paced.report.busy < 0.5 * paced.report.wall  # it mostly waits: the stepping is much faster
    page = (tmp_path / "out" / "realtime.html").read_text()
    assert "Real time: paced at 1 x the wall clock" in page and "steps that overran their deadline" in page
    twice = cosim.simulate(path, real_time=2.0).report
    assert 0.2 - 2 * H <= twice.wall < 0.2 + 1.0


def received(run, query: str = ""):
    """`run(address)` while a client receives its stream; returns its result and the samples."""
    port, samples, ready = free_port(), [], threading.Event()
    listener = threading.Thread(target=lambda: samples.extend(receive(f"udp://127.0.0.1:{port}", timeout=2.0,
                                                                      ready=ready.set)))
    listener.start()
    ready.wait(10)
    result = run(f"udp://127.0.0.1:{port}{query}")
    listener.join()
    return result, samples


def test_a_client_receives_every_streamed_sample_equal_to_the_recorded_ones(tmp_path):
    run, samples = received(lambda address: cosim.simulate(scene(tmp_path), real_time=1.0, stream=address))
    assert [s.sequence for s in samples] == list(range(len(run["time"]) - 1))  # every step's, no gap, in order
    assert samples[0].names[:3] == ("pose_ref.x", "pose_ref.y", "pose_ref.z") and "leg[6].velocity" in samples[0].names
    assert np.array_equal([s.time for s in samples], run["time"][1:])
    for name in samples[0].names:
        assert np.array_equal([s[name] for s in samples], run[name][1:]), name
    walls = np.array([s.wall for s in samples])
    assert np.all(np.diff(walls) >= 0) and walls[-1] - walls[0] > 0.25  # sent as the clock went
    assert run.report.pacing.streamed == len(samples)


def test_every_nth_step_streams_and_no_receiver_loses_nothing(tmp_path):
    run, samples = received(lambda address: cosim.simulate(scene(tmp_path, duration=0.1), real_time=4.0,
                                                           stream=address), "?every=7")
    assert [s.time for s in samples] == run["time"][1:][6::7].tolist()
    alone = cosim.simulate(scene(tmp_path, duration=0.1), stream=f"udp://127.0.0.1:{free_port()}")  # unpaced, nobody
    assert np.array_equal(alone["pose.x"], run["pose.x"])


def follow(tmp_path: Path, send, duration: float = 0.6, watchdog: float = 0.5, **options):
    """Runs the test scene listening on a free port while `send(address, samples)` talks to it
    from a thread that sees the run's stream; returns the run and what the thread returned."""
    listen, stream = f"udp://127.0.0.1:{free_port()}", f"udp://127.0.0.1:{free_port()}"
    ready, out = threading.Event(), {}

    def client():
        out["value"] = send(listen, receive(stream, timeout=3.0, ready=ready.set))

    thread = threading.Thread(target=client)
    thread.start()
    ready.wait(10)
    run = cosim.simulate(scene(tmp_path, duration, watchdog), real_time=1.0, stream=stream, listen=listen, **options)
    thread.join()
    return run, out.get("value")


def send_once(target, after: float):
    """A client for `follow` that sends `target` once, on seeing the sample at `after` s or later,
    and returns that sample's time."""
    def send(address, samples):
        for sample in samples:
            if sample.time >= after:
                with Sender(address) as sender:
                    sender.send(target)
                for _ in samples:  # drain the stream
                    pass
                return sample.time
    return send


def test_a_pose_sent_at_t_drives_the_platform_from_the_next_macro_step_within_its_limits(tmp_path):
    neutral = Core().neutral_pose
    target = neutral + [0.0, 0.03, 0.04, 0.0, 0.0, 0.05]

    run, seen = follow(tmp_path, send_once(target, 0.1), watchdog=5.0)  # held to the end: the watchdog has its own test
    t, ref = run["time"], np.column_stack([run[f"pose_ref.{a}"] for a in cosim.platform.ports.POSE])
    scene_x = 0.02 * np.sin(2 * np.pi * 0.5 * t)
    moved = np.flatnonzero(np.abs(ref[:, 1] - neutral[1]) > 0)[0]  # y: the scene keeps it at 0
    # sent on seeing the sample at `seen`, it arrives at the earliest during the step from seen + h, is taken after it
    # and moves the reference over the next step: the first row it changes is at seen + 2 h at the earliest (here,
    # where the sender answers within the millisecond, exactly; a busy machine may delay the sender a few steps)
    assert seen + 2 * H - 1e-9 <= t[moved] <= seen + 20 * H + 1e-9
    assert np.array_equal(ref[:moved, 0], scene_x[:moved])  # the scene's own reference until then
    assert run.report.pacing.live["accepted"] == 1
    rate = np.diff(ref[moved - 1:], axis=0) / H
    assert np.abs(rate[:, :3]).max() <= 0.2 * (1 + 1e-9)  # [live] velocity_max
    assert np.abs(np.diff(rate[:, :3], axis=0) / H).max() <= 2.0 * (1 + 1e-6)  # acceleration_max
    assert np.abs(ref[-1] - target).max() < 1e-9  # reached, and held
    assert abs(run["pose.z"][-1] - target[2]) < 2e-3  # and the platform followed


def test_the_live_reference_reaches_the_mechanics_with_its_own_rate_at_order_0(tmp_path):
    """Where the master gives no derivatives (order 0) the mechanics takes the reference's rate from
    its pose_ref_rate inputs: the live input replaces them too, with its own rate. Held at the target
    by the end, the reference's rate is 0, and so every leg's velocity reference, while the scene's
    own sine still moves (the rate it would give: 0.063 cos(pi t) m/s in x)."""
    neutral = Core().neutral_pose
    target = neutral + [0.0, 0.02, 0.02, 0.0, 0.0, 0.0]

    legs = [f"leg[{i}].velocity_ref" for i in range(1, 7)]
    outputs = {"coupling.order": 0, "outputs.mechanics": legs}
    run, _ = follow(tmp_path, send_once(target, 0.05), duration=0.4, watchdog=5.0, overrides=outputs)
    t = run["time"]
    velocity_ref = np.column_stack([run[n] for n in legs])
    assert np.abs(velocity_ref[t < 0.04]).max() > 1e-3  # the scene's sine, before the live input
    assert np.abs(run["pose_ref.y"][-1] - target[1]) < 1e-9  # reached and held
    assert np.abs(velocity_ref[-1]).max() < 1e-9


def test_bad_packets_are_counted_by_kind_and_refused(tmp_path):
    neutral = Core().neutral_pose
    good = neutral + [0.0, 0.0, 0.02, 0.0, 0.0, 0.0]

    def send(address, samples):
        host, port = address[len("udp://"):].split(":")
        raw = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        for sample in samples:
            if sample.time >= 0.1:
                break
        now = sample.time
        with Sender(address) as sender, Sender(address) as intruder:
            sender.send(good)
            time.sleep(0.01)
            sender.sequence = 0
            sender.send(good)                                         # repeated
            sender.sequence = 5
            sender.send(good)                                         # taken (a gap is not a fault)
            sender.sequence = 3
            sender.send(good)                                         # out of order
            sender.sequence = 10
            sender.send(neutral + [0, 0, 1.0, 0, 0, 0])               # a leg past its stroke: taken, held at it
            sender.send([*neutral[:5], np.inf])                       # non-finite
            sender.send(good, time=0.0)                               # late: for t = 0
            sender.send(good, time=now + 1000.0)                      # for a time far beyond the next step
            sender.send(good, rates=[0.0, 0.0, 10.0, 0.0, 0.0, 0.0])  # a rate beyond velocity_max
            intruder.sequence = 2 ** 64 - 1
            intruder.send(good + [0.0, 0.05, 0.0, 0.0, 0.0, 0.0])    # another sender's
            session = sender.session
            for junk in (b"junk", b"CREF" + bytes(28),
                         REFERENCE.pack(b"CREF", 2, 6, session, 99, 0.0) + bytes(40),   # short of its count
                         REFERENCE.pack(b"CREF", 2, 5, session, 99, 0.0) + bytes(40),   # count not 6, 12 or 18
                         REFERENCE.pack(b"CREF", 3, 6, session, 99, 0.0) + bytes(48)):  # an unknown version
                raw.sendto(junk, (host, int(port)))                   # malformed: 5
            raw.sendto(struct.pack("<4sHHQd", b"CREF", 1, 6, 99, 0.0) + bytes(48), (host, int(port)))  # version 1
            time.sleep(0.01)
            sender.send(good)                                         # the last word: taken
        raw.close()
        for _ in samples:
            pass

    run, _ = follow(tmp_path, send, duration=0.8, watchdog=5.0)  # time to spare after the last packet
    live = run.report.pacing.live
    assert live == {"accepted": 3, "outside": 1, "late": 1, "future": 1, "repeated": 1, "out_of_order": 1,
                    "malformed": 5, "old_version": 1, "non_finite": 1, "beyond_limits": 1, "foreign": 1,
                    "unauthenticated": 0, "watchdog": 0}
    assert abs(run["pose_ref.z"][-1] - good[2]) < 1e-12  # the last good reference, reached and held
    assert np.abs(run["pose_ref.y"]).max() == 0.0  # the intruder's y never applied
    line = next(line for line in run.report.text().splitlines() if line.startswith("live input"))
    assert ("4 references taken (1 outside the envelope: held at it); refused: 1 late, 1 for a time beyond the next "
            "step, 1 repeated, 1 out of order, 5 malformed, 1 of the old version 1, 1 non-finite, 1 with rates or "
            "accelerations beyond the limits, 1 from another sender") in line


def test_any_bytes_are_taken_or_refused_none_lost_and_the_run_goes_on(tmp_path):
    from cosim.engine.realtime import reference_datagram
    neutral, rng, sent = Core().neutral_pose, np.random.default_rng(7), 400
    valid = bytearray(reference_datagram(neutral + [0.0, 0.0, 0.02, 0.0, 0.0, 0.0], 1000, None, session=5))

    def send(address, samples):
        host, port = address[len("udp://"):].split(":")
        for sample in samples:
            if sample.time >= 0.05:
                break
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as raw:
            for k in range(sent):  # a few bytes of a good datagram changed at random, or cut short
                mutated = valid[:]
                for at in rng.integers(0, len(valid), size=3):
                    mutated[at] = int(rng.integers(0, 256))
                cut = int(rng.integers(0, len(valid))) if rng.random() < 0.3 else len(valid)
                raw.sendto(bytes(mutated[:cut]), (host, int(port)))
                if k % 50 == 0:
                    time.sleep(0.005)
        for _ in samples:
            pass

    run, _ = follow(tmp_path, send, duration=0.6)
    live = run.report.pacing.live
    assert sum(v for k, v in live.items() if k != "watchdog") == sent  # every datagram counted once
    assert live["malformed"] > 0.3 * sent
    assert live["non_finite"] + live["outside"] + live["repeated"] + live["foreign"] + live["beyond_limits"] > 0
    reference = np.column_stack([run[f"pose_ref.{a}"] for a in cosim.platform.ports.POSE])
    assert np.isfinite(reference).all() and np.isfinite(run["pose.z"]).all()
    assert np.all((Core().leg_lengths(reference[-1]) > 1.535) & (Core().leg_lengths(reference[-1]) < 2.2))


def test_a_silent_sender_brings_the_platform_back_to_neutral(tmp_path):
    neutral = Core().neutral_pose

    def send(address, samples):
        for sample in samples:
            if sample.time >= 0.05:
                break
        with Sender(address) as sender:
            sender.send(neutral + [0.0, 0.0, 0.03, 0.0, 0.0, 0.0])
        for _ in samples:
            pass

    run, _ = follow(tmp_path, send, duration=0.7, watchdog=0.15)
    pacing = run.report.pacing
    assert pacing.live["watchdog"] == 1 and 0.15 < pacing.watchdog_time < 0.6
    z = run["pose_ref.z"]
    assert z.max() - neutral[2] > 0.01  # it went up ...
    assert abs(z[-1] - neutral[2]) < 1e-12  # ... and came back
    assert "the watchdog engaged 1 times" in run.report.text()
    said = [m for n, m in run.report.messages if n == "master"]
    assert len(said) == 1 and "no good live input for 0.15 s: the reference goes back to the neutral pose" in said[0].text
    assert said[0].time == pacing.watchdog_time


@pytest.mark.parametrize("arguments, message", [
    (["--real-time", "fast"], "--real-time fast: expected a real-time factor > 0"),
    (["--real-time", "--stream", "tcp://127.0.0.1:1"], "--stream tcp://127.0.0.1:1: expected udp://HOST:PORT"),
    (["--real-time", "--set", "coupling.step_control=\"doubling\""], "a real-time run takes fixed steps"),
])
def test_wrong_real_time_options_are_one_line(tmp_path, capsys, arguments, message):
    assert main(["run", str(scene(tmp_path)), "--no-plots", "--out", str(tmp_path), *arguments]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_a_run_listening_beyond_this_machine_needs_a_key_and_says_so_first(tmp_path, capsys):
    port, key = free_port(), tmp_path / "live.key"
    key.write_text("0123456789abcdef" * 2)
    run = ["run", str(scene(tmp_path, duration=0.01)), "--no-plots", "--out", str(tmp_path), "--listen"]
    assert main([*run, f"udp://0.0.0.0:{port}"]) == 2  # without a key: refused, one line, nothing run
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "0.0.0.0 is not this machine's loopback" in err and "--listen-key" in err
    with pytest.raises(UsageError, match="0.0.0.0 is not this machine's loopback"):  # the API says the same
        cosim.simulate(scene(tmp_path, duration=0.01), listen=f"udp://0.0.0.0:{port}")
    assert main([*run, f"udp://0.0.0.0:{port}", "--listen-key", str(key)]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first == (f"listening on 0.0.0.0: datagrams from other machines that carry the key of {key} can drive "
                     "this run's platform")
    for loopback in ("127.0.0.1", "127.0.0.2", "localhost"):  # all of 127.0.0.0/8 is this machine's
        assert main([*run, f"udp://{loopback}:{port}"]) == 0
        assert not capsys.readouterr().out.startswith("listening on")
    assert main(["run", str(scene(tmp_path, duration=0.01)), "--listen-key", str(key)]) == 2
    assert "--listen-key goes with --listen" in capsys.readouterr().err


def test_the_stream_layout_lists_every_value_at_its_offset(capsys):
    assert main(["stream-layout", "meng_eq35"]) == 0
    out = capsys.readouterr().out
    assert "uint64   sequence number" in out and "     32  float64  pose_ref.x [m]" in out
    assert "    360  float64  current.q[6] [A]" in out  # 6 + 6 + 12 + 18 values after the 32-byte header
    assert struct.calcsize("<4sHHQdd") == 32


def test_the_live_view_draws_the_streamed_platform_in_the_browser(tmp_path):
    import asyncio
    import json

    import tornado.httpclient
    import tornado.websocket

    from cosim.platform.realtime.view import serve
    from cosim.platform.run.compile import scene_values
    path = scene(tmp_path, duration=0.6)
    stream, ports, stop = f"udp://127.0.0.1:{free_port()}", [], threading.Event()
    values = scene_values(cosim.load(path))[0]
    server = threading.Thread(target=serve, args=(values, "real-time test", stream, 0), daemon=True,
                              kwargs=dict(ready=ports.append, stop=stop))
    server.start()
    for _ in range(200):
        if ports:
            break
        time.sleep(0.05)
    url = f"127.0.0.1:{ports[0]}"
    messages = []

    async def watch():
        page = await tornado.httpclient.AsyncHTTPClient().fetch(f"http://{url}/")
        assert b"platform-view" in page.body and b"live from " + stream.encode() in page.body
        socket_ = await tornado.websocket.websocket_connect(f"ws://{url}/ws")
        run = await asyncio.to_thread(cosim.simulate, path, real_time=1.0, stream=stream)
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline:
            message = await asyncio.wait_for(socket_.read_message(), 5)
            messages.append(json.loads(message))
            if "traces" in messages[-1] and abs(messages[-1]["time"] - run["time"][-1]) < 1e-12:
                break
        socket_.close()
        return run

    try:
        run = asyncio.run(watch())
    finally:
        stop.set()
        server.join(5)
    drawn = [m for m in messages if "traces" in m]
    assert drawn and drawn[-1]["figures"]["gaps in the sequence"] == "0"
    last = drawn[-1]
    row = int(np.flatnonzero(run["time"] == last["time"])[0])
    pose = np.array([run[f"pose.{a}"][row] for a in cosim.platform.ports.POSE])
    platform = next(t for t in last["traces"] if t["name"] == "platform")
    joints = Core(values=values).upper_joints_at(pose)[0]
    assert np.abs(np.array(platform["x"][:6]) - joints[:, 0]).max() < 1e-4  # drawn rounded to 0.1 mm
    assert np.abs(np.array(platform["z"][:6]) - joints[:, 2]).max() < 1e-4
    assert int(last["figures"]["samples"]) == len(run["time"]) - 1


def test_the_layout_comes_before_the_first_sample(tmp_path):
    """A receiver written from the guide: a raw socket, the first datagram it gets names the columns."""
    port = free_port()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as raw:
        raw.bind(("127.0.0.1", port))
        raw.settimeout(10)
        cosim.simulate(scene(tmp_path, duration=0.02), stream=f"udp://127.0.0.1:{port}")
        first = raw.recv(65535)
        following = raw.recv(65535)
    assert first[:4] == b"CSLY" and b"pose_ref.x\npose_ref.y" in first
    assert following[:4] == b"CSIM" and struct.unpack_from("<Q", following, 8)[0] == 0  # then sample 0
