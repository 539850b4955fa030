"""The reference node of a fleet's vehicle (``vehicle_address`` 1-15; docs/protocol.md,
"Addressing"): addressed frames from the topic and from a serial stream, its status saying its
address; 0 (the default) is today's node."""

from __future__ import annotations

from typing import Any

import pytest

from codec import ParamValue, encode_frame
from nemesys_vehicle.config import VehicleConfig
from nemesys_vehicle.core import VehicleCore
from nemesys_vehicle.messages import Recorder, frame_bits
from nemesys_vehicle.stream import FrameStream
from tests.nemesys_vehicle.helpers import AT_DATUM, CIRCLE, T0_S, odometry, same_ack
from vehicle_contract.payloads import validate_ack, validate_status

NOISE = bytes.fromhex("5aa5c3f00f")


def to(address: int | None, pattern: str = "circle", **params: ParamValue) -> bytes:
    values = params or (CIRCLE if pattern == "circle" else {})
    return encode_frame(pattern, values, address=address).frame.to_bytes()


def core(**config: Any) -> tuple[VehicleCore, Recorder]:
    rec = Recorder()
    node = VehicleCore(VehicleConfig(**{**AT_DATUM, **config}), rec.sinks())
    node.on_odometry(odometry(T0_S))
    return node, rec


def test_frames_from_the_topic() -> None:
    node, _ = core(vehicle_address=2)
    acks = [node.on_frame(data, T0_S + 1) for data in (to(2), to(3, "surface"), to(0, "surface"))]
    assert [(a["outcome"], a["reason"], a["address"]) for a in acks] == [
        ("accepted", None, 2),
        ("rejected", "other_vehicle", 3),
        ("accepted", None, 0),
    ]
    assert all(validate_ack(a) == [] for a in acks)
    status = node.tick_status(T0_S + 2)
    assert status["address"] == 2 and validate_status(status) == []
    assert status["pattern"] == "surface"


def test_without_an_address_the_node_is_todays() -> None:
    node, _ = core()
    ack = node.on_frame(to(2), T0_S + 1)
    assert ack["reason"] == "malformed" and "address" not in ack
    assert "address" not in node.tick_status(T0_S + 2)
    assert frame_bits(to(2)) == (None, 112)  # 14 bytes are no frame to it


def test_a_serial_stream_gives_the_acks_the_topic_gives() -> None:
    sent = [to(2), to(None, "surface"), to(5), to(None), to(0, "surface")]
    by_topic, topic_rec = core(vehicle_address=2)
    for data in sent:
        by_topic.on_frame(data, T0_S + 1)
    by_serial, serial_rec = core(vehicle_address=2, frame_input="serial", serial_url="loop://")
    stream = NOISE + b"".join(sent) + NOISE
    acks = [
        a
        for i in range(0, len(stream), 3)
        for a in by_serial.on_serial_bytes(stream[i : i + 3], T0_S + 1)
    ]
    assert acks == serial_rec.acks and len(acks) == len(sent)
    for got, want in zip(acks, topic_rec.acks, strict=True):
        assert same_ack(got, want)
    assert [a["address"] for a in acks] == [2, None, 5, None, 0]


def test_the_stream_cuts_each_frame_at_its_length() -> None:
    stream = FrameStream(4)
    frames = stream.feed(NOISE + to(4) + to(None, "surface") + NOISE)
    assert [len(f) for f in frames] == [14, 13]
    assert frames == [to(4), to(None, "surface")]


@pytest.mark.parametrize("bad", [-1, 16, 2.0])
def test_an_address_out_of_range_is_refused(bad: object) -> None:
    with pytest.raises(ValueError, match=r"vehicle_address must be 0 .* 1 to 15"):
        VehicleConfig(vehicle_address=bad)  # type: ignore[arg-type]
