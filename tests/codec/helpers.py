"""Shared helpers of the codec tests: bit flipping, crafted frames, random commands, streams.

Conventions (the codec's own): a codeword is a 72-bit ``int`` whose bit ``i`` is the
coefficient of ``x^i``, so bit 71 is sent first; a frame is a 100-bit ``int`` whose most
significant bit is frame bit 0. Codeword error positions below are ``int`` bit indices
(0..71); header error positions are frame bit indices (0..23, 0 = first bit on the wire).
"""

from __future__ import annotations

import json
import random
from collections.abc import Iterable, Sequence
from functools import cache
from pathlib import Path
from typing import Any

from hypothesis import strategies as st

from codec import (
    CODE,
    CODEWORD_BITS,
    CRC_BITS,
    DICTIONARY,
    FIELD_BITS,
    FIELDS_PER_FRAME,
    FRAME_BITS,
    GUARD_BITS,
    SYNC_BITS,
    SYNC_WORD,
    Accepted,
    Command,
    CommandDictionary,
    Event,
    Field,
    FrameReceiver,
    NumericScale,
    ParamValue,
    Pattern,
    crc4,
    frame_of,
)

VECTORS_PATH = Path(__file__).parent / "data" / "bch_galois_vectors.json"

#: Frame bits from the top of the frame int to the bottom of the sync word.
_SYNC_SHIFT = CODEWORD_BITS + GUARD_BITS


@cache
def galois_vectors() -> dict[str, Any]:
    """The committed galois oracle (``scripts/gen_bch_vectors.py``)."""
    data: dict[str, Any] = json.loads(VECTORS_PATH.read_text(encoding="utf-8"))
    return data


def galois_code(t: int) -> dict[str, Any]:
    """The vectors entry of the t-error-correcting code."""
    for code in galois_vectors()["codes"]:
        if code["t"] == t:
            entry: dict[str, Any] = code
            return entry
    raise KeyError(t)


def mask_of(positions: Iterable[int]) -> int:
    """An int with the given bits set (positions must be distinct)."""
    positions = list(positions)
    assert len(set(positions)) == len(positions), positions
    mask = 0
    for p in positions:
        mask |= 1 << p
    return mask


def random_error(rng: random.Random, width: int, weight: int) -> int:
    """A ``width``-bit error pattern of exactly ``weight`` ones."""
    return mask_of(rng.sample(range(width), weight))


def flip_frame(
    value: int,
    *,
    header: Iterable[int] = (),
    codeword: Iterable[int] = (),
    guard: int = 0,
) -> int:
    """A frame int with header bits (frame indices 0..23) and codeword bits (x^i indices
    0..71) flipped and the guard bits XORed with ``guard``."""
    header_mask = mask_of(FRAME_BITS - 1 - i for i in header)
    return value ^ header_mask ^ (mask_of(codeword) << GUARD_BITS) ^ guard


def frame_value(codeword: int, *, header: int = SYNC_WORD, guard: int = 0) -> int:
    """The 100-bit frame int made of a header, a 72-bit codeword and 4 guard bits."""
    return (header << _SYNC_SHIFT) | (codeword << GUARD_BITS) | guard


def payload(pattern_id: int, codes: Sequence[int]) -> int:
    """The 52-bit payload: 4-bit ID then six 8-bit fields (missing trailing fields zero)."""
    assert len(codes) <= FIELDS_PER_FRAME
    value = pattern_id
    for j in range(FIELDS_PER_FRAME):
        value = (value << FIELD_BITS) | (codes[j] if j < len(codes) else 0)
    return value


def message(pattern_id: int, codes: Sequence[int], *, crc_xor: int = 0) -> int:
    """The 56-bit BCH message of a payload, its CRC-4 XORed with ``crc_xor``."""
    p = payload(pattern_id, codes)
    return (p << CRC_BITS) | (crc4(p) ^ crc_xor)


def crafted_frame(pattern_id: int, codes: Sequence[int], *, crc_xor: int = 0) -> int:
    """A frame int whose codeword is a valid BCH codeword of an arbitrary payload."""
    return frame_value(CODE.encode(message(pattern_id, codes, crc_xor=crc_xor)))


def valid_codes(f: Field) -> list[int]:
    """Every code the field's quantization defines."""
    return [c for c in range(1 << FIELD_BITS) if f.scale.is_valid_code(c)]


def representable(f: Field) -> list[ParamValue]:
    """Every value the field can send, in code order."""
    return [f.value_of(c) for c in valid_codes(f)]


def in_range(f: Field) -> st.SearchStrategy[ParamValue]:
    """Any value the field accepts on encode (not only the representable ones)."""
    scale = f.scale
    if not isinstance(scale, NumericScale):
        choices = list(scale.choices)
        return st.sampled_from(choices + [c.upper() for c in choices] + [f" {c} " for c in choices])
    if scale.integer:
        return st.integers(int(scale.minimum), int(scale.maximum))
    if scale.period is not None:
        return st.floats(-scale.period, scale.period)
    return st.floats(scale.minimum, scale.maximum)


def requested_params(pattern: Pattern) -> st.SearchStrategy[dict[str, ParamValue]]:
    """Parameters for ``pattern``: each a representable value or any value in range."""
    return st.fixed_dictionaries(
        {f.name: st.one_of(st.sampled_from(representable(f)), in_range(f)) for f in pattern.fields}
    )


def random_command(rng: random.Random, dictionary: CommandDictionary = DICTIONARY) -> Command:
    """A command of a random pattern with random valid codes."""
    pattern: Pattern = rng.choice(list(dictionary.values()))
    codes = tuple(rng.choice(valid_codes(f)) for f in pattern.fields)
    return Command(pattern, codes)


def random_bits(rng: random.Random, n: int) -> str:
    """``n`` random '0'/'1' characters."""
    return format(rng.getrandbits(n), f"0{n}b") if n else ""


def frame_bits(
    command: Command,
    *,
    header: Iterable[int] = (),
    codeword: Iterable[int] = (),
    guard: bool = True,
) -> str:
    """The frame of ``command`` as '0'/'1' text, damaged as asked, with or without guard."""
    value = flip_frame(frame_of(command).value, header=header, codeword=codeword)
    bits = format(value, f"0{FRAME_BITS}b")
    return bits if guard else bits[: FRAME_BITS - GUARD_BITS]


def chunked(bits: str, sizes: Iterable[int]) -> list[str]:
    """``bits`` cut into pieces of the given sizes (cycled); the last piece takes the rest."""
    sizes = list(sizes)
    assert sizes and all(s > 0 for s in sizes)
    pieces = []
    i = 0
    k = 0
    while i < len(bits):
        pieces.append(bits[i : i + sizes[k % len(sizes)]])
        i += sizes[k % len(sizes)]
        k += 1
    return pieces


def summary(event: Event) -> tuple[object, ...]:
    """A comparable summary of an event (``DecodeError`` instances compare by identity)."""
    if isinstance(event, Accepted):
        d = event.decoded
        return ("accepted", event.offset, d.command, d.corrected, d.sync_errors)
    return ("rejected", event.offset, event.error.reason, event.error.field, str(event.error))


def feed_pieces(pieces: Iterable[str], **kwargs: Any) -> list[tuple[object, ...]]:
    """Feed the pieces to a fresh receiver; the summaries of all events, in order."""
    receiver = FrameReceiver(**kwargs)
    events: list[Event] = []
    for piece in pieces:
        events += receiver.feed_bits(piece)
    return [summary(e) for e in events]


def accepted(summaries: Iterable[tuple[object, ...]]) -> list[tuple[object, ...]]:
    return [s for s in summaries if s[0] == "accepted"]


def rejected(summaries: Iterable[tuple[object, ...]]) -> list[tuple[object, ...]]:
    return [s for s in summaries if s[0] == "rejected"]


def sync_distance(window: int) -> int:
    """Bits in which a 24-bit window differs from the sync word."""
    assert 0 <= window < 1 << SYNC_BITS
    return (window ^ SYNC_WORD).bit_count()
