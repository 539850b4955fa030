"""``nemesys encode/decode --vehicle N``: a fleet's addressed frames on the command line
(docs/protocol.md, "Addressing"); without the option both are today's."""

from __future__ import annotations

import json

import pytest

from cli.common import EXIT_OK, EXIT_REJECTED, EXIT_USAGE
from codec import ADDRESSED_FRAME_BITS, decode_addressed_frame, encode_frame
from tests.cli.test_cli import SQUARE, encode_json, run

#: The worked example to vehicle 3 (tests/codec/test_address.py checks it by hand).
TO_3 = "aaaa433c1321473000000f40ee0"


def test_encode_to_a_vehicle(capsys: pytest.CaptureFixture[str]) -> None:
    doc = encode_json([*SQUARE, "--vehicle", "3"], capsys)
    assert doc["hex"] == TO_3 and doc["address"] == 3
    assert len(doc["bits"]) == ADDRESSED_FRAME_BITS
    assert doc["airtime_ms"] == pytest.approx(108 / 36_000 * 1e3)
    assert [s["name"] for s in doc["sections"]][2:5] == ["address", "address_check", "pattern"]
    assert "".join(s["bits"] for s in doc["sections"]) == doc["bits"]
    assert decode_addressed_frame(doc["bits"]).address == 3
    status, out, _ = run(["encode", *SQUARE, "--vehicle", "0"], capsys)
    assert status == EXIT_OK and "  to              all vehicles\n" in out
    assert "address_check   bits 28-31  " in out and "airtime  3.000 ms" in out
    assert "address" not in encode_json(SQUARE, capsys)  # no option: today's frame


@pytest.mark.parametrize(
    ("command", "value", "message"),
    [
        ("encode", "16", "vehicle address 16 is out of range: allowed 0 (all vehicles) or 1 to 15"),
        ("encode", "-1", "vehicle address -1 is out of range: allowed 0 (all vehicles) or 1 to 15"),
        ("encode", "two", "vehicle address 'two' is not a whole number: allowed 0"),
        ("decode", "0", "vehicle address 0 is out of range: a vehicle's own address is 1 to 15"),
        ("decode", "99", "vehicle address 99 is out of range: a vehicle's own address is 1 to 15"),
    ],
)
def test_a_bad_vehicle_is_refused_naming_the_range(
    command: str, value: str, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    args = SQUARE if command == "encode" else [TO_3]
    status, out, err = run([command, *args, "--vehicle", value], capsys)
    assert status == EXIT_USAGE and out == ""
    assert message in err and "Traceback" not in err


def test_decode_as_the_console_and_as_each_vehicle(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, _ = run(["decode", TO_3], capsys)
    assert status == EXIT_OK
    assert out.endswith("(corrected 0 bits, to vehicle 3)\n")
    status, out, _ = run(["decode", TO_3, "--vehicle", "3", "--json"], capsys)
    assert status == EXIT_OK and json.loads(out)["address"] == 3
    status, out, err = run(["decode", TO_3, "--vehicle", "5"], capsys)
    assert status == EXIT_REJECTED
    assert err == "nemesys decode: rejected: addressed to vehicle 3, not to this vehicle (5)\n"
    status, out, _ = run(["decode", TO_3, "--vehicle", "5", "--json"], capsys)
    assert json.loads(out)["reason"] == "other_vehicle"


def test_unaddressed_frames_at_a_vehicle(capsys: pytest.CaptureFixture[str]) -> None:
    square = encode_frame("square", speed=0.5, depth=2, side_span=12.34, direction="cw")
    status, out, _ = run(["decode", square.frame.hex], capsys)
    assert status == EXIT_OK and "to vehicle" not in out  # today's output
    status, _, err = run(["decode", square.frame.hex, "--vehicle", "2"], capsys)
    assert status == EXIT_REJECTED and "an unaddressed frame (square)" in err
    status, out, _ = run(["decode", encode_frame("surface").frame.hex, "--vehicle", "2"], capsys)
    assert status == EXIT_OK and out.startswith("surface")
