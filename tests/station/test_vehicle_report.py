"""The pre-dive probe of ``vehicle-check`` (:mod:`station.vehicle_report`): a malformed frame
every receiver synchronises on and every decoder rejects, and what its acknowledgement must
say."""

from __future__ import annotations

from itertools import combinations
from typing import Any

from codec import CODE, CODEWORD_BITS, FRAME_BYTES, FrameReceiver, Rejected
from station.vehicle_report import PROBE_FRAME, PROBE_REASON, Ack, Check, malformed_probe_check


def test_no_codeword_lies_within_the_correction_radius_of_the_probe() -> None:
    """So any bounded-distance BCH decoder, not only ours, finds it uncorrectable."""
    received = PROBE_FRAME.codeword
    for weight in (0, 1, 2):
        for bits in combinations(range(CODEWORD_BITS), weight):
            error = sum(1 << b for b in bits)
            assert CODE.remainder(received ^ error) != 0, bits


def test_the_receiver_synchronises_on_the_probe_and_rejects_it() -> None:
    assert len(PROBE_FRAME.to_bytes()) == FRAME_BYTES
    events = FrameReceiver().feed_bytes(PROBE_FRAME.to_bytes())
    assert len(events) == 1 and isinstance(events[0], Rejected)
    assert events[0].error.reason.value == PROBE_REASON == "uncorrectable"


def ack(**fields: Any) -> Ack:
    body = {
        "outcome": "rejected",
        "reason": "uncorrectable",
        "detail": "more than 2 bit errors",
        "frame_hex": PROBE_FRAME.hex,
        "active": None,
        **fields,
    }
    return Ack(10.25, body)


def check(answer: Ack | None, active: object = None) -> tuple[str, str]:
    row = malformed_probe_check(
        answer, sent_s=10.0, waited_s=3.0, path="published on /nemesys/frame", active=active
    )
    assert row.name == "ack path (probe)"
    return row.result, row.reason


def test_a_rejection_with_the_reason_passes() -> None:
    result, reason = check(ack())
    assert result == "pass"
    assert reason.endswith(
        "rejected as uncorrectable in 0.25 s (the contract's deadline 1 s); nothing changed"
    )


def test_anything_else_fails_naming_it() -> None:
    assert check(None) == (
        "fail",
        f"a malformed frame ({PROBE_FRAME.hex}: codeword beyond correction) published on "
        "/nemesys/frame: no acknowledgement within 3 s (the contract's deadline 1 s)",
    )
    result, reason = check(ack(outcome="accepted", reason=None))
    assert result == "fail" and "accepted in 0.25 s" in reason and "must be rejected" in reason
    result, reason = check(ack(reason="crc_mismatch"))
    assert result == "fail" and "rejected as 'crc_mismatch', not 'uncorrectable'" in reason
    result, reason = check(ack(late=True))
    assert result == "fail" and reason.endswith("answered after the contract's deadline")
    assert check(ack(late=False))[0] == "pass"
    slow = Ack(11.5, ack().ack)  # the vehicle did not say late, but the round trip was 1.5 s
    assert malformed_probe_check(slow, sent_s=10.0, waited_s=3.0, path="p") == Check(
        "ack path (probe)",
        "fail",
        f"a malformed frame ({PROBE_FRAME.hex}: codeword beyond correction) p: rejected as "
        "uncorrectable in 1.50 s (the contract's deadline 1 s): the round trip is past the "
        "deadline",
    )
    circle = {"pattern": "circle", "pattern_id": 3, "params": {}}
    result, reason = check(ack(active=None), active=circle)
    assert result == "fail" and "the active command changed" in reason
    assert check(ack(active=circle), active=circle)[0] == "pass"
    assert check(ack(active=circle), active=...)[0] == "pass"  # not known before: not compared
