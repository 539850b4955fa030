"""The 100-bit NemeSys frame: layout, encode and decode of one aligned frame.

Layout (bit 0 is sent first)::

    bits  0-15  preamble       1010...10 (0xAAAA), receiver bit sync
    bits 16-23  delimiter      01111100 (0x7C), frame sync (see docs/protocol.md)
    bits 24-95  codeword       BCH(72, 56): message (56) then parity (16)
                  24-27  pattern ID (4)
                  28-75  fields j1..j6 (6 x 8), unused fields zero
                  76-79  CRC-4 of bits 24-75 (x^4 + x + 1, initial value 0)
                  80-95  BCH parity
    bits 96-99  guard          0000, ignored by the receiver

Every multi-bit value is MSB first. In code, a frame is a 100-bit ``int`` whose most
significant bit is bit 0 of the frame.
"""

from __future__ import annotations

from collections.abc import Sequence

from codec._bch import UNCORRECTABLE, BCHCode, TableDecoder
from codec._dictionary import (
    DICTIONARY,
    FIELDS_PER_FRAME,
    PATTERN_ID_BITS,
    Command,
    CommandDictionary,
    Pattern,
    make_command,
)
from codec._errors import DecodeError, RejectReason
from codec._fields import FIELD_BITS, ParamValue, Snap
from codec._gf2 import ChunkedRemainder
from codec._record import Record, init

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Mapping
    from typing import Final

PREAMBLE: Final = 0xAAAA
PREAMBLE_BITS: Final = 16
#: Chosen by ``scripts/choose_delimiter.py``: every shift of preamble + delimiter by 1 to 15
#: bits differs from it in at least 4 known bits.
DELIMITER: Final = 0x7C
DELIMITER_BITS: Final = 8
SYNC_WORD: Final = (PREAMBLE << DELIMITER_BITS) | DELIMITER
SYNC_BITS: Final = PREAMBLE_BITS + DELIMITER_BITS
PAYLOAD_BITS: Final = PATTERN_ID_BITS + FIELDS_PER_FRAME * FIELD_BITS  # 52
CRC_BITS: Final = 4
CRC_POLY: Final = 0b10011  # x^4 + x + 1
MESSAGE_BITS: Final = PAYLOAD_BITS + CRC_BITS  # 56
BCH_T: Final = 2
CODE: Final = BCHCode(t=BCH_T, k=MESSAGE_BITS)
CODEWORD_BITS: Final = CODE.n  # 72
PARITY_BITS: Final = CODE.r  # 16
GUARD_BITS: Final = 4
FRAME_BITS: Final = SYNC_BITS + CODEWORD_BITS + GUARD_BITS  # 100
#: Bytes of a packed frame: 100 bits MSB first, then 4 zero bits.
FRAME_BYTES: Final = (FRAME_BITS + 7) // 8  # 13
FRAME_HEX_DIGITS: Final = FRAME_BITS // 4  # 25
#: Bits of preamble + delimiter that may be wrong before a frame is refused.
DEFAULT_SYNC_TOLERANCE: Final = 2
#: The ME link's bit rate (paper, BlueME).
DEFAULT_BITRATE_BPS: Final = 36_000

CODEWORD_MASK: Final = (1 << CODEWORD_BITS) - 1
FRAME_MASK: Final = (1 << FRAME_BITS) - 1

#: CRC-4 of a 52-bit payload, by byte tables (shared with the batch path).
CRC4_REMAINDER: Final = ChunkedRemainder(CRC_POLY, width=PAYLOAD_BITS, shift=CRC_BITS)
#: The fast decoder of :data:`CODE` (syndrome table), shared by the scalar and batch paths.
FAST_DECODER: Final = TableDecoder(CODE)
_PAD_BITS = FRAME_BYTES * 8 - FRAME_BITS


def crc4(payload: int) -> int:
    """CRC-4 of the 52-bit payload: ``(payload(x) * x^4) mod (x^4 + x + 1)``."""
    return CRC4_REMAINDER(payload)


class Section(Record):
    """A named bit range of the frame, for display: ``bits[start:start + length]``."""

    __slots__ = ("length", "name", "start")
    name: str
    start: int
    length: int

    def __init__(self, name: str, start: int, length: int) -> None:
        init(self, "name", name)
        init(self, "start", start)
        init(self, "length", length)


def sections(pattern: Pattern | None = None) -> tuple[Section, ...]:
    """The frame's sections in order; field sections take the pattern's field names."""
    out = [
        Section("preamble", 0, PREAMBLE_BITS),
        Section("delimiter", PREAMBLE_BITS, DELIMITER_BITS),
        Section("pattern", SYNC_BITS, PATTERN_ID_BITS),
    ]
    start = SYNC_BITS + PATTERN_ID_BITS
    fields = pattern.fields if pattern is not None else ()
    for j in range(FIELDS_PER_FRAME):
        name = fields[j].name if j < len(fields) else f"j{j + 1} (unused)"
        out.append(Section(name, start, FIELD_BITS))
        start += FIELD_BITS
    out += [
        Section("crc", start, CRC_BITS),
        Section("parity", start + CRC_BITS, PARITY_BITS),
        Section("guard", SYNC_BITS + CODEWORD_BITS, GUARD_BITS),
    ]
    return tuple(out)


class Frame(Record):
    """A 100-bit frame. ``value``'s most significant bit is the first bit on the wire."""

    __slots__ = ("value",)
    value: int

    def __init__(self, value: int) -> None:
        if not 0 <= value <= FRAME_MASK:
            raise ValueError(f"a frame holds {FRAME_BITS} bits")
        init(self, "value", value)

    @property
    def bits(self) -> str:
        """The 100 bits as '0'/'1' characters, first bit first."""
        return format(self.value, f"0{FRAME_BITS}b")

    @property
    def hex(self) -> str:
        """The 100 bits as 25 hex digits."""
        return format(self.value, f"0{FRAME_HEX_DIGITS}x")

    @property
    def codeword(self) -> int:
        return (self.value >> GUARD_BITS) & CODEWORD_MASK

    def to_bytes(self) -> bytes:
        """13 bytes, MSB first, the last 4 bits zero (the rosbridge and serial wire form)."""
        return (self.value << _PAD_BITS).to_bytes(FRAME_BYTES, "big")

    def grouped(self, pattern: Pattern | None = None) -> str:
        """The bits with a space between sections."""
        bits = self.bits
        return " ".join(bits[s.start : s.start + s.length] for s in sections(pattern))

    def __str__(self) -> str:
        return self.bits


def airtime_s(bitrate_bps: float = DEFAULT_BITRATE_BPS, bits: int = FRAME_BITS) -> float:
    """Time on the link for ``bits`` at ``bitrate_bps`` (s)."""
    if not bitrate_bps > 0:
        raise ValueError(f"bit rate must be positive, got {bitrate_bps} b/s")
    return bits / bitrate_bps


class Encoded(Record):
    """An encoded command: what was asked, what is sent, and the frame.

    ``snaps`` has one entry per field when the command was built from requested values, and
    is empty when a ready :class:`Command` was encoded (nothing was requested or snapped).
    """

    __slots__ = ("command", "frame", "snaps")
    command: Command
    snaps: tuple[Snap, ...]
    frame: Frame

    def __init__(self, command: Command, snaps: tuple[Snap, ...], frame: Frame) -> None:
        init(self, "command", command)
        init(self, "snaps", snaps)
        init(self, "frame", frame)


class Decoded(Record):
    """An accepted frame.

    Attributes:
        command: the command to execute.
        corrected: codeword bits the BCH decoder corrected (0..2).
        sync_errors: preamble + delimiter bits that differed from the sync word.
    """

    __slots__ = ("command", "corrected", "sync_errors")
    command: Command
    corrected: int
    sync_errors: int

    def __init__(self, command: Command, corrected: int, sync_errors: int = 0) -> None:
        init(self, "command", command)
        init(self, "corrected", corrected)
        init(self, "sync_errors", sync_errors)


def payload_of(command: Command) -> int:
    """The 52-bit payload: pattern ID then six 8-bit fields, unused fields zero."""
    payload = command.pattern.id
    codes = command.codes
    for j in range(FIELDS_PER_FRAME):
        payload = (payload << FIELD_BITS) | (codes[j] if j < len(codes) else 0)
    return payload


def message_of(command: Command) -> int:
    """The 56-bit BCH message: payload then its CRC-4."""
    payload = payload_of(command)
    return (payload << CRC_BITS) | CRC4_REMAINDER(payload)


def frame_of(command: Command) -> Frame:
    """The frame that carries ``command``."""
    codeword = CODE.encode(message_of(command))
    return Frame((SYNC_WORD << (CODEWORD_BITS + GUARD_BITS)) | (codeword << GUARD_BITS))


def encode_frame(
    pattern: str | int | Pattern | Command,
    params: Mapping[str, ParamValue] | None = None,
    /,
    dictionary: CommandDictionary = DICTIONARY,
    **kwargs: ParamValue,
) -> Encoded:
    """Encode a command: ``encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw")``.

    ``pattern`` is a name or ID (then the parameters come as a mapping and/or keywords), or a
    ready :class:`Command` (then no parameters).

    Raises:
        EncodeError: unknown pattern, missing/unknown parameter, value out of range.
    """
    if isinstance(pattern, Command):
        if params or kwargs:
            raise TypeError("a Command already holds its parameters")
        command = pattern
        snaps: tuple[Snap, ...] = ()
    else:
        command, snaps = make_command(pattern, {**(params or {}), **kwargs}, dictionary)
    return Encoded(command, snaps, frame_of(command))


def command_of_message(message: int, dictionary: CommandDictionary = DICTIONARY) -> Command:
    """Check a corrected 56-bit message and turn it into a command.

    Raises:
        DecodeError: CRC mismatch, unknown pattern ID, invalid field code, non-zero unused
            field (in that order).
    """
    payload = message >> CRC_BITS
    if CRC4_REMAINDER(payload) != message & 0xF:
        raise DecodeError(
            RejectReason.CRC_MISMATCH,
            "CRC-4 mismatch after error correction: more errors than the code can correct",
        )
    pattern_id = payload >> (FIELDS_PER_FRAME * FIELD_BITS)
    pattern = dictionary.by_id(pattern_id)
    if pattern is None:
        raise DecodeError(
            RejectReason.UNKNOWN_PATTERN, f"pattern ID {pattern_id} is not in the dictionary"
        )
    fields = pattern.fields
    codes = []
    for j in range(FIELDS_PER_FRAME):
        code = (payload >> ((FIELDS_PER_FRAME - 1 - j) * FIELD_BITS)) & 0xFF
        if j < len(fields):
            f = fields[j]
            if not f.scale.is_valid_code(code):
                raise DecodeError(
                    RejectReason.FIELD_OUT_OF_RANGE,
                    f"{pattern.name}: code {code} of {f.name} (j{j + 1}) is not defined",
                    field=f.name,
                )
            codes.append(code)
        elif code:
            raise DecodeError(
                RejectReason.UNUSED_FIELD_SET,
                f"{pattern.name}: unused field j{j + 1} holds {code}, must be 0",
                field=f"j{j + 1}",
            )
    return Command(pattern, tuple(codes))


def decode_codeword(
    codeword: int, dictionary: CommandDictionary = DICTIONARY, sync_errors: int = 0
) -> Decoded:
    """Error-correct a 72-bit codeword and check it (fast table decoder).

    ``sync_errors`` is passed through to the result (the caller measured it).

    Raises:
        DecodeError: uncorrectable, or any check of :func:`command_of_message`.
    """
    message, corrected = FAST_DECODER.decode(codeword & CODEWORD_MASK)
    if corrected == UNCORRECTABLE:
        raise DecodeError(
            RejectReason.UNCORRECTABLE,
            f"more than {BCH_T} bit errors in the codeword: uncorrectable",
        )
    return Decoded(command_of_message(message, dictionary), corrected, sync_errors)


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
        if value & ((1 << _PAD_BITS) - 1):
            raise _malformed(f"the last {_PAD_BITS} bits of byte {FRAME_BYTES} must be zero")
        return value >> _PAD_BITS
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
