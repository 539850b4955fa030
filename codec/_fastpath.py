"""The onboard decode's straight line: a frame that starts at a byte boundary.

A modem delivers a frame as its 13 bytes, so the receiver's common case is a buffer whose
first three bytes are the preamble and delimiter. :func:`straight_line` decodes that case
without the bit-level search: the sync distance from three bytes, the BCH syndrome from the
nine codeword bytes (the code's byte tables), a closed-form correction when it is not zero,
the CRC-4 check in the same lookups (:func:`_check_tables`), and the pattern and field checks
from tables made once per dictionary (all six fields in one mask test, see
:func:`_field_classes`).

It only ever accepts: whenever a check fails (sync beyond the tolerance, uncorrectable,
CRC, unknown pattern, a field) it returns ``None`` and :class:`codec.FrameReceiver` runs its
bit-level path on the same bytes, which reports the rejection with its reason and field and
goes on searching one bit later. An accepted frame is exactly what the bit-level path
accepts: the tables are built from the same checks (``is_valid_code``), and a sync distance
``d`` with ``2 d <= SHIFT_DISTANCE`` cannot be beaten by any of the bit-level path's
look-ahead offsets (see :data:`SHIFT_DISTANCE`), so that path would decode this very offset.
"""

from __future__ import annotations

from codec._dictionary import FIELDS_PER_FRAME, PATTERN_ID_BITS, Command, CommandDictionary, Pattern
from codec._frame import (
    CODE,
    CRC_BITS,
    CRC_POLY,
    FAST_DECODER,
    MESSAGE_BITS,
    SYNC_BITS,
    SYNC_WORD,
    Decoded,
)
from codec._gf2 import linear_table, poly_mod
from codec._record import slot_setters

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    #: ``(received bytes, sync tolerance) -> Decoded``, or ``None`` for "not on the straight
    #: line" (the bit-level path then decides).
    StraightLine = Callable[[bytes, int], Decoded | None]

#: Offsets after a sync candidate that the bit-level path also compares (its look-ahead).
LOOKAHEAD = 8
#: Header + codeword bytes: what the straight line reads.
ALIGNED_BYTES = 12
#: The codeword's message bytes (pattern ID, fields, CRC): bytes 3-9 of the frame.
MESSAGE_BYTES = MESSAGE_BITS // 8


def shift_distance(lookahead: int = LOOKAHEAD) -> int:
    """Fewest bits in which the sync word, shifted by 1..``lookahead`` bits, differs from
    itself where the two overlap (the delimiter makes this 4).

    A window holding the sync word with ``d`` wrong bits then differs from the sync word, at
    any of those shifts, in at least ``SHIFT_DISTANCE - d`` bits: if ``2 d <= SHIFT_DISTANCE``
    no look-ahead offset is strictly closer, and the bit-level path keeps this one.
    """
    mask = (1 << SYNC_BITS) - 1
    return min(
        (((SYNC_WORD << s) ^ SYNC_WORD) & mask & ~((1 << s) - 1)).bit_count()
        for s in range(1, lookahead + 1)
    )


SHIFT_DISTANCE = shift_distance()


def straight_line(dictionary: CommandDictionary) -> StraightLine:
    """The straight-line decoder for ``dictionary`` (built once, then cached on it)."""
    line = dictionary.straight_line
    if line is None:
        line = dictionary.straight_line = _build(dictionary)
    return line


#: Per pattern ID: the pattern, its number of fields and the class bits its codes need.
Entry = tuple[Pattern, int, int]


def _field_classes(dictionary: CommandDictionary) -> tuple[bytes, list[Entry | None]] | None:
    """The field checks of every pattern as one mask test.

    Each distinct set of valid codes (one per scale, from the reference check
    ``is_valid_code``, and ``{0}`` for an unused field) gets a bit; ``classes[c]`` holds the
    bits of the sets that contain code ``c``. Translating the payload's seven bytes through
    ``classes`` then gives, in byte ``j``, the sets field ``j`` passes, and a pattern's fields
    are all valid exactly when that int has every bit of the pattern's mask (its field ``j``'s
    set in byte ``j``). ``None`` if the dictionary has more than 8 distinct sets (the
    straight line then declines every frame and the bit-level path decodes).
    """
    zero = bytes([1] + [0] * 255)  # an unused field must be zero
    bits: dict[bytes, int] = {zero: 1}
    entries: list[Entry | None] = [None] * (1 << PATTERN_ID_BITS)
    for pattern in dictionary.values():
        mask = 0
        for j in range(FIELDS_PER_FRAME):
            valid = (
                bytes(map(pattern.fields[j].scale.is_valid_code, range(256)))
                if j < len(pattern.fields)
                else zero
            )
            bit = bits.setdefault(valid, 1 << len(bits))
            mask |= bit << (8 * (FIELDS_PER_FRAME - 1 - j))
        entries[pattern.id] = (pattern, len(pattern.fields), mask)
    if len(bits) > 8:
        return None
    classes = bytes(sum(bit for valid, bit in bits.items() if valid[code]) for code in range(256))
    return classes, entries


def _check_tables() -> tuple[Sequence[int], ...]:
    """Byte tables of the codeword's seven message bytes giving, in one XOR, the BCH syndrome
    (bits 0-15, the code's remainder tables) and the message's remainder modulo the CRC
    polynomial (bits 16-19: zero exactly when the CRC-4 holds, since the message is the
    payload shifted by 4 plus its CRC). The two parity bytes need no table: their remainder is
    themselves (degree < 16), checked here."""
    tables = CODE.remainder_tables
    if list(tables[7]) != [b << 8 for b in range(256)] or list(tables[8]) != list(range(256)):
        raise ValueError("the parity bytes' remainder tables are not the identity")
    combined = []
    for j in range(MESSAGE_BYTES):
        shift = 8 * (MESSAGE_BYTES - 1 - j)  # message bit of the byte's lowest bit
        units = [
            tables[j][1 << i] | poly_mod(1 << (shift + i), CRC_POLY) << CODE.r for i in range(8)
        ]
        combined.append(linear_table(units, CODE.r + CRC_BITS))
    return tuple(combined)


def _build(dictionary: CommandDictionary) -> StraightLine:
    if SYNC_BITS != 24 or CODE.n != 72 or CODE.r != 16 or FIELDS_PER_FRAME != 6 or CRC_BITS != 4:
        raise ValueError("the straight line is written for the 24 + 72-bit frame layout")
    t0, t1, t2, t3, t4, t5, t6 = _check_tables()
    parity = CODE.r
    # crc_of_bit[k]: the CRC check of codeword bit k - 1 (zero for a parity bit).
    crc_of_bit = [0] + [
        poly_mod(1 << (k - parity), CRC_POLY) if k >= parity else 0 for k in range(CODE.n)
    ]
    correct = FAST_DECODER.correct
    field_classes = _field_classes(dictionary)
    if field_classes is None:
        return _decline
    classes, entries = field_classes
    sync_bytes = SYNC_WORD.to_bytes(3, "big")
    half_shift = SHIFT_DISTANCE // 2
    from_bytes = int.from_bytes
    new = object.__new__
    set_pattern, set_codes = slot_setters(Command, "pattern", "codes")
    set_command, set_corrected, set_sync_errors = slot_setters(
        Decoded, "command", "corrected", "sync_errors"
    )

    def decode(raw: bytes, tolerance: int) -> Decoded | None:
        if raw.startswith(sync_bytes):
            sync = 0
        else:
            sync = (((raw[0] << 16) | (raw[1] << 8) | raw[2]) ^ SYNC_WORD).bit_count()
            if sync > tolerance or sync > half_shift:
                return None
        # Bits 0-15: the BCH syndrome; bits 16-19: the received message's CRC check.
        check = (
            t0[raw[3]] ^ t1[raw[4]] ^ t2[raw[5]] ^ t3[raw[6]] ^ t4[raw[7]]
            ^ t5[raw[8]] ^ t6[raw[9]] ^ (raw[10] << 8) ^ raw[11]
        )  # fmt: skip
        if check:
            syn = check & 0xFFFF
            error = correct(syn) if syn else None  # no BCH error: then the CRC failed
            if error is None:
                return None
            # The CRC check is linear too: the received message's, plus that of the error's
            # (at most two) message bits, by bit position (bit_length: position + 1).
            low = error & -error
            high = error ^ low
            crc = check >> 16 ^ crc_of_bit[low.bit_length()]
            if high:
                crc ^= crc_of_bit[high.bit_length()]
            if crc:
                return None
            p = ((from_bytes(raw[3:12], "big") ^ error) >> 20).to_bytes(7, "big")
            corrected = 2 if high else 1
        else:  # a codeword whose CRC holds
            p = (from_bytes(raw[3:10], "big") >> 4).to_bytes(7, "big")
            corrected = 0
        entry = entries[p[0]]
        if entry is None:
            return None
        pattern, n_fields, mask = entry
        if from_bytes(p.translate(classes), "big") & mask != mask:
            return None  # a field check fails
        # The records, filled through their slots: Command's own __init__ would repeat the
        # checks just made, and the slot setters are about twice as fast as ``init``.
        command = new(Command)
        set_pattern(command, pattern)
        set_codes(command, tuple(p[1 : 1 + n_fields]))
        decoded = new(Decoded)
        set_command(decoded, command)
        set_corrected(decoded, corrected)
        set_sync_errors(decoded, sync)
        return decoded

    return decode


def _decline(raw: bytes, tolerance: int) -> None:
    """The straight line of a dictionary it cannot table: every frame to the bit-level path."""
    return None
