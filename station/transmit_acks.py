"""What comes back over rosbridge, for :mod:`station.transmit_rosbridge`: the vehicle's
acknowledgements, and how one is matched to the sent frame. :func:`ack_match` is
public (import it from :mod:`station.transmit`); the rest serves the rosbridge transmitter.

Acknowledgement matching
------------------------
Acknowledgements already waiting on the connection are discarded before the publish. After it, the
first mission message whose ``frame_hex`` is the sent frame is the acknowledgement ("exact"); so is
one whose codeword is within the BCH correction radius (``CODE.t`` = 2 bits) of the sent codeword (a
frame of the same form: 100-bit, or a fleet's 108-bit addressed one), differences in the fixed
preamble, delimiter and guard bits not counting ("near": the channel flipped bits). Any other new
acknowledgement is kept as a fallback: if no exact or near one follows within ``settle_s`` (0.5 s)
of it, or before the timeout, the first such acknowledgement is returned ("first": matched by order,
e.g. the vehicle slipped bits and reports what it received). No acknowledgement within
``wait_ack_s`` of the publish: failed, reason "timeout" (``sent_t`` is set, the frame did go out).
"""

from __future__ import annotations

import time
from typing import Any

from codec import (
    ADDRESSED_FRAME_BITS,
    ADDRESSED_FRAME_BYTES,
    CODE,
    FRAME_BYTES,
    AddressedFrame,
    DecodeError,
    Frame,
    parse_frame,
)
from rosbridge.client import decode_json_string
from rosbridge.errors import InvalidData
from station.transmit_base import AckMatch, logger

#: Hex digits of an addressed frame's 108 bits.
_ADDRESSED_HEX = ADDRESSED_FRAME_BITS // 4
#: After a new acknowledgement that is not for the sent frame, how long to wait for one that is.
ACK_SETTLE_S = 0.5


def _frame_of(text: object) -> Frame | None:
    """The frame an acknowledgement's ``frame_hex`` names: today's (25 hex digits, or the 26 of
    its 13 packed bytes) or a fleet's addressed frame (27 hex digits, or the 28 of its 14
    bytes, the last 4 bits zero); None if it is neither."""
    if not isinstance(text, str):
        return None
    compact = text.strip()
    try:
        if len(compact) == _ADDRESSED_HEX:
            return AddressedFrame(int(compact, 16))
        if len(compact) == 2 * ADDRESSED_FRAME_BYTES:
            value = int.from_bytes(bytes.fromhex(compact), "big")
            pad = 8 * ADDRESSED_FRAME_BYTES - ADDRESSED_FRAME_BITS
            return None if value & ((1 << pad) - 1) else AddressedFrame(value >> pad)
        if len(compact) == 2 * FRAME_BYTES:
            return Frame(parse_frame(bytes.fromhex(compact)))
        return Frame(parse_frame(compact))
    except (DecodeError, ValueError):
        return None


def ack_match(frame: Frame, ack: dict[str, Any]) -> AckMatch | None:
    """How ``ack`` matches ``frame``: ``"exact"`` if its ``frame_hex`` is the frame, ``"near"``
    if it is a frame of the same form (both 100-bit, or both addressed) whose codeword is
    within the BCH correction radius of the frame's, else None."""
    got = _frame_of(ack.get("frame_hex"))
    if got is None or isinstance(got, AddressedFrame) != isinstance(frame, AddressedFrame):
        return None
    if got.value == frame.value:
        return "exact"
    if (got.codeword ^ frame.codeword).bit_count() <= CODE.t:
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
