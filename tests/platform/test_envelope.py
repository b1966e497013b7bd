"""A live platform that cannot be driven out of its envelope (docs/guide/realtime.md): whatever a
sender asks (a pose beyond the stroke, a rate that extrapolates past it, a target just inside it
at full speed, numbers that overflow, a time far ahead, another sender, bytes at random) the
reference the run applies keeps every leg within its stroke less the margin and within the
[live] limits, the platform's own legs within the stroke, and the run goes on. Senders are
written from the guide's datagram table (packet_fuzz.HEADER), not from cosim.realtime."""

from __future__ import annotations

import hashlib
import hmac
import math
import socket
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from packet_fuzz import fuzz, reference
from test_live import free_port, scene

import cosim
from cosim.engine.realtime import receive
from cosim.platform.core import Core
from cosim.platform.ports import POSE
from cosim.platform.realtime import Envelope
from cosim.platform.run.compile import scene_values

STROKE = (1.535, 2.2)
MARGIN = 0.01           # the shipped limit.stroke_margin, stated here: the suite holds the physics, not the default
LIVE = {"live.velocity_max": 0.5, "live.acceleration_max": 5.0, "mechanics.parameters.\"limit.stroke_margin\"": MARGIN}
LEGS = [f"leg[{i}].length" for i in range(1, 7)]


def drive(tmp_path, send, duration: float, overrides=None, model=None, **options):
    """The test scene (or `model`) paced at real time, listening, with [live] limits that reach the
    stroke within its duration; `send(target, now)` talks to it from a thread (now(): the simulated
    time of the newest streamed sample), from the run's first streamed sample on. Returns the run."""
    listen, stream = free_port(), f"udp://127.0.0.1:{free_port()}"
    ready, seen, done = threading.Event(), [0.0], threading.Event()

    def follow():
        for sample in receive(stream, ready=ready.set, until=done):
            seen[0] = sample.time

    follower = threading.Thread(target=follow, daemon=True)
    follower.start()
    ready.wait(10)
    def talk():
        deadline = time.monotonic() + 10
        while seen[0] == 0.0 and time.monotonic() < deadline:  # the run is listening once it streams
            time.sleep(0.002)
        send(("127.0.0.1", listen), lambda: seen[0])

    sender = threading.Thread(target=talk, daemon=True)
    sender.start()
    try:
        run = cosim.simulate(model or scene(tmp_path, duration, watchdog=5.0), duration=duration, real_time=1.0,
                             stream=stream,
                             listen=f"udp://127.0.0.1:{listen}",
                             overrides={**LIVE, "outputs.mechanics": LEGS, **(overrides or {})}, **options)
    finally:
        done.set()
    sender.join(10)
    return run


def reference_of(run) -> np.ndarray:
    return np.column_stack([run[f"pose_ref.{a}"] for a in POSE])


def assert_within_the_envelope(run, model, velocity_max=0.5, acceleration_max=5.0):
    """The applied reference: every leg within the stroke less the margin and every joint within
    its tilt; the pose's rate and acceleration within [live], the legs' speed within
    limit.leg_velocity; the platform's own legs within the stroke."""
    loaded = cosim.load(model, LIVE)
    values = scene_values(loaded)[0]
    envelope, core = Envelope.of(values), Core(values=values)
    low, high = envelope.usable
    # from where the live input took the reference over (the scene's own until then), and for the
    # limits on its rate 0.1 s later: it takes over from the scene's motion, which may be faster
    own = cosim.simulate(loaded, duration=float(run["time"][-1]))
    taken = int(np.flatnonzero(np.any(reference_of(run) != reference_of(own), axis=1))[0])
    settled = int(np.searchsorted(run["time"], run["time"][taken] + 0.1))
    reference = reference_of(run)[taken:]
    kinematics = core.pose_kinematics(reference)
    legs = kinematics["length"]
    assert legs.min() >= low - 1e-6 and legs.max() <= high + 1e-6, (legs.min(), legs.max())
    tilt = np.maximum(kinematics["lower_angle"], kinematics["upper_angle"])
    assert tilt.max() <= envelope.joint_angle + 1e-6
    steps = np.diff(run["time"][settled:])
    rate = np.diff(reference_of(run)[settled:, :3], axis=0) / steps[:, None]
    assert np.abs(rate).max() <= velocity_max * (1 + 1e-6)
    assert np.abs(np.diff(rate, axis=0) / steps[1:, None]).max() <= acceleration_max * (1 + 1e-4)
    assert np.abs(np.diff(legs[settled - taken:], axis=0) / steps[:, None]).max() <= envelope.leg_velocity * (1 + 1e-3)
    actual = np.column_stack([run[n] for n in LEGS])[taken:]
    assert actual.min() >= envelope.stroke[0] and actual.max() <= envelope.stroke[1], (actual.min(), actual.max())
    return legs, actual


def written_scene(tmp_path) -> Path:
    """The test scene's file as drive() writes it (its values: the platform's envelope)."""
    return tmp_path / "realtime.toml"


def test_a_pose_past_the_stroke_is_held_at_the_envelope_and_the_tracking_margin_covers_the_drives(tmp_path):
    """Up at full speed into the top of the stroke, then down into its bottom: the reference stops
    at the stroke less the margin, braking in time, and the platform, which lags its reference
    by the drives' tracking error, stays inside the stroke: the margin covers that error (measured
    here at the [live] limits of 0.5 m/s and 5 m/s^2)."""
    neutral = Core().neutral_pose

    def send(target, now):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            for k in range(400):  # up until t = 1.0 s, then down (by the run's clock)
                z = 0.6 if now() < 1.0 else -0.6
                sock.sendto(reference(11, k, math.nan, neutral + [0, 0, z, 0, 0, 0]), target)
                time.sleep(0.01)
                if now() > 2.75:
                    break

    run = drive(tmp_path, send, 2.8)
    legs, actual = assert_within_the_envelope(run, written_scene(tmp_path))
    assert legs.max() > STROKE[1] - MARGIN - 1e-4 and legs.min() < STROKE[0] + MARGIN + 1e-3  # it went to both ends
    tracking = np.abs(legs - actual).max()
    print(f"tracking error at 0.5 m/s and 5 m/s^2: {1e3 * tracking:.2f} mm of the {1e3 * MARGIN:g} mm margin")
    assert tracking < MARGIN
    assert run.report.pacing.held["the stroke"] > 0
    assert "the envelope held the reference back at" in run.report.text()


def test_a_rate_that_extrapolates_past_the_stroke_is_held_at_the_envelope(tmp_path):
    """The issue's case: a pose just inside the stroke with a rate out of it, sent for a time just
    short of late, at 100 Hz: taken, and its extrapolation braked at the envelope."""
    core, neutral = Core(), Core().neutral_pose
    top = neutral.copy()
    while core.leg_lengths(top).max() < STROKE[1] - 0.001:
        top[2] += 1e-4

    def send(target, now):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            for k in range(120):
                sock.sendto(reference(12, k, now() - 0.09, np.r_[top, 0, 0, 0.5, 0, 0, 0]), target)
                time.sleep(0.01)

    run = drive(tmp_path, send, 1.6)
    assert_within_the_envelope(run, written_scene(tmp_path))
    assert run.report.pacing.live["outside"] > 0  # the pose is inside the stroke but not the envelope


def test_a_target_just_inside_the_envelope_is_reached_without_overshoot(tmp_path):
    core, neutral = Core(), Core().neutral_pose
    target = neutral.copy()
    while core.leg_lengths(target).max() < STROKE[1] - MARGIN - 40e-6:
        target[2] += 1e-5

    def send(address, now):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            sock.sendto(reference(13, 0, math.nan, target), address)

    run = drive(tmp_path, send, 1.5)
    legs, _ = assert_within_the_envelope(run, written_scene(tmp_path))
    assert abs(run["pose_ref.z"][-1] - target[2]) < 1e-9  # reached and held


@pytest.mark.parametrize("time_ahead, rates, kind", [
    (1e300, [0, 0, 1e10, 0, 0, 0], "future"), (1000.0, [0] * 6, "future"), (0.0, [0, 0, 1.79e308, 0, 0, 0],
                                                                          "beyond_limits"),
    (math.nan, [1.79e308] * 6 + [1.79e308] * 6, "beyond_limits")])
def test_numbers_a_controller_would_refuse_are_refused(tmp_path, time_ahead, rates, kind):
    neutral = Core().neutral_pose

    def send(address, now):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            time.sleep(0.05)
            sock.sendto(reference(14, 0, now() + time_ahead, np.r_[neutral + [0, 0, 0.01, 0, 0, 0], rates]), address)

    run = drive(tmp_path, send, 0.3)
    assert run.report.pacing.live[kind] == 1 and run.report.pacing.live["accepted"] == 0
    assert np.array_equal(run["pose_ref.z"], np.full_like(run["pose_ref.z"], run["pose_ref.z"][0]))  # never moved


def test_a_second_sender_cannot_take_the_platform_from_the_first(tmp_path):
    neutral = Core().neutral_pose
    own, theirs = neutral + [0, 0, 0.02, 0, 0, 0], neutral + [0, 0.05, -0.05, 0, 0, 0]

    def send(address, now):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as owner, \
                socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as intruder:
            for k in range(40):
                owner.sendto(reference(21, k, math.nan, own), address)
                intruder.sendto(reference(22, 2 ** 64 - 1, math.nan, theirs), address)  # highest sequence
                intruder.sendto(reference(21, 2 ** 64 - 1, math.nan, theirs), address)  # the owner's session, not its address
                time.sleep(0.01)

    run = drive(tmp_path, send, 0.7)
    live = run.report.pacing.live
    assert live["accepted"] == 40 and live["foreign"] == 80 and live["out_of_order"] == 0
    assert np.abs(run["pose_ref.y"]).max() == 0.0 and abs(run["pose_ref.z"][-1] - own[2]) < 1e-9


def test_a_keyed_run_takes_only_datagrams_with_the_right_tag(tmp_path):
    """The tag is checked in C (cosim/engine/kernel/hmac.c) against Python's hmac: a short key and
    one longer than SHA-256's block (hashed first)."""
    neutral = Core().neutral_pose
    for key in (b"0123456789abcdef", bytes(range(256)) * 1):
        def send(address, now):
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
                body = reference(31, 0, math.nan, neutral + [0, 0, 0.01, 0, 0, 0])
                sock.sendto(body, address)                                                      # untagged
                sock.sendto(body + hmac.new(b"wrong key, 16 b.", body, hashlib.sha256).digest(), address)
                tagged = body + hmac.new(key, body, hashlib.sha256).digest()
                sock.sendto(tagged[:-1] + bytes([tagged[-1] ^ 1]), address)                   # one bit off
                sock.sendto(tagged, address)

        run = drive(tmp_path, send, 0.3, listen_key=key)
        live = run.report.pacing.live
        assert live["unauthenticated"] == 3 and live["accepted"] == 1, live
        assert abs(run["pose_ref.z"][-1] - (neutral[2] + 0.01)) < 1e-9


@pytest.mark.parametrize("model", [None, "meng_eq35", "sumnu_case_1"])
def test_the_packet_fuzzer_cannot_drive_the_platform_out_of_its_envelope(tmp_path, model):
    """The fuzzer (packet_fuzz) owns the input and sends 1500 datagrams at random in bursts, on the
    test scene and two shipped scenes (Meng's platform with PMSM drives, Sumnu's with linear
    motors, each with its own finer start): the run counts every one by kind, keeps every limit
    and never stops."""
    values = scene_values(cosim.load(model or scene(tmp_path, 2.0, 5.0), LIVE))[0]
    neutral = Core(values=values).neutral_pose
    sent = []
    run = drive(tmp_path, lambda target, now: sent.append(fuzz(target, neutral, now, seed=48, rate_max=0.5)), 2.0,
                model=model)
    live = run.report.pacing.live
    assert sum(v for k, v in live.items() if k != "watchdog") == sent[0]  # every datagram taken or counted once
    assert live["accepted"] + live["outside"] > 10 and live["malformed"] > 100
    assert all(live[k] > 0 for k in ("future", "late", "non_finite", "beyond_limits", "out_of_order"))
    assert_within_the_envelope(run, model or written_scene(tmp_path))
    assert run["time"][-1] == pytest.approx(2.0, abs=1e-9)  # ran to its end
