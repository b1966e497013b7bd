"""One envelope for every reference the platform is given (docs/guide/realtime.md, "The motion
envelope"): whatever its source, the scene's trajectory, the cueing's output, a live sender or the
watchdog's return, the guard keeps the reference inside the envelope and brings one that is
outside back in, and its margins hold on the platform: with every axis at its top [live] rate at
once into each edge, on every shipped platform and drive kind, the platform's legs stay within the
stroke and its joints within their limit at every recorded sample. Senders are written from the
guide's datagram table (packet_fuzz), and the shipped scenes run as shipped."""

from __future__ import annotations

import math
import os
import socket
import threading
import time
from dataclasses import replace

import numpy as np
import pytest
from packet_fuzz import HEADER, reference
from test_live import free_port

import cosim
from cosim.engine.realtime import receive
from cosim.platform.core import Core
from cosim.platform.ports import POSE
from cosim.platform.realtime import Envelope, guarded_plan
from cosim.platform.realtime.margins import directions, measure, probe_scene
from cosim.platform.run.compile import scene_values
from cosim.platform.run.envelope import GUARD_KINDS, GUARD_OUTPUTS
from cosim.platform.run.runner import run_scene
from cosim.platform.scene import load_scene

SHIPPED = ("meng_eq35", "meng_eq35_linear", "sumnu_case_1", "sumnu_case_1_pmsm")  # every platform and drive kind
GUIDE_POSE = [0, 0.05, 1.72, 0, 0, 0.1]  # the guide's three-command example


def unguarded_cueing(plan):
    """The plan with its cueing FMU's guard off: what the cueing would do to the platform unguarded."""
    components = [replace(c, parameters={**c.parameters, "guard": False}) if c.name == "cueing" else c
                  for c in plan.structure.components]
    return replace(plan, structure=replace(plan.structure, components=components))


def columns(run, prefix: str) -> np.ndarray:
    return np.column_stack([run[f"{prefix}.{a}"] for a in POSE])


def limits_of(model, overrides=None) -> tuple[Envelope, Core]:
    values = scene_values(model if not isinstance(model, (str, os.PathLike)) else load_scene(model, overrides))[0]
    return Envelope.of(values), Core(values=values)


def assert_platform_within_its_limits(run, envelope: Envelope, core: Core) -> None:
    """The platform's legs within the stroke and its joints within their limit, every sample."""
    kinematics = core.pose_kinematics(columns(run, "pose"))
    legs, tilt = kinematics["length"], np.maximum(kinematics["lower_angle"], kinematics["upper_angle"])
    assert legs.min() >= envelope.stroke[0] and legs.max() <= envelope.stroke[1], (legs.min(), legs.max())
    assert tilt.max() <= envelope.joint_angle, np.degrees(tilt.max())


def assert_reference_inside(reference: np.ndarray, envelope: Envelope, core: Core) -> None:
    """The reference within the stroke less its margin and the joints less theirs, every sample."""
    kinematics = core.pose_kinematics(reference)
    legs, tilt = kinematics["length"], np.maximum(kinematics["lower_angle"], kinematics["upper_angle"])
    low, high = envelope.usable
    assert legs.min() >= low - 1e-9 and legs.max() <= high + 1e-9, (legs.min(), legs.max())
    assert tilt.max() <= envelope.usable_joint_angle + 1e-9, np.degrees(tilt.max())


@pytest.mark.parametrize("name", SHIPPED)
def test_every_axis_at_its_top_rate_into_each_edge_keeps_the_platform_inside(name):
    """The reference steps far outside on every axis at once, signed as each leg lengthens (shortens)
    fastest: it reaches the envelope's edge at the [live] limits and brakes there; the platform,
    lagging it, stays within the stroke and the joints' limit, so the shipped margins cover its
    tracking error at the limits the guard admits."""
    scene = load_scene(name)
    envelope, _ = limits_of(scene)
    probes = measure(scene, duration=4.0)
    assert len(probes) >= 6
    for p in probes:
        assert p.reached, p.direction
        assert envelope.stroke[0] <= p.legs[0] and p.legs[1] <= envelope.stroke[1], (p.direction, p.legs)
        assert p.tilt <= envelope.joint_angle, (p.direction, math.degrees(p.tilt))
        assert p.stroke_excess < envelope.margin and p.joint_excess < envelope.joint_margin, p


def test_the_margins_are_needed():
    """Without them the same drive takes Meng's platform past its stroke and its joints' limit:
    the probe sees the lag the margins are there for (a guard with no margin is the issue's case)."""
    scene = load_scene("meng_eq35", {'mechanics.parameters."limit.stroke_margin"': 0.0,
                                     'mechanics.parameters."limit.joint_margin"': 0.0})
    probes = measure(scene, duration=4.0)
    assert max(p.legs[1] for p in probes) > 2.2 and max(p.tilt for p in probes) > math.radians(20.0)


def test_a_reference_that_starts_outside_goes_back_in_within_the_limits():
    """From a state outside the envelope (the scene's own reference and the platform in the stroke's
    margin at the start), the guard does not hold it there: it brings the reference in within the
    [live] rate and acceleration limits, and the platform with it."""
    core = Core()
    start = core.neutral_pose.copy()
    while core.leg_lengths(start).max() < 2.195:  # inside the stroke, 5 mm from its top: in the margin
        start[2] += 1e-4
    scene = load_scene("meng_eq35", {"scene.duration": 1.5, "load.pulses": [],
                                     **{f"trajectory.{a}.sines": [] for a in POSE},
                                     **{f"trajectory.{a}.offset": float(start[k]) for k, a in enumerate(POSE)},
                                     **{f'mechanics.parameters."initial.pose.{a}"': float(start[k])
                                        for k, a in enumerate(POSE)}})
    envelope, core = limits_of(scene)
    result, report = run_scene(scene, adapt=guarded_plan)
    reference, t = columns(result, "pose_ref"), result["time"]
    legs = core.pose_kinematics(reference)["length"].max(axis=1)
    assert legs[0] > envelope.usable[1]  # it started outside
    inside = np.flatnonzero(legs <= envelope.usable[1])[0]
    # within the time a [live] limit takes to cover the way (1 cm at 0.25 m/s, 2 m/s^2) and never out again
    assert t[inside] < 0.2 and legs[inside:].max() <= envelope.usable[1] + 1e-9
    speed = np.abs(np.diff(reference[:, :3], axis=0) / np.diff(t)[:, None]).max()
    assert speed <= 0.25 * (1 + 1e-9)
    assert report.pacing.held["its way back in from outside"] > 0
    assert_platform_within_its_limits(result, envelope, core)


def sender_run(tmp_path, model, duration: float, send, real_time_factor: float = 1.0, **options):
    """`model` paced at real time, listening, streaming to a follower that tells `send(target, now)`
    the simulated time; returns the run."""
    listen, stream = free_port(), f"udp://127.0.0.1:{free_port()}"
    ready, seen, done = threading.Event(), [0.0], threading.Event()

    def follow():
        for sample in receive(stream, ready=ready.set, until=done):
            seen[0] = sample.time

    threading.Thread(target=follow, daemon=True).start()
    ready.wait(10)
    out = {}

    def talk():
        deadline = time.monotonic() + 20
        while seen[0] == 0.0 and time.monotonic() < deadline:  # the run is listening once it streams
            time.sleep(0.002)
        out["sent"] = send(("127.0.0.1", listen), lambda: seen[0])

    sender = threading.Thread(target=talk, daemon=True)
    sender.start()
    try:
        run = cosim.simulate(model, duration=duration, real_time=real_time_factor, stream=stream, listen=f"udp://127.0.0.1:{listen}",
                             **options)
    finally:
        done.set()
    sender.join(30)
    run.sent = out.get("sent")
    return run


@pytest.mark.parametrize("start", [1.0, 3.5])
def test_a_sender_that_starts_late_on_the_shipped_scene_takes_over_and_the_platform_stays_inside(tmp_path, start):
    """The guide's example started late: Eq 35's own reference is outside the stroke at 1 s and
    3.5 s; in a listening run it is guarded from the first step, the sender takes over from
    inside, the reference reaches its pose and holds it, and the platform's legs and joints stay
    within their limits at every sample."""
    envelope, core = limits_of("meng_eq35")

    def send(target, now):
        session = int.from_bytes(os.urandom(8), "little")
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            deadline = time.monotonic() + 30
            while now() < start and time.monotonic() < deadline:
                time.sleep(0.002)
            taken_at = now()
            for k in range(10_000):
                if time.monotonic() > deadline or now() > start + 1.9:
                    break
                sock.sendto(reference(session, k, math.nan, np.array(GUIDE_POSE, float)), target)
                time.sleep(0.01)
        return taken_at

    run = sender_run(tmp_path, "meng_eq35", start + 2.0, send, overrides={"live.watchdog": 5.0})
    reference_poses = columns(run, "pose_ref")
    assert run.report.pacing.live["accepted"] > 100 and run.report.pacing.live["outside"] == 0
    assert_reference_inside(reference_poses, envelope, core)
    assert_platform_within_its_limits(run, envelope, core)
    # followed: at the sender's pose within the braking time of the limits (well under a second here), held there
    after = run["time"] >= run.sent + 1.2
    assert np.abs(reference_poses[after] - GUIDE_POSE).max() < 1e-9
    own = cosim.simulate("meng_eq35", duration=start + 2.0)  # Eq 35 unguarded: it leaves the stroke
    assert core.pose_kinematics(columns(own, "pose_ref"))["length"].max() > envelope.stroke[1]


def test_ten_thousand_well_formed_packets_keep_the_platform_inside(tmp_path):
    """A fuzz of 10^4 well-formed datagrams over 20 s from the owner of the input (poses anywhere in
    and far beyond the workspace, rates and accelerations up to the limits, for now or a recent
    time, some repeated or out of order), against the shipped scene as shipped: every datagram is
    taken, refused by kind or counted as dropped by the operating system; the reference stays inside
    the envelope and the platform inside its stroke and joints' limit at every sample."""
    envelope, core = limits_of("meng_eq35")
    neutral = core.neutral_pose
    count, seconds = 10_000, 20.0

    def send(target, now):
        rng = np.random.default_rng(59)
        session = int.from_bytes(os.urandom(8), "little")
        sequence, sent, begun = 0, 0, time.monotonic()
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            # on a schedule of 10^4 over the run's first 19.5 s (a late sender catches up in bursts), none
            # after it: every datagram sent arrives while the run still reads
            while sent < count and now() < seconds - 0.5 and time.monotonic() - begun < 2 * seconds:
                if time.monotonic() < begun + sent * (seconds - 0.5) / count:
                    time.sleep(0.0005)
                    continue
                pose = neutral + rng.uniform(-1, 1, 6) * [0.5, 0.5, 0.5, 0.6, 0.6, 1.0]
                kind = int(rng.integers(0, 3))
                rates = rng.uniform(-1, 1, 6 * kind) * np.tile([0.25] * 3 + [0.5] * 3 + [2.0] * 3 + [4.0] * 3, 2)[:6 * kind]
                at = float(rng.choice([math.nan, now(), now() - 0.05]))
                sock.sendto(HEADER.pack(b"CREF", 2, 6 + 6 * kind, session, sequence, at)
                            + np.r_[pose, rates].astype("<f8").tobytes(), target)
                sent += 1
                sequence += int(rng.choice([1, 1, 1, 1, 2, 0, -1]))
                sequence = max(sequence, 0)
        return sent

    run = sender_run(tmp_path, "meng_eq35", seconds, send, overrides={"live.watchdog": 5.0})
    live = run.report.pacing.live
    assert run.sent >= count * 0.9
    assert sum(v for k, v in live.items() if k != "watchdog") + run.report.pacing.dropped == run.sent, live
    assert live["accepted"] + live["outside"] > count / 2
    assert_reference_inside(columns(run, "pose_ref"), envelope, core)
    assert_platform_within_its_limits(run, envelope, core)
    assert run["time"][-1] == pytest.approx(seconds, abs=1e-9)


def test_a_limit_is_compared_exactly(tmp_path):
    """A rate one ulp past [live] velocity_max is refused; the limit itself is taken."""
    neutral = Core().neutral_pose

    def send(target, now):
        session = int.from_bytes(os.urandom(8), "little")
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            time.sleep(0.05)
            for k, rate in enumerate((np.nextafter(0.25, 1.0), 0.25)):
                sock.sendto(reference(session, k, math.nan, np.r_[neutral, 0, 0, rate, 0, 0, 0]), target)
        return 2

    run = sender_run(tmp_path, "meng_eq35", 0.3, send)
    assert run.report.pacing.live["beyond_limits"] == 1 and run.report.pacing.live["accepted"] == 1


def test_an_interior_target_is_reached_without_overshoot(tmp_path):
    """From rest at the neutral pose to a pose 10 cm up and 0.1 rad in yaw: the reference cruises at
    the [live] limits, brakes in time and lands on the pose, never past it."""
    core = Core()
    target = core.neutral_pose + [0, 0, 0.1, 0, 0, 0.1]
    envelope, _ = limits_of("meng_eq35")
    assert envelope.usable[0] < core.leg_lengths(target).min() and core.leg_lengths(target).max() < envelope.usable[1]

    def send(address, now):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            time.sleep(0.05)
            sock.sendto(reference(77, 0, math.nan, target), address)
        return 1

    flat = {f"trajectory.{a}.sines": [] for a in POSE}
    run = sender_run(tmp_path, "meng_eq35", 1.5, send, overrides={**flat, "load.pulses": [], "live.watchdog": 5.0})
    z, yaw = run["pose_ref.z"], run["pose_ref.yaw"]
    assert z.max() <= target[2] + 1e-12 and yaw.max() <= target[5] + 1e-12
    assert abs(z[-1] - target[2]) < 1e-9 and abs(yaw[-1] - target[5]) < 1e-9


def emergency_stop(folder) -> str:
    """examples/vehicle/car_drive.toml on a drive of braking at 8 m/s^2 from 2 s for 3 s (0.15 s
    onsets), then standing: the classical washout's hardest case (benchmarks/cueing_mpc.py)."""
    from cosim.engine.artifacts import ROOT
    t = np.arange(0.0, 10.0 + 1e-9, 0.01)
    up = np.clip((t - 2.0) / 0.15, 0, 1) * np.clip((5.0 - t) / 0.15, 0, 1)
    motion = np.column_stack([t, -8.0 * up, 0 * t, np.full_like(t, 9.81), 0 * t, 0 * t, 0 * t])
    np.savetxt(folder / "stop.csv", motion, delimiter=",", comments="", fmt="%.10g",
               header="time,specific_force.x,specific_force.y,specific_force.z,angular_rate.x,angular_rate.y,angular_rate.z")
    scene = (ROOT / "examples" / "vehicle" / "car_drive.toml").read_text().replace('vehicle = "drive.csv"',
                                                                                    'vehicle = "stop.csv"')
    (folder / "stop.toml").write_text(scene.replace("duration = 20.0", "duration = 10.0"))
    return str(folder / "stop.toml")


def test_the_classical_washout_is_guarded_on_an_emergency_stop(tmp_path):
    """Unguarded, the washout commands the upper joints far past 20 deg on an emergency stop; as a
    cueing scene is run, the cueing FMU's guard holds its output at the envelope (the steps it held
    counted in its outputs and said in the report) and the platform's joints stay within their
    limit (and its legs within the stroke) at every sample."""
    model = emergency_stop(tmp_path)
    envelope, core = limits_of(model)
    run = cosim.simulate(model)
    held = int(run["guard.held.joint"][-1])
    assert held > 0 and np.all(np.diff(run["guard.held.joint"]) >= 0)
    assert f"the envelope held the reference back at {held} steps by a joint's tilt" in run.report.text()
    assert_reference_inside(columns(run, "pose_ref"), envelope, core)
    assert_platform_within_its_limits(run, envelope, core)
    unguarded, _ = run_scene(load_scene(model), adapt=lambda compiled: (unguarded_cueing(compiled.plan), None))
    tilt = core.pose_kinematics(columns(unguarded, "pose_ref"))
    assert np.maximum(tilt["lower_angle"], tilt["upper_angle"]).max() > math.radians(25.0)
    assert unguarded["guard.held.joint"][-1] == 0


def test_the_cueing_fmus_guard_is_the_masters_bit_for_bit(tmp_path):
    """The cueing FMU's own guard (fmu/cueing/guard.c) and the step kernel's guard on a source
    (realtime.c) are one stepping (motion_guard.c) on one envelope: the emergency stop held by the
    kernel, with the cueing FMU's guard off, gives every recorded column bit for bit, and the kernel
    counts the steps held as the FMU does."""
    model = emergency_stop(tmp_path)

    def kernel_guarded(compiled):
        plan, _ = guarded_plan(compiled)
        live = replace(plan.real_time.live, guarded=True)  # the kernel guards the cueing's output
        return replace(unguarded_cueing(plan), real_time=replace(plan.real_time, live=live)), None
    by_kernel, report = run_scene(load_scene(model), adapt=kernel_guarded)
    by_fmu, _ = run_scene(load_scene(model))
    assert by_kernel.dtype.names == by_fmu.dtype.names
    for name in by_fmu.dtype.names:
        if not name.startswith("guard.held."):
            assert np.array_equal(by_kernel[name], by_fmu[name]), name
    held = {kind: int(by_fmu[name][-1]) for kind, name in zip(GUARD_KINDS, GUARD_OUTPUTS)}
    assert held["a joint's tilt"] > 1000 and held == report.pacing.held


def test_the_one_fmu_export_holds_the_cueing_as_cosim_run_does(tmp_path, capsys):
    """The cueing FMU's guard goes with it into the one-FMU exports: in fmpy the exported emergency
    stop as Co-Simulation is `cosim run`'s bit for bit at the scene's step, the reference within the
    envelope; as Model Exchange, integrated by fmpy's CVODE through the braking (the guard's steps
    its time events at the scene's step), the reference within the envelope at every output and the
    platform's joints within their limit; each says so in a line and in its description (what a
    tool shows of an FMU it imports)."""
    from fmpy import read_model_description, simulate_fmu
    from cosim.cli import main
    model, fmu, me = emergency_stop(tmp_path), tmp_path / "stop.fmu", tmp_path / "stop_me.fmu"
    guarded = "held within the platform's envelope by the cueing FMU's own guard"
    assert main(["export", model, "--fmu", str(fmu)]) == 0
    assert guarded in capsys.readouterr().out and guarded in read_model_description(str(fmu)).description
    envelope, core = limits_of(model)
    run = cosim.simulate(model)
    step = load_scene(model).step
    names = [f"pose_ref.{a}" for a in POSE] + [f"pose.{a}" for a in POSE] + ["guard.held.joint"]
    result = simulate_fmu(str(fmu), stop_time=10.0, step_size=step, output_interval=step, output=names)
    at = np.searchsorted(run["time"], result["time"][1:] - 1e-9)
    assert np.allclose(run["time"][at], result["time"][1:], rtol=0, atol=1e-9)
    for name in names:
        assert np.array_equal(result[name][1:], run[name][at]), name
    assert_reference_inside(np.column_stack([result[f"pose_ref.{a}"] for a in POSE]), envelope, core)
    assert main(["export", model, "--fmu", str(me), "--me"]) == 0
    said = capsys.readouterr().out
    assert f"{guarded}, as in `cosim run`, its steps time events {step:g} s apart" in said
    assert guarded in read_model_description(str(me)).description
    integrated = simulate_fmu(str(me), fmi_type="ModelExchange", stop_time=4.0, output=names)
    assert integrated["guard.held.joint"][-1] > 1000
    assert_reference_inside(np.column_stack([integrated[f"pose_ref.{a}"] for a in POSE]), envelope, core)
    assert_platform_within_its_limits(integrated, envelope, core)


def test_a_paper_scene_keeps_its_trajectory_and_reports_each_excursion():
    """Meng's Eq 35 leaves Table 4's stroke as the paper's does: not guarded in a plain run, and
    the report gives each excursion with its longest (shortest) leg and how long it lasted."""
    run = cosim.simulate("meng_eq35", duration=2.0)
    assert run.report.pacing is None
    text = run.report.text()
    envelope, core = limits_of("meng_eq35")
    legs = core.pose_kinematics(columns(run, "pose"))["length"]
    longest = legs[:, 3].max()
    assert longest > envelope.stroke[1]
    line = next(line for line in text.splitlines() if line.startswith("leg 4 past the stroke's top"))
    assert f"at most {longest:.4f} m" in line
    over = run["time"][legs[:, 3] > envelope.stroke[1]]
    first, back = over[0], run["time"][np.searchsorted(run["time"], over[-1]) + 1]
    assert f"from t = {first:.3f} to {back:.3f} s ({back - first:.3f} s)" in line


def test_the_probe_drives_every_axis_at_once():
    """The probe's directions: every axis moves (all six signs set), each leg lengthening and
    shortening; and its scene steps every axis from the neutral pose."""
    core = Core()
    found = directions(core)
    assert all(len(signs) == 6 and all(s in (-1, 1) for s in signs) for _, signs in found)
    for leg in range(6):
        grows = [s for d, s in found if d.startswith(f"leg {leg + 1} ")]
        assert grows or any(core.leg_lengths(core.neutral_pose + 0.01 * np.array(s))[leg] >
                            core.leg_lengths(core.neutral_pose)[leg] for _, s in found)
    scene = probe_scene(load_scene("meng_eq35"), found[0][1], 1.0)
    assert all(len(scene.document.value(f"trajectory.{a}", "steps")) == 1 for a in POSE)


def test_datagrams_the_operating_system_drops_are_counted(tmp_path):
    """A burst far larger than the socket's receive buffer, from a process of its own, at a run that
    reads it every 20 ms of wall time (paced at 1/20 of the wall clock): the operating system drops
    some (the socket's drop counter), and every datagram sent is taken, refused by kind or counted
    as dropped, in the report too."""
    import subprocess
    import sys
    neutral = Core().neutral_pose
    burst = ("import socket, sys\n"
             "sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)\n"
             "for k in range(4000):\n"
             "    sock.sendto(bytes.fromhex(sys.argv[3]) + k.to_bytes(8, 'little') + bytes.fromhex(sys.argv[4]),"
             " (sys.argv[1], int(sys.argv[2])))\n")

    def send(target, now):
        deadline = time.monotonic() + 30
        while now() < 0.08 and time.monotonic() < deadline:  # past the scene's finer start: a step every 20 ms
            time.sleep(0.002)
        whole = reference(0x5EED, 0, math.nan, np.r_[neutral, np.zeros(12)])  # session 0x5EED, sequences 0 ..
        subprocess.run([sys.executable, "-c", burst, target[0], str(target[1]), whole[:16].hex(), whole[24:].hex()],
                       check=True, timeout=60)
        return 4000

    run = sender_run(tmp_path, "meng_eq35", 0.15, send, real_time_factor=0.05)
    pacing = run.report.pacing
    assert pacing.dropped > 0, (pacing.live, run.sent)
    assert sum(v for k, v in pacing.live.items() if k != "watchdog") + pacing.dropped == run.sent
    assert f"{pacing.dropped} dropped unread by the operating system" in run.report.text()


def test_a_cueing_scene_with_an_adaptive_step_is_refused_in_one_line(capsys, tmp_path):
    """The guard holds the reference at every fixed macro step: a cueing scene that asks for step
    doubling is refused before it runs (not run unguarded), in one line saying why."""
    from cosim.cli import main
    from cosim.engine.artifacts import ROOT
    assert main(["run", str(ROOT / "examples" / "vehicle" / "car_drive.toml"), "--set", "step_control=doubling",
                 "--duration", "0.1", "--no-plots", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "a guarded reference takes fixed steps" in err and "Traceback" not in err
