"""Transmitters: byte-exact serial/TCP output (pty pair, loop://, a TCP server), the rosbridge
client's exact messages and acknowledgement matching against a fake rosbridge endpoint, and
every failure reported as a reason, never raised. Everything talks to 127.0.0.1 only."""

from __future__ import annotations

import asyncio
import errno
import itertools
import json
import logging
import os
import select
import socket
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import serial

from codec import FRAME_BYTES, GUARD_BITS, Frame, encode_frame
from station.transmit import (
    DEFAULT_BAUDRATE,
    TARGET_FORMS,
    RosbridgeTransmitter,
    SendResult,
    SerialTransmitter,
    TcpTransmitter,
    ack_match,
    failure_reason,
    open_transmitter,
)
from tests.rosbridge.fake_rosbridge import FakeRosbridge, ack_for, mission
from tests.rosbridge.helpers import free_port

FRAMES = [
    encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw").frame,
    encode_frame("square", speed=1.0, depth=3, side_span=12.5, direction="ccw").frame,
    encode_frame("circle", speed=0.75, depth=10, radius=40, direction="ccw").frame,
]
FRAME = FRAMES[0]


def flipped(frame: Frame, *codeword_bits: int) -> Frame:
    """``frame`` with the given codeword bits (0 = last codeword bit) inverted."""
    value = frame.value
    for k in codeword_bits:
        value ^= 1 << (GUARD_BITS + k)
    return Frame(value)


def read_exactly(fd: int, n: int, timeout_s: float = 2.0) -> bytes:
    data = b""
    deadline = time.monotonic() + timeout_s
    while len(data) < n:
        ready, _, _ = select.select([fd], [], [], max(0.0, deadline - time.monotonic()))
        if not ready:
            break
        data += os.read(fd, 4096)
    return data


@pytest.fixture
def pty_pair() -> Iterator[tuple[int, str]]:
    """The master fd and the slave's device path (which the transmitter opens)."""
    master, slave = os.openpty()
    try:
        yield master, os.ttyname(slave)
    finally:
        os.close(master)
        os.close(slave)


# --- serial and TCP -----------------------------------------------------------------------


def test_pty_gets_exactly_13_bytes_per_frame_in_order(pty_pair: tuple[int, str]) -> None:
    master, path = pty_pair
    with open_transmitter(f"serial://{path}") as tx:
        assert isinstance(tx, SerialTransmitter)
        results = [tx.send(frame) for frame in FRAMES]
        assert tx.frames_sent == 3
    got = read_exactly(master, 3 * FRAME_BYTES)
    assert got == b"".join(f.to_bytes() for f in FRAMES)
    assert len(got) == 39
    # MSB first, 4 zero pad bits: the first bytes are the preamble 0xAAAA and delimiter 0x7C
    assert got[:3] == bytes([0xAA, 0xAA, 0x7C]) and got[12] & 0x0F == 0
    assert all(r.ok and r.sent and r.ack is None and r.accepted is None for r in results)
    assert [r.transport for r in results] == ["serial"] * 3
    assert results[0].target == f"serial://{path}" and results[0].reason is None
    assert results[0].sent_t is not None and abs(results[0].sent_t - time.time()) < 5


def test_pty_nothing_more_than_the_frame_bytes(pty_pair: tuple[int, str]) -> None:
    master, path = pty_pair
    with SerialTransmitter(path) as tx:
        assert tx.send(FRAME).ok
    assert read_exactly(master, FRAME_BYTES) == FRAME.to_bytes()
    ready, _, _ = select.select([master], [], [], 0.1)
    assert not ready  # no newline, length, checksum or anything after the 13 bytes


def test_serial_baud_option_reaches_the_port(pty_pair: tuple[int, str]) -> None:
    master, path = pty_pair
    tx = open_transmitter(f"serial://{path}?baud=57600")
    assert isinstance(tx, SerialTransmitter) and tx.baudrate == 57600
    with tx:
        assert tx.send(FRAME).ok
        assert tx.port is not None and tx.port.baudrate == 57600
    assert tx.port is None  # closed
    assert read_exactly(master, FRAME_BYTES) == FRAME.to_bytes()
    assert SerialTransmitter(path).baudrate == DEFAULT_BAUDRATE == 115200


def test_loop_url_reads_back_the_frames() -> None:
    with open_transmitter("loop://") as tx:
        assert isinstance(tx, SerialTransmitter)
        for frame in FRAMES:
            assert tx.send(frame).ok
        assert tx.port is not None
        tx.port.timeout = 1
        assert tx.port.read(3 * FRAME_BYTES) == b"".join(f.to_bytes() for f in FRAMES)


def test_frames_are_spaced_by_at_least_the_airtime() -> None:
    with SerialTransmitter("loop://", bitrate_bps=1000) as tx:  # 100 bits: 0.1 s each
        assert tx.gap_s == pytest.approx(0.1)
        times = [tx.send(frame).sent_t or 0.0 for frame in FRAMES]
    gaps = [b - a for a, b in itertools.pairwise(times)]
    assert min(gaps) >= 0.095


def test_tcp_gateway_receives_exactly_the_bytes() -> None:
    received = bytearray()
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def serve_one() -> None:
        conn, _ = server.accept()
        with conn:
            conn.settimeout(2)
            while chunk := conn.recv(4096):
                received.extend(chunk)

    thread = threading.Thread(target=serve_one, daemon=True)
    thread.start()
    try:
        tx = open_transmitter(f"tcp://127.0.0.1:{port}")
        assert isinstance(tx, TcpTransmitter) and (tx.host, tx.port) == ("127.0.0.1", port)
        with tx:
            results = [tx.send(frame) for frame in FRAMES]
        thread.join(2)
    finally:
        server.close()
    assert all(r.ok for r in results)
    assert results[0].target == f"tcp://127.0.0.1:{port}"
    assert bytes(received) == b"".join(f.to_bytes() for f in FRAMES)


def test_a_serial_check_writes_nothing_and_sees_the_device_go() -> None:
    """A pty whose other end closes stands for a USB adapter pulled out: the check (no byte
    written) fails and the port is closed (the next check opens it again)."""
    master, slave = os.openpty()
    path = os.ttyname(slave)
    with SerialTransmitter(path) as tx:
        ok = tx.check()
        assert ok.ok and ok.what == "modem" and tx.connected
        assert "0 bytes waiting to go out" in ok.detail
        assert not select.select([master], [], [], 0)[0]  # nothing was written
        os.close(master)
        os.close(slave)
        gone = tx.check()
        assert not gone.ok and gone.reason == "i/o error" and not tx.connected


def test_missing_device_is_port_not_found(tmp_path: Any) -> None:
    path = tmp_path / "ttyNOPE"
    with open_transmitter(f"serial://{path}") as tx:
        result = tx.send(FRAME)
    assert not result.ok and not result.sent and result.ack is None
    assert result.reason == "port not found"
    assert str(path) in result.detail


def test_regular_file_is_not_a_serial_port(tmp_path: Any) -> None:
    path = tmp_path / "file"
    path.write_bytes(b"")
    result = SerialTransmitter(str(path)).send(FRAME)
    assert not result.ok and result.reason == "not a serial port"
    assert path.read_bytes() == b""


def test_refused_tcp_port_is_connection_refused() -> None:
    port = free_port()
    with open_transmitter(f"tcp://127.0.0.1:{port}") as tx:
        result = tx.send(FRAME)
        assert tx.send(FRAME).reason == "connection refused"  # and again: nothing left open
    assert not result.ok and result.reason == "connection refused" and not result.sent
    assert result.target == f"tcp://127.0.0.1:{port}"


@pytest.mark.parametrize(
    ("exc", "reason"),
    [
        (serial.SerialException(errno.EACCES, "could not open port"), "permission denied"),
        (serial.SerialException(errno.EBUSY, "could not open port"), "port busy"),
        (serial.SerialException(errno.ENOENT, "could not open port"), "port not found"),
        (serial.SerialTimeoutException("Write timeout"), "write timeout"),
        (socket.gaierror(-2, "Name or service not known"), "host not found"),
        (TimeoutError("timed out"), "timeout"),
        (ConnectionRefusedError(errno.ECONNREFUSED, "refused"), "connection refused"),
        (ValueError("odd"), "error"),
    ],
)
def test_failure_reasons(exc: BaseException, reason: str) -> None:
    assert failure_reason(exc) == reason


def test_failure_reason_looks_through_the_chained_cause() -> None:
    try:
        try:
            raise PermissionError(errno.EACCES, "Permission denied")
        except OSError as inner:
            raise serial.SerialException(f"could not open port: {inner}") from None
    except serial.SerialException as outer:
        assert outer.__context__ is not None
        assert failure_reason(outer) == "permission denied"


def test_async_send_works_for_serial_too() -> None:
    async def go() -> SendResult:
        async with SerialTransmitter("loop://") as tx:
            return await tx.send_async(FRAME)

    assert asyncio.run(go()).ok


# --- targets ------------------------------------------------------------------------------


def test_good_targets() -> None:
    ws = open_transmitter("ws://127.0.0.1:9090")
    assert isinstance(ws, RosbridgeTransmitter) and ws.url == "ws://127.0.0.1:9090"
    wss = open_transmitter("wss://vessel.lan:9443/rosbridge")
    assert isinstance(wss, RosbridgeTransmitter) and wss.url == "wss://vessel.lan:9443/rosbridge"
    ser = open_transmitter(" serial:///dev/ttyUSB0 ")
    assert isinstance(ser, SerialTransmitter)
    assert (ser.url, ser.baudrate, ser.target) == ("/dev/ttyUSB0", 115200, "serial:///dev/ttyUSB0")
    tcp = open_transmitter("tcp://[::1]:4001", bitrate_bps=18_000)
    assert isinstance(tcp, TcpTransmitter) and (tcp.host, tcp.port) == ("::1", 4001)
    assert tcp.gap_s == pytest.approx(100 / 18_000)
    assert len(TARGET_FORMS) == 5


@pytest.mark.parametrize(
    ("target", "problem"),
    [
        ("", "empty"),
        ("ftp://host:21", "unknown scheme 'ftp://'"),
        ("/dev/ttyUSB0", "write serial:///dev/ttyUSB0"),
        ("127.0.0.1:9090", "no scheme"),
        ("serial://dev/ttyUSB0", "three slashes"),
        ("serial://", "no device path"),
        ("serial:///dev/ttyUSB0?baud=fast", "baud must be a positive whole number"),
        ("serial:///dev/ttyUSB0?baud=0", "baud must be a positive whole number"),
        ("serial:///dev/ttyUSB0?speed=9600", "unknown option 'speed'"),
        ("tcp://127.0.0.1", "no port"),
        ("tcp://127.0.0.1:99999", "port must be a number"),
        ("tcp://127.0.0.1:x", "port must be a number"),
        ("tcp://127.0.0.1:4001/x", "only host:port"),
        ("ws://:9090", "no host"),
        ("ws://127.0.0.1:0", "port must be a number"),
        ("loop://x", "loop:// takes nothing"),
    ],
)
def test_bad_targets_name_the_problem_and_the_forms(target: str, problem: str) -> None:
    with pytest.raises(ValueError, match="bad transmitter target") as info:
        open_transmitter(target)
    message = str(info.value)
    assert problem in message
    assert repr(target) in message
    assert "ws://host:port[/path]" in message and "tcp://host:port" in message
    assert "\n" not in message


# --- rosbridge ----------------------------------------------------------------------------


def wait_until(condition: Callable[[], bool], timeout_s: float = 2.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, "condition not met in time"
        time.sleep(0.005)


def test_rosbridge_exact_messages_and_exact_ack() -> None:
    with FakeRosbridge() as fake:
        tx = RosbridgeTransmitter(fake.url)
        result = tx.send(FRAME, wait_ack_s=2)
        tx.close()
        wait_until(lambda: len(fake.received) == 6)
    assert fake.received[:4] == [
        {
            "op": "advertise",
            "id": "advertise:/nemesys/frame:1",
            "type": "std_msgs/UInt8MultiArray",
            "topic": "/nemesys/frame",
            "latch": False,
            "queue_size": 100,
        },
        {
            "op": "subscribe",
            "id": "subscribe:/nemesys/mission:2",
            "type": "std_msgs/String",
            "topic": "/nemesys/mission",
            "compression": "none",
            "throttle_rate": 0,
            "queue_length": 0,
        },
        {
            "op": "call_service",
            # the publish message is made (id 3) before the connection opens and asks rosapi
            "id": "call_service:/rosapi/subscribers:4",
            "service": "/rosapi/subscribers",
            "args": {"topic": "/nemesys/frame"},
        },
        {
            "op": "publish",
            "id": "publish:/nemesys/frame:3",
            "topic": "/nemesys/frame",
            "msg": {"data": list(FRAME.to_bytes())},
            "latch": False,
        },
    ]
    assert fake.received[4:] == [
        {"op": "unsubscribe", "id": "subscribe:/nemesys/mission:2", "topic": "/nemesys/mission"},
        {"op": "unadvertise", "id": "advertise:/nemesys/frame:1", "topic": "/nemesys/frame"},
    ]
    data = fake.received[3]["msg"]["data"]
    assert len(data) == 13 and all(isinstance(b, int) and 0 <= b <= 255 for b in data)
    assert result.ok and result.sent and result.reason is None
    assert result.transport == "rosbridge" and result.target == fake.url
    assert result.ack == ack_for(FRAME.to_bytes())
    assert result.ack_match == "exact" and result.accepted is True
    assert result.warning is None and result.detail == "acknowledged"
    json.dumps(result.to_json())


def test_rosbridge_bit_flipped_ack_matches_near() -> None:
    def respond(data: bytes) -> list[dict[str, Any] | str]:
        rx = flipped(Frame(int.from_bytes(data, "big") >> 4), 3, 40)
        return [mission(ack_for(rx.to_bytes(), seq=4, corrected_bits=2))]

    with FakeRosbridge(respond) as fake, RosbridgeTransmitter(fake.url) as tx:
        start = time.monotonic()
        result = tx.send(FRAME, wait_ack_s=2)
        assert time.monotonic() - start < 0.4  # no settling wait for a near match
    assert result.ok and result.ack_match == "near" and result.ack is not None
    assert result.ack["seq"] == 4 and result.ack["corrected_bits"] == 2
    assert "bit errors" in result.detail


def test_ack_match_rule() -> None:
    other = FRAMES[1]
    assert ack_match(FRAME, {"frame_hex": FRAME.hex}) == "exact"
    assert ack_match(FRAME, {"frame_hex": FRAME.hex.upper()}) == "exact"
    assert ack_match(FRAME, {"frame_hex": FRAME.to_bytes().hex()}) == "exact"  # 13-byte form
    assert ack_match(FRAME, {"frame_hex": flipped(FRAME, 0, 71).hex}) == "near"
    assert ack_match(FRAME, {"frame_hex": flipped(FRAME, 0, 1, 2).hex}) is None  # beyond t=2
    sync_hit = Frame(FRAME.value ^ (0b1011 << 90))  # preamble bits only: not the codeword
    assert ack_match(FRAME, {"frame_hex": sync_hit.hex}) == "near"
    assert ack_match(FRAME, {"frame_hex": other.hex}) is None
    assert ack_match(FRAME, {"frame_hex": None}) is None
    assert ack_match(FRAME, {"frame_hex": "zz"}) is None
    assert ack_match(FRAME, {}) is None


def test_rosbridge_unrelated_ack_is_taken_by_order_after_settling() -> None:
    def respond(data: bytes) -> list[dict[str, Any] | str]:
        return [mission(ack_for(FRAMES[1].to_bytes(), seq=9))]

    with FakeRosbridge(respond) as fake, RosbridgeTransmitter(fake.url, settle_s=0.1) as tx:
        start = time.monotonic()
        result = tx.send(FRAME, wait_ack_s=2)
        elapsed_s = time.monotonic() - start
    assert 0.09 <= elapsed_s < 0.6
    assert result.ok and result.ack_match == "first" and result.ack is not None
    assert result.ack["seq"] == 9 and "by order" in result.detail


def test_rosbridge_prefers_the_exact_ack_over_an_earlier_other_one() -> None:
    def respond(data: bytes) -> list[dict[str, Any] | str]:
        return [
            mission(ack_for(FRAMES[2].to_bytes(), seq=7)),
            mission(ack_for(data, seq=8)),
        ]

    with FakeRosbridge(respond) as fake, RosbridgeTransmitter(fake.url, settle_s=1.0) as tx:
        result = tx.send(FRAME, wait_ack_s=2)
    assert result.ack is not None and result.ack["seq"] == 8 and result.ack_match == "exact"


def test_rosbridge_ignores_status_other_topics_and_junk(caplog: pytest.LogCaptureFixture) -> None:
    def respond(data: bytes) -> list[dict[str, Any] | str]:
        return [
            {"op": "status", "level": "error", "msg": "unknown topic type"},
            {"op": "publish", "topic": "/nemesys/pose", "msg": {"x": 1}},
            "not json at all",
            '["a", "list"]',
            {"op": "publish", "topic": "/nemesys/mission", "msg": {"data": "{broken"}},
            {"op": "publish", "topic": "/nemesys/mission", "msg": {"data": 42}},
            mission(ack_for(data, seq=3, outcome="rejected")),
        ]

    with (
        caplog.at_level(logging.DEBUG, logger="station.transmit"),
        FakeRosbridge(respond) as fake,
        RosbridgeTransmitter(fake.url) as tx,
    ):
        result = tx.send(FRAME, wait_ack_s=2)
    assert result.ok and result.ack is not None and result.ack["seq"] == 3
    assert result.accepted is False and result.ack["reason"] == "crc_mismatch"
    assert "rosbridge status: unknown topic type" in caplog.text
    assert "not JSON" in caplog.text


def test_rosbridge_timeout_when_nothing_answers() -> None:
    with FakeRosbridge(respond=None) as fake, RosbridgeTransmitter(fake.url) as tx:
        start = time.monotonic()
        result = tx.send(FRAME, wait_ack_s=0.2)
        elapsed_s = time.monotonic() - start
        assert fake.published() == [FRAME.to_bytes()]
    assert 0.19 <= elapsed_s < 1.0
    assert not result.ok and result.reason == "timeout" and result.ack is None
    assert result.sent  # the frame did go out
    assert "0.2 s" in result.detail


def test_rosbridge_no_wait_returns_after_publishing() -> None:
    with FakeRosbridge(respond=None) as fake, RosbridgeTransmitter(fake.url) as tx:
        result = tx.send(FRAME, wait_ack_s=0)
        wait_until(lambda: len(fake.published()) == 1)
    assert result.ok and result.sent and result.ack is None and result.accepted is None
    assert "not waiting" in result.detail


def test_rosbridge_refused_when_nothing_listens() -> None:
    url = f"ws://127.0.0.1:{free_port()}"
    with RosbridgeTransmitter(url, open_timeout_s=1) as tx:
        result = tx.send(FRAME, wait_ack_s=1)
    assert not result.ok and result.reason == "connection refused" and not result.sent
    assert url in result.detail


def test_rosbridge_handshake_failure_is_reported() -> None:
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def answer_http_404() -> None:
        conn, _ = server.accept()
        with conn:
            conn.recv(4096)
            conn.sendall(b"HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\n\r\n")

    thread = threading.Thread(target=answer_http_404, daemon=True)
    thread.start()
    try:
        result = RosbridgeTransmitter(f"ws://127.0.0.1:{port}").send(FRAME, wait_ack_s=1)
    finally:
        thread.join(2)
        server.close()
    assert not result.ok and result.reason == "handshake failed (HTTP 404)"


def test_rosbridge_keeps_one_connection_and_drops_stale_acks() -> None:
    def respond(data: bytes) -> list[dict[str, Any] | str]:
        # the right ack, then a late stray one that must not answer the next frame
        return [mission(ack_for(data, seq=1)), mission(ack_for(FRAMES[2].to_bytes(), seq=99))]

    with FakeRosbridge(respond) as fake, RosbridgeTransmitter(fake.url, settle_s=1.0) as tx:
        first = tx.send(FRAMES[0], wait_ack_s=2)
        time.sleep(0.05)  # let the stray ack arrive before the next send
        second = tx.send(FRAMES[1], wait_ack_s=2)
        assert fake.connections == 1
        assert fake.ops().count("advertise") == 1 and fake.ops().count("subscribe") == 1
    assert first.ack is not None and first.ack_match == "exact"
    assert second.ack is not None and second.ack_match == "exact"
    assert second.ack["frame_hex"] == FRAMES[1].hex
    assert fake.published() == [FRAMES[0].to_bytes(), FRAMES[1].to_bytes()]


def test_rosbridge_reconnects_after_the_server_closed() -> None:
    with FakeRosbridge(close_after=1) as fake, RosbridgeTransmitter(fake.url) as tx:
        assert tx.send(FRAMES[0], wait_ack_s=2).ack_match == "exact"
        wait_until(lambda: not tx.connected)
        result = tx.send(FRAMES[1], wait_ack_s=2)
        assert fake.connections == 2
    advertise_ids = [m["id"] for m in fake.received if m["op"] == "advertise"]
    assert advertise_ids == ["advertise:/nemesys/frame:1"] * 2  # same id on the new connection
    assert result.ok and result.ack is not None and result.ack["frame_hex"] == FRAMES[1].hex


def test_rosbridge_closed_while_waiting() -> None:
    with FakeRosbridge(respond=None, close_after=1) as fake, RosbridgeTransmitter(fake.url) as tx:
        start = time.monotonic()
        result = tx.send(FRAME, wait_ack_s=2)
        assert time.monotonic() - start < 1.0
    assert not result.ok and result.reason == "connection closed" and result.sent


# --- rosbridge: waiting for the vehicle's subscriber before the first publish ------------


def _timed_send(
    fake: FakeRosbridge, wait_ack_s: float = 2.0, subscriber_wait_s: float = 0.5
) -> tuple[SendResult, float]:
    with RosbridgeTransmitter(fake.url, subscriber_wait_s=subscriber_wait_s) as tx:
        start = time.monotonic()
        result = tx.send(FRAME, wait_ack_s=wait_ack_s)
        return result, time.monotonic() - start


def _asked_before_publishing(fake: FakeRosbridge) -> list[dict[str, Any]]:
    ops = fake.ops()
    asks = [m for m in fake.received[: ops.index("publish")] if m["op"] == "call_service"]
    assert asks, ops
    for ask in asks:
        assert ask["service"] == "/rosapi/subscribers"
        assert ask["args"] == {"topic": "/nemesys/frame"}
    return asks


def test_a_subscriber_present_publishes_at_once() -> None:
    with FakeRosbridge() as fake:
        result, elapsed_s = _timed_send(fake, subscriber_wait_s=5.0)
        assert len(_asked_before_publishing(fake)) == 1
    assert elapsed_s < 0.5  # one question, answered: no waiting for the bound
    assert result.ok and result.ack_match == "exact" and result.warning is None


def test_a_subscriber_that_appears_late_is_waited_for() -> None:
    with FakeRosbridge(subscribed_after=2) as fake:
        result, elapsed_s = _timed_send(fake, subscriber_wait_s=5.0)
        assert len(_asked_before_publishing(fake)) == 3  # nobody, nobody, the vehicle
    assert 0.15 <= elapsed_s < 1.5  # asked again every 0.1 s, not the 5 s bound
    assert result.ok and result.warning is None


@pytest.mark.slow  # the transmitter's real bound
def test_no_subscriber_ever_publishes_after_the_bound_with_a_warning() -> None:
    with FakeRosbridge(respond=None, subscribers=[]) as fake:
        result, elapsed_s = _timed_send(fake, wait_ack_s=0.2, subscriber_wait_s=0.5)
        assert fake.published() == [FRAME.to_bytes()]  # published all the same
        assert len(_asked_before_publishing(fake)) > 1
    assert 0.5 + 0.2 <= elapsed_s < 2.0
    warning = "no subscriber to /nemesys/frame after 0.5 s: the frame may be lost"
    assert result.warning == warning and result.sent
    assert result.reason == "timeout" and result.detail.endswith(f"; {warning}")


def test_the_warning_stays_when_an_acknowledgement_comes_anyway() -> None:
    with FakeRosbridge(subscribers=[]) as fake:
        result, _ = _timed_send(fake, subscriber_wait_s=0.3)
    assert result.ok and result.ack_match == "exact"
    assert result.warning is not None and "may be lost" in result.warning
    assert result.detail == "acknowledged"  # an acknowledgement proves it was not lost


@pytest.mark.parametrize(
    ("options", "why"),
    [
        ({"subscribers_service": False}, "/rosapi/subscribers failed: Service"),
        ({"rosapi": False}, "no answer from /rosapi/subscribers"),
    ],
)
def test_when_rosapi_cannot_tell_it_publishes_after_the_bound(
    options: dict[str, Any], why: str
) -> None:
    with FakeRosbridge(respond=None, **options) as fake:
        result, elapsed_s = _timed_send(fake, wait_ack_s=0, subscriber_wait_s=0.4)
        wait_until(lambda: fake.published() == [FRAME.to_bytes()])
        assert len(_asked_before_publishing(fake)) == 1  # not asked again
    assert 0.4 <= elapsed_s < 1.5
    assert result.ok and result.warning is None
    assert why in result.detail and "published 0.4 s after advertising" in result.detail


def test_a_kept_connection_does_not_wait_again() -> None:
    with FakeRosbridge(subscribers=[]) as fake:
        with RosbridgeTransmitter(fake.url, subscriber_wait_s=0.3) as tx:
            first = tx.send(FRAMES[0], wait_ack_s=2)
            start = time.monotonic()
            second = tx.send(FRAMES[1], wait_ack_s=2)
            assert time.monotonic() - start < 0.25
        assert fake.ops().count("call_service") > 1
        assert fake.ops().index("publish") > max(
            i for i, op in enumerate(fake.ops()) if op == "call_service"
        )
    assert first.warning is not None and second.warning is None


def test_no_wait_when_switched_off() -> None:
    with FakeRosbridge() as fake:
        result, _ = _timed_send(fake, subscriber_wait_s=0)
        assert "call_service" not in fake.ops()
    assert result.ok and result.warning is None


# --- docs ---------------------------------------------------------------------------------


def test_transmitters_doc_examples_are_the_real_bytes() -> None:
    doc = (Path(__file__).parents[2] / "docs" / "transmitters.md").read_text()
    assert " ".join(f"{b:02x}" for b in FRAME.to_bytes()) in doc
    assert f"(hex `{FRAME.hex}`)" in doc
    assert json.dumps({"data": list(FRAME.to_bytes())}) in doc
    for form in TARGET_FORMS:
        assert form.split("[")[0] in doc
