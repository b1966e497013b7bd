"""The real-time layer's own pieces (cosim.engine.realtime): addresses, the datagrams both ways,
and what it refuses, with one line each."""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest

from cosim.engine.errors import UsageError
from cosim.engine.realtime import (REFERENCE, SAMPLE, Pacing, RealTime, address, decode, layout_datagram,
                                   reference_datagram)


def test_addresses_default_to_the_loopback_and_bad_ones_are_one_line():
    assert address("udp://:9870", "--stream") == ("127.0.0.1", 9870, {})
    assert address("udp://10.0.0.2:9870?every=5", "--stream") == ("10.0.0.2", 9870, {"every": "5"})
    assert address("127.0.0.1:9870", "--listen")[:2] == ("127.0.0.1", 9870)
    for bad in ("tcp://127.0.0.1:9870", "udp://127.0.0.1", "udp://127.0.0.1:99999", "udp://host:port"):
        with pytest.raises(UsageError, match="expected udp://HOST:PORT") as caught:
            address(bad, "--stream")
        assert "\n" not in str(caught.value)
    for options, message in (({"factor": 0.0}, "factor > 0"), ({"factor": math.nan}, "factor > 0"),
                             ({"stream": "udp://:9870?every=0"}, "every=0"),
                             ({"stream": "udp://:9870?often=2"}, "unknown option 'often'"),
                             ({"listen": "udp://:9871"}, "names no outputs")):
        with pytest.raises(UsageError, match=message):
            RealTime(**options)
    assert RealTime(stream="udp://:9870?every=4").every == 4


def test_a_sample_decodes_to_its_values_by_name_bit_for_bit():
    values = np.array([1.0, -2.5e-300, np.pi, 1e300])
    datagram = SAMPLE.pack(b"CSIM", 1, 4, 17, 0.125, 1.7e9) + values.astype("<f8").tobytes()
    names = ["pose.z", "a", "b", "c"]
    assert decode(layout_datagram(names)) == names
    sample = decode(datagram, names)
    assert (sample.sequence, sample.time, sample.wall) == (17, 0.125, 1.7e9)
    assert sample["pose.z"] == 1.0 and np.array_equal(sample.values, values)
    with pytest.raises(KeyError, match="not streamed"):
        sample["pose.x"]
    assert decode(datagram, ["too", "few"]).names == ("value[0]", "value[1]", "value[2]", "value[3]")
    for broken in (datagram[:-1], b"XSIM" + datagram[4:], datagram[:4] + struct.pack("<H", 2) + datagram[6:], b""):
        assert decode(broken) is None


def test_a_reference_datagram_carries_values_rates_and_accelerations_in_order():
    pose, rates = [0.0, 0.1, 1.7, 0.0, 0.02, 0.0], [0.0] * 5 + [0.3]
    datagram = reference_datagram(pose, 9, None, rates, [1.0] * 6, session=0xfeed)
    magic, version, count, session, sequence, time = REFERENCE.unpack_from(datagram)
    assert (magic, version, count, session, sequence) == (b"CREF", 2, 18, 0xfeed, 9) and math.isnan(time)
    assert REFERENCE.size == 32
    values = np.frombuffer(datagram, "<f8", offset=REFERENCE.size)
    assert values.tolist() == [*pose, *rates, *[1.0] * 6]
    assert len(reference_datagram(pose, 0, 2.0, accelerations=[1.0] * 6)) == REFERENCE.size + 18 * 8  # rates 0
    with pytest.raises(UsageError, match="as many each"):
        reference_datagram(pose, 0, rates=[0.0])


def test_pacing_figures_come_from_the_steps():
    lateness = np.array([0.0, 1e-5, 2e-5, 3e-4, 5e-3])
    pacing = Pacing(1.0, lateness, np.array([-1e-3, -1e-3, 2e-4, -1e-4, 4e-3]), streamed=5)
    p50, p99, largest = pacing.percentiles()
    assert p50 == 2e-5 and largest == 5e-3 and 3e-4 < p99 <= 5e-3
    assert pacing.overruns == 2
    counts, edges = pacing.histogram(10)
    assert counts.sum() == 5 and edges[-1] == 5e-3
    assert "2 of 5 steps overran" in pacing.lines()[0] and pacing.row()["overruns"] == 2


def test_a_keyed_datagram_ends_in_the_hmac_sha256_of_the_rest():
    import hashlib
    import hmac
    key = b"k" * 32
    datagram = reference_datagram([0.0] * 6, 3, 1.5, session=7, key=key)
    assert len(datagram) == REFERENCE.size + 6 * 8 + 32
    assert datagram[-32:] == hmac.new(key, datagram[:-32], hashlib.sha256).digest()


@pytest.mark.parametrize("host, loopback", [("127.0.0.1", True), ("127.0.0.2", True), ("127.255.0.9", True),
                                            ("::1", True), ("localhost", True), ("0.0.0.0", False),
                                            ("10.0.0.2", False), ("::", False), ("192.168.1.1", False)])
def test_the_loopback_is_127_0_0_0_8_and_1(host, loopback):
    from cosim.engine.realtime import is_loopback
    assert is_loopback(host) is loopback


def test_a_key_file_is_read_whole_and_its_length_checked(tmp_path):
    from cosim.engine.realtime import read_key
    good = tmp_path / "key"
    good.write_text("0123456789abcdef0123456789abcdef\n")
    assert read_key(good) == b"0123456789abcdef0123456789abcdef"
    for text, message in (("short", "a key of 5 bytes; it takes 16 to 256"), ("x" * 300, "a key of 300 bytes")):
        good.write_text(text)
        with pytest.raises(UsageError, match=message):
            read_key(good)
    with pytest.raises(UsageError, match="--listen-key .*missing"):
        read_key(tmp_path / "missing")


def test_a_live_input_replaces_no_more_outputs_than_the_kernel_has_room_for():
    """The master's bound on a live input's outputs (MAX_LIVE) is the C kernel's: realtime.c sizes its
    scratch by motion_guard.h's MOTION_GUARD_CHANNELS (one number, read here from the header)."""
    import re

    from cosim.engine.artifacts import ROOT
    from cosim.engine.realtime.session import MAX_LIVE
    header = (ROOT / "fmu" / "common" / "motion_guard.h").read_text()
    assert int(re.search(r"MOTION_GUARD_CHANNELS = (\d+)", header).group(1)) == MAX_LIVE
    assert "3 * MOTION_GUARD_CHANNELS" in (ROOT / "cosim" / "engine" / "kernel" / "realtime.c").read_text()
