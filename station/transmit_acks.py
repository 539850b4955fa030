"""What comes back over rosbridge, for :mod:`station.transmit_rosbridge`: the vehicle's
acknowledgements, and how one is matched to the sent frame. :func:`ack_match` is
public (import it from :mod:`station.transmit`); the rest serves the rosbridge transmitter.

Acknowledgement matching
------------------------
Acknowledgements already waiting on the connection are discarded before the publish. After it,
the first mission message whose ``frame_hex`` is the sent frame is the acknowledgement
("exact"); so is one whose codeword is within the BCH correction radius (``CODE.t`` = 2 bits)
of the sent codeword, differences in the fixed preamble, delimiter and guard bits not counting
("near": the channel flipped bits). Any other new acknowledgement is kept as a fallback: if no
exact or near one follows within ``settle_s`` (0.5 s) of it, or before the timeout, the first
such acknowledgement is returned ("first": matched by order, e.g. the vehicle slipped bits and
reports what it received). No acknowledgement within ``wait_ack_s`` of the publish: failed,
reason "timeout" (``sent_t`` is set, the frame did go out).
"""

from __future__ import annotations

import time
from typing import Any

from codec import CODE, FRAME_BYTES, DecodeError, Frame, parse_frame
from rosbridge.client import decode_json_string
from rosbridge.errors import InvalidData
from station.transmit_base import AckMatch, logger

#: After a new acknowledgement that is not for the sent frame, how long to wait for one that is.
ACK_SETTLE_S = 0.5


def _frame_value(text: object) -> int | None:
    """The 100-bit value of an acknowledgement's ``frame_hex`` (25 hex digits, or the 26 of the
    13 packed bytes); None if it is not one."""
    if not isinstance(text, str):
        return None
    try:
        if len(text.strip()) == 2 * FRAME_BYTES:
            return parse_frame(bytes.fromhex(text))
        return parse_frame(text)
    except (DecodeError, ValueError):
        return None


def ack_match(frame: Frame, ack: dict[str, Any]) -> AckMatch | None:
    """How ``ack`` matches ``frame``: ``"exact"`` if its ``frame_hex`` is the frame, ``"near"``
    if its codeword is within the BCH correction radius of the frame's, else None."""
    value = _frame_value(ack.get("frame_hex"))
    if value is None:
        return None
    if value == frame.value:
        return "exact"
    if (Frame(value).codeword ^ frame.codeword).bit_count() <= CODE.t:
        return "near"
    return None


class _AckMatcher:
    """Applies the matching rule to the acknowledgements that arrive after a publish."""

    def __init__(self, frame: Frame, wait_s: float, settle_s: float) -> None:
        self.frame = frame
        self.settle_s = settle_s
        self.deadline = time.monotonic() + wait_s
        self.ack: dict[str, Any] | None = None
        self.match: AckMatch | None = None
        self._first_until: float | None = None

    def offer(self, ack: dict[str, Any]) -> bool:
        """Take one new acknowledgement; True when the search is over."""
        match = ack_match(self.frame, ack)
        if match is not None:
            self.ack, self.match = ack, match
            return True
        if self._first_until is None:
            logger.info("acknowledgement seq=%s is not for frame %s", ack.get("seq"), self.frame)
            self.ack, self.match = ack, "first"
            self._first_until = min(self.deadline, time.monotonic() + self.settle_s)
        return False

    def remaining_s(self) -> float:
        until = self.deadline if self._first_until is None else self._first_until
        return until - time.monotonic()


def ack_of(msg: object) -> dict[str, Any] | None:
    """The acknowledgement a ``/nemesys/mission`` message carries, or None (logged) if it
    holds none."""
    try:
        return decode_json_string(msg)
    except InvalidData as error:
        logger.warning("ignoring a mission message: %s", error.reason)
        return None
