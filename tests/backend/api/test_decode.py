"""``POST /api/decode`` with a fleet's addressed frames (issue 23): every frame a fleet's console
sends is a 108-bit addressed frame, so the decode tool takes it as well as the single
vehicle's 100-bit frame, and says whom it is for on this console. A frame that fails a check
is refused with the codec's reason, never read as what it might have been.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from fastapi.testclient import TestClient

from codec import encode_frame, payload_of
from codec._address import (
    _CRC_CHECK,
    ADDRESSED_CODE,
    ADDRESSED_CODEWORD_BITS,
    ADDRESSED_FRAME_BITS,
    FLEET_SYNC_WORD,
    AddressedFrame,
)
from codec._frame import CRC_BITS, GUARD_BITS, PAYLOAD_BITS
from tests.agent_link import agent_fleet
from tests.backend.conftest import CIRCLE, SQUARE, MakeLightClient, wait_until
from vehicle_contract.fleet import parse_vehicles

#: The single vehicle's answer, exactly as before fleets (no key of an addressed frame).
SINGLE_KEYS = {"ok", "command", "corrected", "sync_errors"}


@pytest.fixture
def fleet(make_light_client: MakeLightClient) -> Iterator[TestClient]:
    link = agent_fleet(parse_vehicles("3"))
    client = make_light_client(link, vehicles="3")  # type: ignore[arg-type]
    wait_until(lambda: all(v["pose"] for v in client.get("/api/vehicles").json()))
    yield client


def decode(client: TestClient, frame: str) -> Any:
    return client.post("/api/decode", json={"frame": frame})


def rejected(client: TestClient, frame: str) -> dict[str, Any]:
    r = decode(client, frame)
    assert r.status_code == 422, r.text
    detail: dict[str, Any] = r.json()["detail"]
    assert set(detail) == {"reason", "message", "field"}
    return detail


def flipped(bits: str, *at: int) -> str:
    out = list(bits)
    for i in at:
        out[i] = "1" if out[i] == "0" else "0"
    return "".join(out)


def test_what_the_fleet_console_sent_decodes_with_its_vehicle(fleet: TestClient) -> None:
    """The frame /api/encode gives for auv2 (what a send to it puts on the air), as hex and
    as bits, decodes to its command, address 2 and the console's auv2."""
    body = {"pattern": "square", "params": SQUARE, "vehicle": "auv2"}
    sent = fleet.post("/api/encode", json=body).json()
    assert len(sent["hex"]) == ADDRESSED_FRAME_BITS // 4 and sent["frame_bits"] == 108
    for text in (sent["hex"], sent["hex"].upper(), sent["bits"], "0x" + sent["hex"]):
        r = decode(fleet, text)
        assert r.status_code == 200, r.text
        d = r.json()
        assert d["command"]["pattern"] == "square"
        assert d["command"]["params"] == sent["params"]
        assert (d["address"], d["vehicle"]) == (2, "auv2")
        assert d["addressed_to"] == "auv2 (address 2)"
        assert d["corrected"] == 0 and d["sync_errors"] == 0


def test_surface_to_all_is_for_all_vehicles(fleet: TestClient) -> None:
    sent = fleet.post(
        "/api/encode", json={"pattern": "surface", "params": {}, "vehicle": "all"}
    ).json()
    d = decode(fleet, sent["hex"]).json()
    assert d["command"]["pattern"] == "surface"
    assert (d["address"], d["vehicle"]) == (0, "all")
    assert d["addressed_to"].startswith("all vehicles")


def test_an_address_no_vehicle_of_the_fleet_has(fleet: TestClient) -> None:
    frame = encode_frame("circle", CIRCLE, address=7).frame
    d = decode(fleet, frame.hex).json()
    assert (d["address"], d["vehicle"]) == (7, None)
    assert "no vehicle of this console's fleet" in d["addressed_to"]
    assert "auv3 3" in d["addressed_to"]  # the addresses it has


def test_the_single_vehicle_answer_is_unchanged_and_an_addressed_frame_says_no_fleet(
    make_light_client: MakeLightClient,
) -> None:
    client = make_light_client()
    single = decode(client, encode_frame("square", SQUARE).frame.hex)
    assert single.status_code == 200 and set(single.json()) == SINGLE_KEYS
    addressed = decode(client, encode_frame("square", SQUARE, address=4).frame.bits).json()
    assert set(addressed) == SINGLE_KEYS | {"address", "vehicle", "addressed_to"}
    assert (addressed["address"], addressed["vehicle"]) == (4, None)
    assert "no fleet" in addressed["addressed_to"]


def test_bit_errors_within_reach_are_corrected_and_counted(fleet: TestClient) -> None:
    frame = encode_frame("circle", CIRCLE, address=1).frame
    # one sync bit, two codeword bits (the address word's and a field's)
    d = decode(fleet, flipped(frame.bits, 3, 26, 60)).json()
    assert (d["sync_errors"], d["corrected"]) == (1, 2)
    assert (d["address"], d["vehicle"]) == (1, "auv1")
    assert d["command"]["params"] == encode_frame("circle", CIRCLE).command.params


def test_a_frame_that_fails_a_check_is_refused_not_guessed(fleet: TestClient) -> None:
    bits = encode_frame("circle", CIRCLE, address=2).frame.bits
    # the sync word beyond the tolerance
    assert rejected(fleet, flipped(bits, 0, 2, 4, 6))["reason"] == "no_sync"
    # the single vehicle's sync word on an addressed frame's length: not an addressed frame
    single_sync = format(encode_frame("circle", CIRCLE).frame.value >> 84, "024b")
    assert rejected(fleet, single_sync + bits[24:])["reason"] == "no_sync"
    # three codeword errors: beyond the code (uncorrectable, or a miscorrection caught later)
    three = rejected(fleet, flipped(bits, 30, 50, 70))
    assert three["reason"] in {"uncorrectable", "crc_mismatch", "other_vehicle"}
    # a codeword with a good CRC whose address word is no address: refused, not rounded to one
    covered = (0x35 << PAYLOAD_BITS) | payload_of(encode_frame("circle", CIRCLE).command)
    message = (covered << CRC_BITS) | _CRC_CHECK(covered << CRC_BITS)
    codeword = ADDRESSED_CODE.encode(message)
    sync = FLEET_SYNC_WORD << (ADDRESSED_CODEWORD_BITS + GUARD_BITS)
    word = AddressedFrame(sync | (codeword << GUARD_BITS))
    detail = rejected(fleet, word.hex)
    assert detail["reason"] == "other_vehicle" and "no address" in detail["message"]


@pytest.mark.parametrize(
    "frame",
    ["0" * 99, "f" * 26, "a" * 28, "0" * 107, "1" * 109, "0x" + "a" * 26],
)
def test_a_wrong_length_names_both_frames_lengths(fleet: TestClient, frame: str) -> None:
    detail = rejected(fleet, frame)
    assert detail["reason"] == "malformed"
    message = detail["message"]
    for allowed in ("100 binary digits", "25 hex digits", "108 binary digits", "27 hex digits"):
        assert allowed in message, message


@pytest.mark.parametrize(("frame", "bad"), [("0" * 107 + "2", "'2'"), ("g" + "0" * 26, "'g'")])
def test_an_addressed_length_of_wrong_digits_names_the_digit(
    fleet: TestClient, frame: str, bad: str
) -> None:
    detail = rejected(fleet, frame)
    assert detail["reason"] == "malformed" and bad in detail["message"]
