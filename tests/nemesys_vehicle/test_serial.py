"""The serial ME receiver input: frame sync over any chunking, and a real port (a pty)."""

from __future__ import annotations

import itertools
import os
import time
from collections.abc import Iterator

import pytest
from hypothesis import given
from hypothesis import strategies as st

from codec import FRAME_BITS, FRAME_BYTES
from nemesys_vehicle.config import VehicleConfig
from nemesys_vehicle.core import VehicleCore
from nemesys_vehicle.messages import Recorder
from nemesys_vehicle.serial_input import SerialByteSource
from nemesys_vehicle.stream import FrameStream
from tests.nemesys_vehicle.helpers import AT_DATUM, CIRCLE, T0_S, frame_bytes, odometry, same_ack
from vehicle_contract.payloads import validate_ack

CIRCLE_BYTES = frame_bytes("circle", **CIRCLE)
SQUARE_BYTES = frame_bytes("square", speed=0.2, depth=2, side_span=8, direction="cw")
#: Bytes a receiver puts out between frames (no false sync among them).
NOISE = bytes([0x00, 0xFF, 0x13, 0x37, 0xC4, 0x00, 0x5A, 0x0F])


def _chunks(data: bytes, cuts: list[int]) -> list[bytes]:
    points = sorted({c % (len(data) + 1) for c in cuts} | {0, len(data)})
    return [data[a:b] for a, b in itertools.pairwise(points)]


def _shifted(frame: bytes, lead_bits: int) -> bytes:
    """``lead_bits`` zero bits, then the frame's 100 bits, then zero padding to a byte."""
    value = int.from_bytes(frame, "big") >> (8 * FRAME_BYTES - FRAME_BITS)
    total = lead_bits + FRAME_BITS
    n_bytes = (total + 7) // 8
    return (value << (8 * n_bytes - total)).to_bytes(n_bytes, "big")


# --- frame sync over a byte stream ---------------------------------------------------------


@given(st.lists(st.integers(0, 200), max_size=12), st.integers(0, 15))
def test_a_frame_comes_out_once_whatever_the_chunking(cuts: list[int], lead_bits: int) -> None:
    stream = FrameStream()
    data = NOISE + _shifted(CIRCLE_BYTES, lead_bits) + NOISE
    frames = [f for chunk in _chunks(data, cuts) for f in stream.feed(chunk)]
    assert frames == [CIRCLE_BYTES]
    assert stream.pending_bits < 8 * len(data)


def test_back_to_back_frames_come_out_in_order() -> None:
    stream = FrameStream()
    data = NOISE + CIRCLE_BYTES + SQUARE_BYTES + CIRCLE_BYTES
    frames = [f for b in data for f in stream.feed(bytes([b]))]
    assert frames == [CIRCLE_BYTES, SQUARE_BYTES, CIRCLE_BYTES]
    assert stream.frames_out == 3
    assert stream.bytes_in == len(data)


def test_guard_bits_on_the_wire_do_not_matter() -> None:
    stream = FrameStream()
    dirty = CIRCLE_BYTES[:-1] + bytes([CIRCLE_BYTES[-1] | 0x0F])
    assert stream.feed(dirty + NOISE) == [CIRCLE_BYTES]


def test_the_buffer_stays_short_in_endless_noise() -> None:
    stream = FrameStream()
    for _ in range(200):
        assert stream.feed(NOISE * 8) == []
    assert stream.pending_bits < 200


# --- the core fed from a stream ------------------------------------------------------------


def _core() -> tuple[VehicleCore, Recorder]:
    rec = Recorder()
    core = VehicleCore(VehicleConfig(**AT_DATUM), rec.sinks())
    core.on_odometry(odometry(T0_S))
    return core, rec


def test_a_stream_gives_the_acks_the_topic_gives() -> None:
    bad = bytearray(CIRCLE_BYTES)
    for pos in (30, 50, 70):  # three codeword errors: synchronised, then uncorrectable
        bad[pos // 8] ^= 0x80 >> (pos % 8)
    sent = [CIRCLE_BYTES, bytes(bad), SQUARE_BYTES, SQUARE_BYTES]
    by_topic, topic_rec = _core()
    for data in sent:
        by_topic.on_frame(data, T0_S + 1)
    by_serial, serial_rec = _core()
    stream = NOISE + b"".join(sent) + NOISE
    acks = [
        a
        for i in range(0, len(stream), 5)
        for a in by_serial.on_serial_bytes(stream[i : i + 5], T0_S + 1)
    ]
    assert acks == serial_rec.acks
    assert len(acks) == 4
    assert [a["outcome"] for a in acks] == ["accepted", "rejected", "accepted", "accepted"]
    assert acks[1]["reason"] == "uncorrectable"
    assert acks[3]["duplicate"] is True
    for got, want in zip(acks, topic_rec.acks, strict=True):
        assert same_ack(got, want)
        assert validate_ack(got) == []


# --- a real serial port: a pty -------------------------------------------------------------


@pytest.fixture
def pty_port() -> Iterator[tuple[int, str]]:
    """A pty: the master fd (the receiver's side, written by the test) and the slave's path."""
    master, slave = os.openpty()
    try:
        yield master, os.ttyname(slave)
    finally:
        os.close(slave)
        os.close(master)


def _poll(core: VehicleCore, source: SerialByteSource, want: int, timeout_s: float = 5.0) -> int:
    """Poll like the node's timer until ``want`` acks came out (or the time is up)."""
    n = 0
    deadline = time.monotonic() + timeout_s
    while n < want and time.monotonic() < deadline:
        n += len(core.on_serial_bytes(source.read_available(), T0_S))
        time.sleep(0.005)
    # and a little longer: nothing more may come
    for _ in range(5):
        n += len(core.on_serial_bytes(source.read_available(), T0_S))
        time.sleep(0.005)
    return n


def test_a_frame_written_in_chunks_to_a_pty_is_acknowledged_once(
    pty_port: tuple[int, str],
) -> None:
    master, path = pty_port
    core, rec = _core()
    source = SerialByteSource(path, 115_200)
    source.open()  # raw mode before anything is written (a pty starts in canonical mode)
    try:
        for chunk in (NOISE[:3], NOISE[3:], CIRCLE_BYTES[:2], CIRCLE_BYTES[2:7], CIRCLE_BYTES[7:]):
            os.write(master, chunk)
            time.sleep(0.01)
        assert _poll(core, source, 1) == 1
        assert len(rec.acks) == 1
        assert rec.acks[0]["outcome"] == "accepted"
        assert rec.acks[0]["command"]["pattern"] == "circle"
        assert source.bytes_read == len(NOISE) + FRAME_BYTES
        # two frames back to back in one write
        os.write(master, SQUARE_BYTES + CIRCLE_BYTES + NOISE)
        assert _poll(core, source, 2) == 2
        assert [a["command"]["pattern"] for a in rec.acks] == ["circle", "square", "circle"]
        assert [a["duplicate"] for a in rec.acks] == [False, False, False]
        assert source.errors == 0
    finally:
        source.close()
    assert not source.is_open


def test_a_port_that_cannot_open_is_retried_later() -> None:
    logged: list[str] = []
    source = SerialByteSource("/nonexistent/ttyME0", reopen_after_s=60.0, log=logged.append)
    assert source.read_available() == b""
    assert source.errors == 1
    assert "cannot open /nonexistent/ttyME0" in logged[0]
    assert source.read_available() == b""  # within the back-off: not tried again
    assert source.errors == 1
    eager = SerialByteSource("/nonexistent/ttyME0", reopen_after_s=0.0)
    assert eager.read_available() == eager.read_available() == b""
    assert eager.errors == 2
    assert not eager.is_open


def test_a_receiver_that_goes_away_is_closed_and_reopened() -> None:
    master, slave = os.openpty()
    logged: list[str] = []
    source = SerialByteSource(os.ttyname(slave), reopen_after_s=0.0, log=logged.append)
    try:
        source.open()
        os.close(slave)
        os.write(master, CIRCLE_BYTES)
        deadline = time.monotonic() + 5.0
        got = b""
        while len(got) < FRAME_BYTES and time.monotonic() < deadline:
            got += source.read_available()
        assert got == CIRCLE_BYTES
        os.close(master)  # the receiver is unplugged: reading fails, the port is closed
        assert source.read_available() == b""
        assert source.errors == 1
        assert not source.is_open
        assert any("reading" in line for line in logged)
    finally:
        source.close()
