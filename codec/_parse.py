"""Decoding one aligned frame given in any accepted form: :func:`parse_frame` and
:func:`decode_frame` (and :func:`decode_addressed_frame`, a fleet's 108-bit frame), for the
console, the CLI and the benches.

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

TYPE_CHECKING = False
if TYPE_CHECKING:
    from codec._address import AddressedDecoded


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


def _addressed_value(frame: object) -> int | None:
    """The value of a 108-bit addressed frame given in a form of its own length (the forms of
    :func:`parse_frame`, 108 bits, 27 hex digits or 14 bytes; an int from 2^100 up), else
    ``None`` (then it is read as a 100-bit frame)."""
    from codec._address import (
        ADDRESSED_FRAME_BITS,
        ADDRESSED_FRAME_BYTES,
        ADDRESSED_FRAME_HEX_DIGITS,
        ADDRESSED_PAD_BITS,
        AddressedFrame,
    )

    if isinstance(frame, AddressedFrame):
        return frame.value
    if isinstance(frame, str):
        compact = frame.strip().replace(" ", "").replace("_", "")
        if compact[:2].lower() == "0x":
            compact = compact[2:]
        if len(compact) == ADDRESSED_FRAME_BITS and not compact.strip("01"):
            return int(compact, 2)
        if len(compact) == ADDRESSED_FRAME_HEX_DIGITS and not compact.strip(_HEX_DIGITS):
            return int(compact, 16)
        return None
    if isinstance(frame, bytes | bytearray | memoryview) and len(frame) == ADDRESSED_FRAME_BYTES:
        value = int.from_bytes(bytes(frame), "big")
        if value & ((1 << ADDRESSED_PAD_BITS) - 1):
            raise _malformed(
                f"the last {ADDRESSED_PAD_BITS} bits of byte {ADDRESSED_FRAME_BYTES} must be zero"
            )
        return value >> ADDRESSED_PAD_BITS
    if isinstance(frame, int) and not isinstance(frame, bool) and frame > FRAME_MASK:
        if frame >> ADDRESSED_FRAME_BITS:
            raise _malformed(f"an int frame must be 0 <= value < 2^{ADDRESSED_FRAME_BITS}")
        return frame
    if isinstance(frame, list | tuple) and len(frame) == ADDRESSED_FRAME_BITS:
        value = 0
        for bit in frame:
            if type(bit) is not int or bit not in (0, 1):
                raise _malformed(f"bits must be 0 or 1, got {bit!r}")
            value = (value << 1) | bit
        return value
    return None


def _decode_addressed(
    value: int, sync_tolerance: int, dictionary: CommandDictionary, vehicle: int | None
) -> AddressedDecoded:
    from codec._address import (
        ADDRESSED_CODEWORD_BITS,
        FLEET_SYNC_WORD,
        decode_addressed_codeword,
    )

    sync_errors = ((value >> (ADDRESSED_CODEWORD_BITS + GUARD_BITS)) ^ FLEET_SYNC_WORD).bit_count()
    if sync_errors > sync_tolerance:
        raise DecodeError(
            RejectReason.NO_SYNC,
            f"preamble + delimiter differ from the addressed frame's sync word in {sync_errors} "
            f"bits (at most {sync_tolerance} tolerated)",
        )
    return decode_addressed_codeword(value >> GUARD_BITS, vehicle, dictionary, sync_errors)


def decode_frame(
    frame: object,
    *,
    sync_tolerance: int = DEFAULT_SYNC_TOLERANCE,
    dictionary: CommandDictionary = DICTIONARY,
    vehicle: int | None = None,
) -> Decoded:
    """Decode one aligned 100-bit frame (see :func:`parse_frame` for the accepted forms).

    The preamble + delimiter may differ from the sync word in at most ``sync_tolerance``
    bits; the guard bits are ignored.

    ``vehicle`` (1-15) decides as that vehicle of a fleet does (docs/protocol.md,
    "Addressing"): it also takes a 108-bit addressed frame (the forms of
    :func:`decode_addressed_frame`), rejects one addressed to another vehicle, and of
    unaddressed frames takes only surface (``other_vehicle`` otherwise). Without it, exactly
    today's single-vehicle decode.

    Raises:
        DecodeError: and nothing else, whatever ``frame`` is; ``reason`` says why.
        ValueError: ``vehicle`` is no vehicle's address (1-15).
    """
    if vehicle is None:
        return _decode_single(parse_frame(frame), sync_tolerance, dictionary)
    from codec._address import MisaddressedError, check_vehicle_address

    check_vehicle_address(vehicle)
    addressed = _addressed_value(frame)
    if addressed is not None:
        return _decode_addressed(addressed, sync_tolerance, dictionary, vehicle)
    decoded = _decode_single(parse_frame(frame), sync_tolerance, dictionary)
    if decoded.command.pattern.name != "surface":
        raise MisaddressedError(
            f"an unaddressed frame ({decoded.command.pattern.name}): vehicle {vehicle} "
            "takes frames addressed to it or to all, and unaddressed only surface",
            None,
        )
    return decoded


def decode_addressed_frame(
    frame: object,
    *,
    sync_tolerance: int = DEFAULT_SYNC_TOLERANCE,
    dictionary: CommandDictionary = DICTIONARY,
    vehicle: int | None = None,
) -> AddressedDecoded:
    """Decode one aligned 108-bit addressed frame: an :class:`codec.AddressedFrame`, 108
    binary or 27 hex digits (spaces, ``_`` and ``0x`` as for :func:`parse_frame`), 14 bytes
    (the last 4 bits zero), an int from 2^100 below 2^108, or 108 ints 0/1.

    ``vehicle``: ``None`` reads it as the console does (any address is accepted, and the
    result says which); 1-15 as that vehicle (another's is rejected ``other_vehicle``).

    Raises:
        DecodeError: and nothing else, whatever ``frame`` is; ``reason`` says why.
        ValueError: ``vehicle`` is no vehicle's address (1-15).
    """
    from codec._address import (
        ADDRESSED_FRAME_BITS,
        ADDRESSED_FRAME_BYTES,
        ADDRESSED_FRAME_HEX_DIGITS,
        check_vehicle_address,
    )

    if vehicle is not None:
        check_vehicle_address(vehicle)
    value = _addressed_value(frame)
    if value is None:
        raise _malformed(
            f"an addressed frame is {ADDRESSED_FRAME_BITS} binary digits, "
            f"{ADDRESSED_FRAME_HEX_DIGITS} hex digits or {ADDRESSED_FRAME_BYTES} bytes"
        )
    return _decode_addressed(value, sync_tolerance, dictionary, vehicle)


def _decode_single(value: int, sync_tolerance: int, dictionary: CommandDictionary) -> Decoded:
    sync_errors = ((value >> (CODEWORD_BITS + GUARD_BITS)) ^ SYNC_WORD).bit_count()
    if sync_errors > sync_tolerance:
        raise DecodeError(
            RejectReason.NO_SYNC,
            f"preamble + delimiter differ from the sync word in {sync_errors} bits "
            f"(at most {sync_tolerance} tolerated)",
        )
    return decode_codeword(value >> GUARD_BITS, dictionary, sync_errors)
