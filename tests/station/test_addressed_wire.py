"""A fleet's addressed frames on the station's frame path (issue 23): the 14 bytes of a 108-bit
frame leave whole through the serial and TCP transmitters and the rosbridge message, an
acknowledgement of an addressed frame matches it (exactly, or within the BCH radius) and never
a 100-bit frame, and ``other_vehicle`` is no sign of a damaged frame to the BER estimate."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from codec import (
    ADDRESSED_FRAME_BYTES,
    FRAME_BYTES,
    AddressedFrame,
    Frame,
    RejectReason,
    decode_addressed_frame,
    encode_frame,
)
from station.channel_estimate import evidence_of
from station.transmit import SerialTransmitter, TcpTransmitter, ack_match, frame_msg
from tests.station.gateways import Gateway

CIRCLE: dict[str, float | str] = {"speed": 0.5, "depth": 2, "radius": 5, "direction": "cw"}
TO_3 = encode_frame("circle", CIRCLE, address=3).frame
TO_ALL = encode_frame("surface", {}, address=0).frame
PLAIN = encode_frame("circle", CIRCLE).frame


@pytest.fixture
def gateway() -> Iterator[Gateway]:
    g = Gateway("read", frame_bytes=ADDRESSED_FRAME_BYTES)
    try:
        yield g
    finally:
        g.close()


def test_the_tcp_transmitter_writes_each_addressed_frame_whole(gateway: Gateway) -> None:
    frames: list[bytes] = []
    gateway.on_frame = frames.append
    tx = TcpTransmitter("127.0.0.1", gateway.port, name=gateway.target)
    with tx:
        results = [tx.send(f) for f in (TO_3, TO_ALL)]
        gateway.wait_for("2 frames", lambda: gateway.total() == 2 * ADDRESSED_FRAME_BYTES)
    assert all(r.ok for r in results)
    assert "14 bytes" in results[0].detail
    decoded = [decode_addressed_frame(f) for f in frames]
    assert [(d.address, d.command.pattern.name) for d in decoded] == [(3, "circle"), (0, "surface")]


def test_the_serial_transmitter_writes_the_14_bytes() -> None:
    tx = SerialTransmitter("loop://", bitrate_bps=36_000)
    with tx:
        result = tx.send(TO_3)
        assert result.ok and "14 bytes" in result.detail
        port = tx._port
        assert port is not None
        data = port.read(ADDRESSED_FRAME_BYTES)
    assert data == TO_3.to_bytes() and len(data) == ADDRESSED_FRAME_BYTES
    assert decode_addressed_frame(data).address == 3


def test_the_rosbridge_message_carries_every_byte() -> None:
    assert frame_msg(TO_3) == {"data": list(TO_3.to_bytes())}
    assert len(frame_msg(TO_3)["data"]) == ADDRESSED_FRAME_BYTES
    assert len(frame_msg(PLAIN)["data"]) == FRAME_BYTES


def _flip(frame: Frame, *bits: int) -> AddressedFrame:
    value = frame.value
    for b in bits:  # counted from the last codeword bit (above the 4 guard bits)
        value ^= 1 << (4 + b)
    return AddressedFrame(value)


def test_an_acknowledgement_matches_its_addressed_frame_in_every_form() -> None:
    assert ack_match(TO_3, {"frame_hex": TO_3.hex}) == "exact"
    assert ack_match(TO_3, {"frame_hex": TO_3.to_bytes().hex()}) == "exact"  # 28 hex digits
    assert ack_match(TO_3, {"frame_hex": _flip(TO_3, 5, 40).hex}) == "near"
    assert ack_match(TO_3, {"frame_hex": _flip(TO_3, 5, 40, 60).hex}) is None
    assert ack_match(TO_3, {"frame_hex": TO_ALL.hex}) is None


def test_frames_of_the_two_forms_never_match_each_other() -> None:
    plain_surface = encode_frame("surface", {}).frame
    assert ack_match(plain_surface, {"frame_hex": TO_ALL.hex}) is None
    assert ack_match(TO_ALL, {"frame_hex": plain_surface.hex}) is None
    assert ack_match(PLAIN, {"frame_hex": PLAIN.hex}) == "exact"  # today's, unchanged


def test_other_vehicle_says_nothing_of_the_channel_to_the_estimate() -> None:
    rejected = {"outcome": "rejected", "reason": RejectReason.OTHER_VEHICLE.value}
    assert evidence_of({**rejected, "corrected_bits": 0, "sync_errors": 0}) is None
    damaged = {"outcome": "rejected", "reason": RejectReason.UNCORRECTABLE.value}
    evidence = evidence_of(damaged)
    assert evidence is not None and not evidence.decoded
