"""Decoding one aligned frame given in any accepted form: :func:`parse_frame` and
:func:`decode_frame`, for the console, the CLI and the benches.

The vehicle decodes through :class:`codec.FrameReceiver` (:mod:`codec._sync`) and never loads
this module; :mod:`codec` imports it on first use of one of its names.
"""

from __future__ import annotations

from collections.abc import Sequence

from codec._dictionary import DICTIONARY, CommandDictionary
from codec._errors import DecodeError, RejectReason
from codec._frame import (
    CODEWORD_BITS,
    DEFAULT_SYNC_TOLERANCE,
    FRAME_BITS,
    FRAME_BYTES,
    FRAME_HEX_DIGITS,
    FRAME_MASK,
    GUARD_BITS,
    PAD_BITS,
    SYNC_WORD,
    Decoded,
    Frame,
    decode_codeword,
)


def parse_frame(frame: object) -> int:
    """A 100-bit frame in any accepted form, as an int.

    Accepted: :class:`Frame`; a string of 100 '0'/'1' (spaces and underscores ignored) or 25
    hex digits (optional ``0x``); 13 bytes (MSB first, last 4 bits zero); an int below
    2^100; a sequence of 100 ints 0/1.

    Raises:
        DecodeError: ``MALFORMED``, saying what was expected.
    """
    if isinstance(frame, Frame):
        return frame.value
    if isinstance(frame, str):
        return _parse_text(frame)
    if isinstance(frame, bytes | bytearray | memoryview):
        data = bytes(frame)
        if len(data) != FRAME_BYTES:
            raise _malformed(f"expected {FRAME_BYTES} bytes, got {len(data)}")
        value = int.from_bytes(data, "big")
        if value & ((1 << PAD_BITS) - 1):
            raise _malformed(f"the last {PAD_BITS} bits of byte {FRAME_BYTES} must be zero")
        return value >> PAD_BITS
    if isinstance(frame, bool):
        raise _malformed("expected a frame, got a bool")
    if isinstance(frame, int):
        if not 0 <= frame <= FRAME_MASK:
            raise _malformed(f"an int frame must be 0 <= value < 2^{FRAME_BITS}")
        return frame
    if isinstance(frame, Sequence):
        if len(frame) != FRAME_BITS:
            raise _malformed(f"expected {FRAME_BITS} bits, got {len(frame)}")
        value = 0
        for bit in frame:
            if type(bit) is not int or bit not in (0, 1):
                raise _malformed(f"bits must be 0 or 1, got {bit!r}")
            value = (value << 1) | bit
        return value
    raise _malformed(f"expected bits, hex, bytes or an int, got {type(frame).__name__}")


def _parse_text(text: str) -> int:
    compact = text.strip().replace(" ", "").replace("_", "")
    if len(compact) == FRAME_BITS:
        if compact.strip("01"):
            bad = next(c for c in compact if c not in "01")
            raise _malformed(f"a {FRAME_BITS}-character frame may hold only 0 and 1, found {bad!r}")
        return int(compact, 2)
    if compact[:2].lower() == "0x":
        compact = compact[2:]
    if len(compact) == FRAME_HEX_DIGITS:
        # int(..., 16) alone would also take a sign and non-ASCII digits.
        if compact.strip(_HEX_DIGITS):
            raise _malformed(f"{compact!r} is not {FRAME_HEX_DIGITS} hex digits (0-9, a-f)")
        return int(compact, 16)
    shown = text if len(text) <= 40 else text[:37] + "..."
    raise _malformed(
        f"expected {FRAME_BITS} binary digits or {FRAME_HEX_DIGITS} hex digits, "
        f"got {len(compact)} characters: {shown!r}"
    )


_HEX_DIGITS = "0123456789abcdefABCDEF"


def _malformed(detail: str) -> DecodeError:
    return DecodeError(RejectReason.MALFORMED, f"malformed frame: {detail}")


def decode_frame(
    frame: object,
    *,
    sync_tolerance: int = DEFAULT_SYNC_TOLERANCE,
    dictionary: CommandDictionary = DICTIONARY,
) -> Decoded:
    """Decode one aligned 100-bit frame (see :func:`parse_frame` for the accepted forms).

    The preamble + delimiter may differ from the sync word in at most ``sync_tolerance``
    bits; the guard bits are ignored.

    Raises:
        DecodeError: and nothing else, whatever ``frame`` is; ``reason`` says why.
    """
    value = parse_frame(frame)
    sync_errors = ((value >> (CODEWORD_BITS + GUARD_BITS)) ^ SYNC_WORD).bit_count()
    if sync_errors > sync_tolerance:
        raise DecodeError(
            RejectReason.NO_SYNC,
            f"preamble + delimiter differ from the sync word in {sync_errors} bits "
            f"(at most {sync_tolerance} tolerated)",
        )
    return decode_codeword(value >> GUARD_BITS, dictionary, sync_errors)
