"""The onboard decode's straight line: a frame that starts at a byte boundary.

A modem delivers a frame as its 13 bytes, so the receiver's common case is a buffer whose
first three bytes are the preamble and delimiter. :func:`straight_line` decodes that case
without the bit-level search: the sync distance from three bytes, the BCH syndrome from the
nine codeword bytes (the table decoder's message tables, ``FAST_DECODER.message_tables``), a
closed-form correction when it is not zero (its tables, written out as in the table decoder),
the CRC-4 check in the same lookups (the tables carry it: ``codec._frame._check_tables``), and
the pattern and field checks from tables made once per dictionary (all six fields in one mask
test, see :func:`_field_classes`).

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
from codec._gf2 import poly_mod
from codec._record import slot_setters

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Callable

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


#: Per pattern ID: the pattern, the slice of the payload's bytes that are its codes, and the
#: class bits its codes need.
Entry = tuple[Pattern, slice, int]


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
        entries[pattern.id] = (pattern, slice(1, 1 + len(pattern.fields)), mask)
    if len(bits) > 8:
        return None
    classes = bytes(sum(bit for valid, bit in bits.items() if valid[code]) for code in range(256))
    return classes, entries


def _build(dictionary: CommandDictionary) -> StraightLine:  # noqa: PLR0915 (the hot path below)
    if SYNC_BITS != 24 or CODE.n != 72 or CODE.r != 16 or FIELDS_PER_FRAME != 6 or CRC_BITS != 4:
        raise ValueError("the straight line is written for the 24 + 72-bit frame layout")
    closed_form = FAST_DECODER.closed_form
    if closed_form is None or len(FAST_DECODER.message_tables) != MESSAGE_BYTES:
        raise ValueError("the straight line needs the t = 2 table decoder")
    # Bits 0-15 of each message byte's entry: its BCH remainder; bits 16-19: its CRC check.
    t0, t1, t2, t3, t4, t5, t6 = FAST_DECODER.message_tables
    if any(max(t) >> CODE.r + CRC_BITS for t in FAST_DECODER.message_tables) or not any(
        max(t) >> CODE.r for t in FAST_DECODER.message_tables
    ):
        raise ValueError("the table decoder's message tables do not carry the CRC check")
    st_lo, st_hi, log, cube, first, second, first0, second0, bit = closed_form
    # crc_of[e]: the CRC check of the error at the position of log e (bit[e]'s), 0 for a
    # parity bit and where bit[e] is 0: the received message's check plus the errors' is the
    # corrected message's (the check is linear).
    crc_of = tuple(poly_mod(error >> CODE.r, CRC_POLY) if error >> CODE.r else 0 for error in bit)
    field_classes = _field_classes(dictionary)
    if field_classes is None:
        return _decline
    classes, entries = field_classes
    half_shift = SHIFT_DISTANCE // 2
    from_bytes = int.from_bytes
    new = object.__new__
    set_pattern, set_codes = slot_setters(Command, "pattern", "codes")
    set_command, set_corrected, set_sync_errors = slot_setters(
        Decoded, "command", "corrected", "sync_errors"
    )
    payload_mask = (1 << (MESSAGE_BITS - CRC_BITS)) - 1
    payload_shift = CODE.r + CRC_BITS

    def decode(raw: bytes, tolerance: int) -> Decoded | None:  # noqa: PLR0915 (written out)
        w = from_bytes(raw[:ALIGNED_BYTES], "big")  # sync word, then the codeword
        sync = w >> 72 ^ SYNC_WORD
        if sync:
            sync = sync.bit_count()
            if sync > tolerance or sync > half_shift:
                return None
        # Bits 0-15: the BCH syndrome (the parity bytes are their own remainder); bits 16-19:
        # the received message's CRC check.
        check = (
            t0[raw[3]] ^ t1[raw[4]] ^ t2[raw[5]] ^ t3[raw[6]] ^ t4[raw[7]] ^ t5[raw[8]]
            ^ t6[raw[9]] ^ (w & 0xFFFF)
        )  # fmt: skip
        if check:
            # The closed form (codec._bch), written out: a call costs more than it.
            syn = check & 0xFFFF
            if not syn:
                return None  # no BCH error: the CRC failed
            st = st_lo[syn & 0xFF] ^ st_hi[syn >> 8]  # S1 | S3 << 8
            s1 = st & 0xFF
            if not s1:
                return None
            l1 = log[s1]
            s3 = st >> 8
            if s3:
                k = log[s3] - cube[l1]
                if not k:  # one error, at log S1
                    error = bit[l1]
                    if not error or check >> 16 != crc_of[l1]:
                        return None
                    p = ((w ^ error) >> payload_shift & payload_mask).to_bytes(7, "big")
                    corrected = 1
                else:
                    i1 = first[k] + l1
                    i2 = second[k] + l1
                    error = bit[i1]
                    if not error or not bit[i2] or check >> 16 != crc_of[i1] ^ crc_of[i2]:
                        return None
                    error ^= bit[i2]
                    p = ((w ^ error) >> payload_shift & payload_mask).to_bytes(7, "big")
                    corrected = 2
            else:
                i1 = first0 + l1
                i2 = second0 + l1
                error = bit[i1]
                if not error or not bit[i2] or check >> 16 != crc_of[i1] ^ crc_of[i2]:
                    return None
                error ^= bit[i2]
                p = ((w ^ error) >> payload_shift & payload_mask).to_bytes(7, "big")
                corrected = 2
        else:  # a codeword whose CRC holds
            p = (w >> payload_shift & payload_mask).to_bytes(7, "big")
            corrected = 0
        entry = entries[p[0]]
        if entry is None:
            return None
        pattern, codes, mask = entry
        if from_bytes(p.translate(classes), "big") & mask != mask:
            return None  # a field check fails
        # The records, filled through their slots: Command's own __init__ would repeat the
        # checks just made, and the slot setters are about twice as fast as ``init``.
        command = new(Command)
        set_pattern(command, pattern)
        set_codes(command, tuple(p[codes]))
        decoded = new(Decoded)
        set_command(decoded, command)
        set_corrected(decoded, corrected)
        set_sync_errors(decoded, sync)
        return decoded

    return decode


def _decline(raw: bytes, tolerance: int) -> None:
    """The straight line of a dictionary it cannot table: every frame to the bit-level path."""
    return None
