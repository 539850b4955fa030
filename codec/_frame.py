"""The 100-bit NemeSys frame: layout, and the onboard decode of one codeword.

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

Encoding (:mod:`codec._wire`) and parsing the accepted frame forms for the one-frame
:func:`codec.decode_frame` (:mod:`codec._parse`) are the console's: the vehicle decodes
through :class:`codec.FrameReceiver` and loads neither (``nemesys bench reconfig`` measures
its memory).
"""

from __future__ import annotations

from codec._bch import BCHCode, TableDecoder
from codec._dictionary import (
    DICTIONARY,
    FIELDS_PER_FRAME,
    PATTERN_ID_BITS,
    Command,
    CommandDictionary,
    Pattern,
)
from codec._errors import UNCORRECTABLE, DecodeError, RejectReason
from codec._gf2 import ChunkedRemainder, linear_table, poly_mod
from codec._record import Record, init
from codec._scales import FIELD_BITS

TYPE_CHECKING = False
if TYPE_CHECKING:
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


def _check_tables() -> tuple[tuple[int, ...], ...]:
    """Byte tables of the codeword's seven message bytes giving, in one XOR, the BCH remainder
    (bits 0-15, the code's remainder tables) and the message's remainder modulo the CRC
    polynomial (bits 16-19: zero exactly when the CRC-4 holds, since the message is the
    payload shifted by 4 plus its CRC). As tuples: indexing one is about twice as fast as the
    code's packed tables, for some 60 KiB, paid once: the table decoder uses them (it keeps
    bits 0-15) and so does the receiver's straight line (:mod:`codec._fastpath`)."""
    message_bytes = MESSAGE_BITS // 8
    tables = CODE.remainder_tables
    combined = []
    for j in range(message_bytes):
        shift = 8 * (message_bytes - 1 - j)  # message bit of the byte's lowest bit
        units = [
            tables[j][1 << i] | poly_mod(1 << (shift + i), CRC_POLY) << CODE.r for i in range(8)
        ]
        combined.append(tuple(linear_table(units, CODE.r + CRC_BITS)))
    return tuple(combined)


#: The fast decoder of :data:`CODE` (syndrome table), shared by the scalar and batch paths;
#: its message tables carry the CRC-4 check too (:func:`_check_tables`).
FAST_DECODER: Final = TableDecoder(CODE, _check_tables())
#: Zero bits after the frame in its 13 bytes.
PAD_BITS: Final = FRAME_BYTES * 8 - FRAME_BITS
#: The widths of the frame's sections in wire order (bits): preamble, delimiter, pattern ID, the
#: six fields, CRC, parity, guard. :meth:`Frame.grouped` spaces them; :func:`codec.sections`
#: (the console's) names them.
SECTION_BITS: Final = (
    PREAMBLE_BITS,
    DELIMITER_BITS,
    PATTERN_ID_BITS,
    *(FIELD_BITS,) * FIELDS_PER_FRAME,
    CRC_BITS,
    PARITY_BITS,
    GUARD_BITS,
)


def crc4(payload: int) -> int:
    """CRC-4 of the 52-bit payload: ``(payload(x) * x^4) mod (x^4 + x + 1)``."""
    return CRC4_REMAINDER(payload)


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
        return (self.value << PAD_BITS).to_bytes(FRAME_BYTES, "big")

    def grouped(self, pattern: Pattern | None = None) -> str:
        """The bits with a space between sections (:data:`SECTION_BITS`).

        ``pattern`` names the field sections in :func:`codec.sections`; it moves no boundary,
        so the grouping is the same for every pattern.
        """
        bits = self.bits
        parts = []
        start = 0
        for width in SECTION_BITS:
            parts.append(bits[start : start + width])
            start += width
        return " ".join(parts)

    def __str__(self) -> str:
        return self.bits


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
    return command_of_payload(payload, dictionary)


def command_of_payload(payload: int, dictionary: CommandDictionary = DICTIONARY) -> Command:
    """The dictionary's checks of a 52-bit payload (pattern ID, then the fields j1..j6), and
    its command: what every frame, addressed or not, carries after its CRC.

    Raises:
        DecodeError: unknown pattern ID, invalid field code, non-zero unused field (in that
            order).
    """
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
