"""Addressed frames: several vehicles on one ME link (docs/protocol.md, "Addressing").

The ME link is a broadcast medium: every vehicle in range receives every frame. With a fleet
the console sends **addressed frames**, and a vehicle executes only those addressed to it or
to all (address 0). The single-vehicle frame is untouched: a console or vehicle with no
address configured sends and takes exactly today's 100-bit frame.

Layout (bit 0 is sent first; ``analysis/addressing.py`` measured it against the alternatives
before it was chosen)::

    bits   0-15  preamble       1010...10 (0xAAAA), as today
    bits  16-23  delimiter      01000011 (0x43): marks an addressed frame
    bits  24-103 codeword       BCH(80, 64): message (64) then parity (16)
                   24-31  address word: the address (4 bits, 0 = all vehicles, 1-15 a
                          vehicle) then its check nibble (an [8, 4, 4] extended Hamming word)
                   32-35  pattern ID
                   36-83  fields j1..j6 (6 x 8), unused fields zero
                   84-87  CRC-4 of bits 24-83 (x^4 + x + 1, initial value 0)
                   88-103 BCH parity
    bits 104-107 guard          0000, ignored

Why the check nibble: a BCH miscorrection adds a codeword of weight 5 or more to the one sent.
With a bare 4-bit address, some of those codewords change the address and keep the CRC: a
vehicle then executes another's command (about 1e-6 of frames at a bit error rate of 1e-2).
Two address words differ in at least 4 bits, so such a codeword must have at least 4 of its
bits in the address word and keep the CRC: the lightest one in this code weighs 8, and
misaddressed acceptance falls below 1e-10 at 1e-2.

The vehicle's side is :func:`decode_addressed_codeword` (and :mod:`codec._address_sync`'s
receiver); encoding (:func:`addressed_frame_of`) is the console's. Nothing here is loaded by a
vehicle with no address.
"""

from __future__ import annotations

from codec._bch import BCHCode, make_corrector
from codec._dictionary import DICTIONARY, FIELDS_PER_FRAME, PATTERN_ID_BITS, CommandDictionary
from codec._errors import UNCORRECTABLE, DecodeError, RejectReason
from codec._frame import (
    BCH_T,
    CRC_BITS,
    CRC_POLY,
    DELIMITER_BITS,
    GUARD_BITS,
    PARITY_BITS,
    PAYLOAD_BITS,
    PREAMBLE,
    PREAMBLE_BITS,
    SYNC_BITS,
    Decoded,
    Frame,
    command_of_payload,
)
from codec._gf2 import ChunkedRemainder
from codec._record import init
from codec._scales import FIELD_BITS

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Final

    from codec._dictionary import Command

#: The address of every vehicle at once ("all vehicles").
BROADCAST_ADDRESS: Final = 0
#: Bits of an address; vehicles are 1 .. MAX_ADDRESS.
ADDRESS_BITS: Final = 4
MAX_ADDRESS: Final = (1 << ADDRESS_BITS) - 1
#: The address word: the address, then its check nibble ([8, 4, 4] extended Hamming).
ADDRESS_WORD_BITS: Final = 2 * ADDRESS_BITS
#: Chosen by the same ranking as the single-vehicle delimiter (``scripts/choose_delimiter.py``:
#: shifts of it differ from it in at least 4 known bits, like 0x7C's) and, of those, the
#: farthest from 0x7C: the two sync words differ in 6 bits aligned and in at least 4 at every
#: shift of 1..15 bits, so neither frame is taken for the other within the sync tolerance.
FLEET_DELIMITER: Final = 0x43
FLEET_SYNC_WORD: Final = (PREAMBLE << DELIMITER_BITS) | FLEET_DELIMITER
#: The BCH message: address word, payload, CRC-4 of both.
ADDRESSED_MESSAGE_BITS: Final = ADDRESS_WORD_BITS + PAYLOAD_BITS + CRC_BITS  # 64
ADDRESSED_CODE: Final = BCHCode(t=BCH_T, k=ADDRESSED_MESSAGE_BITS)
ADDRESSED_CODEWORD_BITS: Final = ADDRESSED_CODE.n  # 80
ADDRESSED_FRAME_BITS: Final = SYNC_BITS + ADDRESSED_CODEWORD_BITS + GUARD_BITS  # 108
#: Bytes of a packed addressed frame: 108 bits MSB first, then 4 zero bits.
ADDRESSED_FRAME_BYTES: Final = (ADDRESSED_FRAME_BITS + 7) // 8  # 14
ADDRESSED_FRAME_HEX_DIGITS: Final = ADDRESSED_FRAME_BITS // 4  # 27
ADDRESSED_PAD_BITS: Final = 8 * ADDRESSED_FRAME_BYTES - ADDRESSED_FRAME_BITS
#: The sections of an addressed frame in wire order (bits), as :data:`codec._frame.SECTION_BITS`.
ADDRESSED_SECTION_BITS: Final = (
    PREAMBLE_BITS,
    DELIMITER_BITS,
    ADDRESS_BITS,
    ADDRESS_BITS,
    PATTERN_ID_BITS,
    *(FIELD_BITS,) * FIELDS_PER_FRAME,
    CRC_BITS,
    PARITY_BITS,
    GUARD_BITS,
)

_CODEWORD_MASK = (1 << ADDRESSED_CODEWORD_BITS) - 1
_FRAME_MASK = (1 << ADDRESSED_FRAME_BITS) - 1
_PAYLOAD_MASK = (1 << PAYLOAD_BITS) - 1
_WORD_SHIFT = PAYLOAD_BITS + CRC_BITS
#: The message's remainder modulo the CRC polynomial: zero exactly when its CRC-4 holds (the
#: message is the covered bits shifted by 4 plus their CRC); also the CRC of ``covered << 4``.
_CRC_CHECK = ChunkedRemainder(CRC_POLY, width=ADDRESSED_MESSAGE_BITS)
#: Non-zero remainder of a received codeword -> the error pattern of weight 1-2, or None.
_CORRECT = make_corrector(ADDRESSED_CODE)
_REMAINDER = ADDRESSED_CODE.remainder
_PARITY = ADDRESSED_CODE.r


def check_address(address: int) -> int:
    """``address`` if it is one (0 = all vehicles, 1-15 a vehicle).

    Raises:
        ValueError: naming the allowed range.
    """
    if type(address) is not int or not 0 <= address <= MAX_ADDRESS:
        raise ValueError(
            f"vehicle address {address!r} is out of range: allowed {BROADCAST_ADDRESS} (all "
            f"vehicles) or 1 to {MAX_ADDRESS}"
        )
    return address


def check_vehicle_address(address: int) -> int:
    """``address`` if a vehicle may have it (1-15: 0 is every vehicle's, never one's own).

    Raises:
        ValueError: naming the allowed range.
    """
    if type(address) is not int or not 1 <= address <= MAX_ADDRESS:
        raise ValueError(
            f"vehicle address {address!r} is out of range: a vehicle's own address is 1 to "
            f"{MAX_ADDRESS} ({BROADCAST_ADDRESS} addresses all vehicles)"
        )
    return address


def address_word(address: int) -> int:
    """The 8-bit address word: the address, then its check nibble, the address with its two
    halves swapped, inverted when the address has an odd number of ones. Any two words differ
    in at least 4 bits (the [8, 4, 4] extended Hamming code). Of the 24 such check nibbles,
    the swap is one of the 8 for which no BCH codeword lighter than 8 bits turns one address
    word into another and keeps the CRC (``analysis/addressing.py`` counts them)."""
    swapped = ((address & 0b11) << 2) | (address >> 2)
    check = swapped ^ (MAX_ADDRESS if address.bit_count() & 1 else 0)
    return (address << ADDRESS_BITS) | check


def address_of_word(word: int) -> int | None:
    """The address an address word carries, or ``None`` if it is no address word."""
    address = word >> ADDRESS_BITS
    return address if address_word(address) == word else None


def decode_addressed_message(codeword: int) -> tuple[int, int]:
    """Error-correct an 80-bit addressed codeword (t = 2, bounded distance, as the 72-bit one).

    Returns:
        ``(message, corrected)``; ``corrected`` is ``UNCORRECTABLE`` when the word is beyond
        the decoder's reach (the message is then the bits as received).
    """
    rem = _REMAINDER(codeword)
    if not rem:
        return codeword >> _PARITY, 0
    error = _CORRECT(rem)
    if error is None:
        return codeword >> _PARITY, UNCORRECTABLE
    return (codeword ^ error) >> _PARITY, error.bit_count()


class MisaddressedError(DecodeError):
    """A frame this vehicle must not execute because it is not addressed to it
    (``reason`` ``other_vehicle``).

    Attributes:
        address: the address the frame carries, or ``None`` (an unaddressed frame, or an
            address word that is no address).
    """

    def __init__(self, message: str, address: int | None) -> None:
        super().__init__(RejectReason.OTHER_VEHICLE, message)
        self.address = address


class AddressedDecoded(Decoded):
    """An accepted addressed frame: :class:`codec.Decoded` and the address it carried
    (0: all vehicles)."""

    __slots__ = ("address",)
    address: int

    def __init__(self, command: Command, corrected: int, sync_errors: int, address: int) -> None:
        super().__init__(command, corrected, sync_errors)
        init(self, "address", address)


def decode_addressed_codeword(
    codeword: int,
    vehicle: int | None,
    dictionary: CommandDictionary = DICTIONARY,
    sync_errors: int = 0,
) -> AddressedDecoded:
    """Error-correct and check an 80-bit addressed codeword, as vehicle ``vehicle`` would
    (``None``: as the console reads it, any address accepted).

    Checks in order: BCH, CRC-4, the address word (an address, and this vehicle's or 0), then
    the dictionary's (:func:`codec._frame.command_of_payload`).

    Raises:
        DecodeError: uncorrectable, CRC mismatch, the dictionary's; :class:`MisaddressedError`
            (``other_vehicle``) for a frame not addressed to ``vehicle``.
    """
    message, corrected = decode_addressed_message(codeword & _CODEWORD_MASK)
    if corrected == UNCORRECTABLE:
        raise DecodeError(
            RejectReason.UNCORRECTABLE,
            f"more than {BCH_T} bit errors in the codeword: uncorrectable",
        )
    if _CRC_CHECK(message):
        raise DecodeError(
            RejectReason.CRC_MISMATCH,
            "CRC-4 mismatch after error correction: more errors than the code can correct",
        )
    word = message >> _WORD_SHIFT
    address = address_of_word(word)
    if address is None:
        raise MisaddressedError(
            f"address word {word:08b} is no address (a miscorrection): not executed", None
        )
    if vehicle is not None and address not in (vehicle, BROADCAST_ADDRESS):
        raise MisaddressedError(
            f"addressed to vehicle {address}, not to this vehicle ({vehicle})", address
        )
    command = command_of_payload((message >> CRC_BITS) & _PAYLOAD_MASK, dictionary)
    return AddressedDecoded(command, corrected, sync_errors, address)


class AddressedFrame(Frame):
    """A 108-bit addressed frame. ``value``'s most significant bit is the first on the wire."""

    __slots__ = ()

    def __init__(self, value: int) -> None:
        if not 0 <= value <= _FRAME_MASK:
            raise ValueError(f"an addressed frame holds {ADDRESSED_FRAME_BITS} bits")
        init(self, "value", value)

    @property
    def bits(self) -> str:
        """The 108 bits as '0'/'1' characters, first bit first."""
        return format(self.value, f"0{ADDRESSED_FRAME_BITS}b")

    @property
    def hex(self) -> str:
        """The 108 bits as 27 hex digits."""
        return format(self.value, f"0{ADDRESSED_FRAME_HEX_DIGITS}x")

    @property
    def codeword(self) -> int:
        return (self.value >> GUARD_BITS) & _CODEWORD_MASK

    @property
    def address(self) -> int | None:
        """The address its address word carries as sent (``None``: not an address word)."""
        return address_of_word(self.codeword >> (ADDRESSED_CODEWORD_BITS - ADDRESS_WORD_BITS))

    def to_bytes(self) -> bytes:
        """14 bytes, MSB first, the last 4 bits zero."""
        return (self.value << ADDRESSED_PAD_BITS).to_bytes(ADDRESSED_FRAME_BYTES, "big")

    def grouped(self, pattern: object = None) -> str:
        """The bits with a space between sections (:data:`ADDRESSED_SECTION_BITS`)."""
        bits = self.bits
        parts = []
        start = 0
        for width in ADDRESSED_SECTION_BITS:
            parts.append(bits[start : start + width])
            start += width
        return " ".join(parts)


# --- the console's side: encoding ------------------------------------------------------------


def addressed_message_of(payload: int, address: int) -> int:
    """The 64-bit BCH message of a 52-bit payload to ``address``: address word, payload,
    CRC-4 of both."""
    covered = (address_word(check_address(address)) << PAYLOAD_BITS) | payload
    return (covered << CRC_BITS) | _CRC_CHECK(covered << CRC_BITS)


def addressed_frame_of(payload: int, address: int) -> AddressedFrame:
    """The addressed frame carrying a 52-bit payload (:func:`codec.payload_of`) to
    ``address`` (0: all vehicles).

    Raises:
        ValueError: ``address`` out of range (:func:`check_address`).
    """
    codeword = ADDRESSED_CODE.encode(addressed_message_of(payload, address))
    return AddressedFrame(
        (FLEET_SYNC_WORD << (ADDRESSED_CODEWORD_BITS + GUARD_BITS)) | (codeword << GUARD_BITS)
    )
