"""Vectorised encode, error injection and decode of many frames at once (numpy).

For Monte Carlo analysis of the link (decode success and wrong-command rates against bit
error rate). It runs the same framing and checks as :func:`codec.decode_frame`, in the same
order (sync, BCH, CRC, pattern ID, fields), on arrays of frames; the tests cross-check it
frame by frame against the scalar path. Not imported by :mod:`codec` itself, so the onboard
path stays numpy-free.

Frames are ``(N, 13)`` ``uint8`` arrays: 100 bits MSB first plus 4 zero pad bits, exactly
:meth:`codec.Frame.to_bytes`. Messages are ``uint64`` arrays holding the 56-bit BCH message.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from codec._dictionary import DICTIONARY, FIELDS_PER_FRAME, CommandDictionary
from codec._errors import RejectReason
from codec._frame import (
    CODE,
    CRC4_REMAINDER,
    DEFAULT_SYNC_TOLERANCE,
    FAST_DECODER,
    FRAME_BITS,
    FRAME_BYTES,
    SYNC_WORD,
)
from codec._scales import FIELD_BITS, FIELD_CODES

U8 = NDArray[np.uint8]
U64 = NDArray[np.uint64]

#: Status codes of :class:`BatchResult`: 0 is accepted, then the reasons in check order.
STATUS_NAMES: Final = (
    "accepted",
    RejectReason.NO_SYNC.value,
    RejectReason.UNCORRECTABLE.value,
    RejectReason.CRC_MISMATCH.value,
    RejectReason.UNKNOWN_PATTERN.value,
    RejectReason.FIELD_OUT_OF_RANGE.value,
    RejectReason.UNUSED_FIELD_SET.value,
)
ACCEPTED: Final = 0
_NO_SYNC, _UNCORRECTABLE, _CRC, _UNKNOWN, _RANGE, _UNUSED = range(1, 7)

#: Above this BER, :func:`inject_errors` draws every bit (measured crossover ~0.003-0.01).
SPARSE_BER_LIMIT: Final = 0.005

_CW_FIRST_BYTE: Final = 3  # bits 24..95 are bytes 3..11
_CW_BYTES: Final = 9
_SYNC_BYTES: Final = np.array(
    [(SYNC_WORD >> 16) & 0xFF, (SYNC_WORD >> 8) & 0xFF, SYNC_WORD & 0xFF], dtype=np.uint8
)
_POPCOUNT8: Final = np.array([bin(i).count("1") for i in range(256)], dtype=np.uint8)


def _tables(tables: tuple[Sequence[int], ...]) -> NDArray[np.uint16]:
    """Byte tables as one array, most significant byte first (as in :mod:`codec._gf2`)."""
    return np.array([list(t) for t in tables], dtype=np.uint16)


# The scalar path's byte tables: parity of the message, syndrome of the codeword, CRC-4.
_PARITY_T: Final = _tables(CODE.parity_tables)
_SYNDROME_T: Final = _tables(CODE.remainder_tables)
_CRC_T: Final = _tables(CRC4_REMAINDER.tables)


def _error_tables() -> tuple[U8, NDArray[np.int8]]:
    size = 1 << CODE.r
    patterns = np.zeros((size, _CW_BYTES), dtype=np.uint8)
    counts = np.full(size, -1, dtype=np.int8)
    counts[0] = 0
    for syndrome, error in FAST_DECODER.error_patterns.items():
        patterns[syndrome] = np.frombuffer(error.to_bytes(_CW_BYTES, "big"), dtype=np.uint8)
        counts[syndrome] = error.bit_count()
    return patterns, counts


_ERR_PATTERN, _ERR_COUNT = _error_tables()


_VALIDITY_CACHE: dict[int, tuple[CommandDictionary, tuple[NDArray[np.bool_], ...]]] = {}


def _validity(dictionary: CommandDictionary) -> tuple[NDArray[np.bool_], ...]:
    """Per pattern ID: known?; per (ID, field, code): valid?; per (ID, field): used? (cached)."""
    cached = _VALIDITY_CACHE.get(id(dictionary))
    if cached is not None and cached[0] is dictionary:
        return cached[1]
    known = np.zeros(16, dtype=np.bool_)
    valid = np.zeros((16, FIELDS_PER_FRAME, FIELD_CODES), dtype=np.bool_)
    used = np.zeros((16, FIELDS_PER_FRAME), dtype=np.bool_)
    for pattern in dictionary.values():
        known[pattern.id] = True
        for j in range(FIELDS_PER_FRAME):
            if j < len(pattern.fields):
                used[pattern.id, j] = True
                scale = pattern.fields[j].scale
                valid[pattern.id, j] = [scale.is_valid_code(c) for c in range(FIELD_CODES)]
            else:
                valid[pattern.id, j, 0] = True
    _VALIDITY_CACHE[id(dictionary)] = (dictionary, (known, valid, used))
    return known, valid, used


@dataclass(frozen=True)
class BatchResult:
    """Per-frame outcome of :func:`decode_frames`.

    Attributes:
        status: 0 accepted, else the index of the reason in :data:`STATUS_NAMES`.
        corrected: codeword bits corrected (-1 where uncorrectable or not synced).
        sync_errors: preamble + delimiter bits that differ from the sync word.
        message: the corrected 56-bit message (meaningful where status is 0).
    """

    status: NDArray[np.uint8]
    corrected: NDArray[np.int8]
    sync_errors: NDArray[np.uint8]
    message: U64

    @property
    def accepted(self) -> NDArray[np.bool_]:
        accepted: NDArray[np.bool_] = self.status == ACCEPTED
        return accepted


def _bytes_to_u64(columns: U8) -> U64:
    out = np.zeros(columns.shape[0], dtype=np.uint64)
    for j in range(columns.shape[1]):
        out = (out << np.uint64(8)) | columns[:, j].astype(np.uint64)
    return out


def _remainder(tables: NDArray[np.uint16], value: U64) -> NDArray[np.uint16]:
    """XOR of the byte tables indexed by the bytes of ``value`` (MSB-first tables)."""
    out = np.zeros(value.shape[0], dtype=np.uint16)
    last = tables.shape[0] - 1
    for j in range(tables.shape[0]):
        shift = np.uint64(8 * (last - j))
        out ^= tables[j][((value >> shift) & np.uint64(0xFF)).astype(np.intp)]
    return out


def crc4_batch(payloads: U64) -> NDArray[np.uint16]:
    """CRC-4 of each 52-bit payload."""
    return _remainder(_CRC_T, payloads)


def encode_messages(messages: U64) -> U8:
    """Frames (N, 13) for 56-bit messages (payload + CRC-4 already in place)."""
    messages = np.asarray(messages, dtype=np.uint64)
    n = messages.shape[0]
    parity = _remainder(_PARITY_T, messages)
    frames = np.zeros((n, FRAME_BYTES), dtype=np.uint8)
    frames[:, :3] = _SYNC_BYTES
    frames[:, 3:10] = messages.astype(">u8").view(np.uint8).reshape(n, 8)[:, 1:]
    frames[:, 10] = (parity >> 8).astype(np.uint8)
    frames[:, 11] = (parity & 0xFF).astype(np.uint8)
    return frames


def messages_of_payloads(payloads: U64) -> U64:
    """56-bit messages (payload << 4 | CRC-4) for 52-bit payloads."""
    payloads = np.asarray(payloads, dtype=np.uint64)
    return (payloads << np.uint64(4)) | crc4_batch(payloads).astype(np.uint64)


def inject_errors(
    frames: U8, ber: float, rng: np.random.Generator, n_bits: int = FRAME_BITS
) -> NDArray[np.int64]:
    """Flip each of the 100 bits of every frame independently with probability ``ber``
    (``n_bits``: the first ``n_bits`` of each row, e.g. an addressed frame's 108).

    Changes ``frames`` in place and returns the number of bits flipped per frame. Below
    :data:`SPARSE_BER_LIMIT` the error positions are drawn sparsely (a Binomial number of
    errors, then an exact uniform subset of positions), which costs little at low BERs;
    above it every bit gets its own uniform draw (float32, resolution 2^-24).
    """
    if not 0.0 <= ber <= 1.0:
        raise ValueError(f"ber must be in [0, 1], got {ber}")
    n = frames.shape[0]
    if ber > SPARSE_BER_LIMIT:
        flips = rng.random((n, n_bits), dtype=np.float32) < np.float32(ber)
        frames[:, : (n_bits + 7) // 8] ^= np.packbits(flips, axis=1)
        counts: NDArray[np.int64] = flips.sum(axis=1, dtype=np.int64)
        return counts
    total_bits = n * n_bits
    positions = _distinct_positions(total_bits, int(rng.binomial(total_bits, ber)), rng)
    _flip(frames, positions, n_bits)
    return np.bincount(positions // n_bits, minlength=n)


def inject_weight(
    frames: U8, weight: int, rng: np.random.Generator, first_bit: int = 0, end_bit: int = FRAME_BITS
) -> None:
    """Flip exactly ``weight`` distinct bits in ``[first_bit, end_bit)`` of every frame."""
    span = end_bit - first_bit
    if not 0 <= weight <= span:
        raise ValueError(f"weight must be 0..{span}")
    n = frames.shape[0]
    if weight == 0:
        return
    # argsort of random keys gives a uniform random permutation per row; keep the first k.
    keys = rng.random((n, span), dtype=np.float32)
    chosen = np.argpartition(keys, weight - 1, axis=1)[:, :weight] + first_bit
    rows = np.repeat(np.arange(n, dtype=np.int64), weight)
    _flip(frames, rows * FRAME_BITS + chosen.reshape(-1))


def _distinct_positions(total: int, k: int, rng: np.random.Generator) -> NDArray[np.int64]:
    positions = np.unique(rng.integers(0, total, size=k, dtype=np.int64))
    while positions.shape[0] < k:  # replace duplicates: the result is a uniform k-subset
        extra = rng.integers(0, total, size=k - positions.shape[0], dtype=np.int64)
        positions = np.unique(np.concatenate([positions, extra]))
    return positions


def _flip(frames: U8, positions: NDArray[np.int64], n_bits: int = FRAME_BITS) -> None:
    rows = positions // n_bits
    bits = positions % n_bits
    flat_byte = rows * frames.shape[1] + bits // 8
    masks = (0x80 >> (bits % 8)).astype(np.float64)
    # Positions are distinct, so per byte the sum of the masks is their OR.
    flips = np.bincount(flat_byte, weights=masks, minlength=frames.size).astype(np.uint8)
    frames ^= flips.reshape(frames.shape)


def _dictionary_checks(
    payload: U64, dictionary: CommandDictionary
) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.bool_]]:
    """Per 52-bit payload: pattern ID known, every used field's code valid, unused fields
    zero (the scalar path's checks after the CRC)."""
    known, valid, used = _validity(dictionary)
    pattern_id = (payload >> np.uint64(FIELDS_PER_FRAME * FIELD_BITS)).astype(np.intp)
    range_ok = np.ones(payload.shape[0], dtype=np.bool_)
    unused_ok = np.ones(payload.shape[0], dtype=np.bool_)
    for j in range(FIELDS_PER_FRAME):
        shift = np.uint64((FIELDS_PER_FRAME - 1 - j) * FIELD_BITS)
        code = ((payload >> shift) & np.uint64(0xFF)).astype(np.intp)
        ok = valid[pattern_id, j, code]
        is_used = used[pattern_id, j]
        # Unused fields always follow the used ones, so the scalar path's "first failing
        # field" is a range failure whenever there is one: np.select's order gives that.
        unused_ok &= ok | is_used
        range_ok &= ok | ~is_used
    known_ok: NDArray[np.bool_] = known[pattern_id]
    return known_ok, range_ok, unused_ok


def decode_frames(
    frames: U8,
    *,
    sync_tolerance: int = DEFAULT_SYNC_TOLERANCE,
    dictionary: CommandDictionary = DICTIONARY,
) -> BatchResult:
    """Decode aligned frames with the checks of :func:`codec.decode_frame`."""
    frames = np.asarray(frames, dtype=np.uint8)
    if frames.ndim != 2 or frames.shape[1] != FRAME_BYTES:
        raise ValueError(f"frames must have shape (N, {FRAME_BYTES})")
    sync_errors = (
        _POPCOUNT8[frames[:, 0] ^ _SYNC_BYTES[0]]
        + _POPCOUNT8[frames[:, 1] ^ _SYNC_BYTES[1]]
        + _POPCOUNT8[frames[:, 2] ^ _SYNC_BYTES[2]]
    )
    codeword = frames[:, _CW_FIRST_BYTE : _CW_FIRST_BYTE + _CW_BYTES]
    syndrome = np.zeros(frames.shape[0], dtype=np.uint16)
    for j in range(_CW_BYTES):
        syndrome ^= _SYNDROME_T[j][codeword[:, j]]
    corrected = _ERR_COUNT[syndrome]
    fixed = codeword ^ _ERR_PATTERN[syndrome]
    message = _bytes_to_u64(fixed[:, :7])
    payload = message >> np.uint64(4)
    crc_ok = crc4_batch(payload) == (message & np.uint64(0xF))
    known_ok, range_ok, unused_ok = _dictionary_checks(payload, dictionary)
    status = np.select(
        [
            sync_errors > sync_tolerance,
            corrected < 0,
            ~crc_ok,
            ~known_ok,
            ~range_ok,
            ~unused_ok,
        ],
        [_NO_SYNC, _UNCORRECTABLE, _CRC, _UNKNOWN, _RANGE, _UNUSED],
        default=ACCEPTED,
    ).astype(np.uint8)
    corrected = np.where(status == _NO_SYNC, np.int8(-1), corrected).astype(np.int8)
    return BatchResult(status, corrected, sync_errors, message)
