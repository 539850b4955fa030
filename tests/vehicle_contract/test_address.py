"""What 2.1 states: a fleet on one ME link. A vehicle's address is optional; where it is set,
the addressed frame, the other_vehicle reason and the address fields (docs/protocol.md,
"Addressing")."""

from __future__ import annotations

from typing import Any

from codec import BROADCAST_ADDRESS, MAX_ADDRESS, RejectReason, encode_frame
from vehicle_contract import codes, contract
from vehicle_contract.payloads import validate_ack, validate_status


def _ack(**changes: Any) -> dict[str, Any]:
    frame = encode_frame("surface", address=3).frame
    ack: dict[str, Any] = {
        "seq": 1,
        "t_s": 1.0,
        "outcome": "rejected",
        "frame_hex": frame.hex,
        "reason": "other_vehicle",
        "detail": "addressed to vehicle 3, not to this vehicle (4)",
        "command": None,
        "duplicate": False,
        "active": None,
        "from": None,
        "address": 3,
    }
    return {**ack, **changes}


def test_the_reason_and_the_address_range_are_the_codecs() -> None:
    assert codes.OTHER_VEHICLE == RejectReason.OTHER_VEHICLE.value in codes.REJECT_REASONS
    assert (codes.BROADCAST_ADDRESS, codes.MAX_ADDRESS) == (BROADCAST_ADDRESS, MAX_ADDRESS)


def test_the_obligations_and_the_frame_topic_say_so() -> None:
    text = " ".join(contract.OBLIGATIONS)
    for words in ("vehicle_address", "other_vehicle", "1 to 15", "14 bytes", "only surface"):
        assert words in text, words
    assert "108-bit addressed frame in 14 bytes" in contract.topic(contract.FRAME_TOPIC).description


def test_an_addressed_acknowledgement_validates() -> None:
    assert validate_ack(_ack()) == []
    assert validate_ack(_ack(address=None)) == []
    assert (
        validate_ack(_ack(frame_hex=encode_frame("surface", address=3).frame.to_bytes().hex()))
        == []
    )
    assert validate_ack(_ack(address=16)) != []
    assert validate_ack(_ack(frame_hex="a" * 29)) != []


def test_the_status_says_the_vehicles_own_address() -> None:
    status = {
        "t_s": 1.0,
        "depth_m": 0.0,
        "heading_deg": 0.0,
        "speed_mps": 0.0,
        "battery_pct": None,
        "mode": "idle",
        "pattern": None,
    }
    assert validate_status({**status, "address": 4}) == []
    assert validate_status(status) == []  # no address: a single vehicle, as in 2.0
    assert validate_status({**status, "address": 0}) != []  # 0 is everyone's, never one's own
