"""Vectorised encode and decode of addressed frames (numpy): the Monte Carlo twin of
:func:`codec.decode_frame` with ``vehicle`` on the 108-bit frame (docs/protocol.md,
"Addressing").

Frames are ``(N, 14)`` ``uint8`` arrays: 108 bits MSB first plus 4 zero pad bits, exactly
:meth:`codec.AddressedFrame.to_bytes`. Messages are ``uint64`` arrays holding the 64-bit BCH
message (address word, payload, CRC-4). The checks run in the scalar path's order (sync, BCH,
CRC, address, pattern, fields) and the tests compare the two frame by frame. Errors are
injected with :func:`codec.batch.inject_errors` (``n_bits=ADDRESSED_FRAME_BITS``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from codec._address import (
    _CRC_CHECK,
    ADDRESSED_CODE,
    ADDRESSED_FRAME_BYTES,
    BROADCAST_ADDRESS,
    FLEET_SYNC_WORD,
    MAX_ADDRESS,
    address_of_word,
    address_word,
    check_vehicle_address,
)
from codec._dictionary import DICTIONARY, CommandDictionary
from codec._errors import RejectReason
from codec._frame import DEFAULT_SYNC_TOLERANCE, PAYLOAD_BITS
from codec.batch import (
    _POPCOUNT8,
    ACCEPTED,
    STATUS_NAMES,
    U8,
    U64,
    BatchResult,
    _bytes_to_u64,
    _dictionary_checks,
    _remainder,
    _tables,
)

#: Status codes of :func:`decode_addressed_frames`: :data:`codec.batch.STATUS_NAMES`, then
#: ``other_vehicle``; in check order the address comes right after the CRC.
ADDRESSED_STATUS_NAMES: Final = (*STATUS_NAMES, RejectReason.OTHER_VEHICLE.value)
OTHER_VEHICLE: Final = len(STATUS_NAMES)
_NO_SYNC, _UNCORRECTABLE, _CRC, _UNKNOWN, _RANGE, _UNUSED = range(1, 7)

_CW_FIRST_BYTE: Final = 3  # bits 24..103 are bytes 3..12
_CW_BYTES: Final = ADDRESSED_CODE.n // 8  # 10
_MESSAGE_BYTES: Final = ADDRESSED_CODE.k // 8  # 8
_SYNC_BYTES: Final = np.array(
    [(FLEET_SYNC_WORD >> 16) & 0xFF, (FLEET_SYNC_WORD >> 8) & 0xFF, FLEET_SYNC_WORD & 0xFF],
    dtype=np.uint8,
)
_PARITY_T: Final = _tables(ADDRESSED_CODE.parity_tables)
_SYNDROME_T: Final = _tables(ADDRESSED_CODE.remainder_tables)
#: The message's remainder modulo the CRC polynomial (zero: the CRC holds), by bytes.
_CRC_T: Final = _tables(_CRC_CHECK.tables)
#: Address -> its word; word -> its address, or -1 for a byte that is no address word.
_WORDS: Final = np.array([address_word(a) for a in range(MAX_ADDRESS + 1)], dtype=np.uint64)
_ADDRESS_OF: Final = np.array(
    [-1 if (a := address_of_word(w)) is None else a for w in range(256)], dtype=np.int8
)


def _error_tables() -> tuple[U8, NDArray[np.int8]]:
    from codec._berlekamp import correctable_errors

    size = 1 << ADDRESSED_CODE.r
    patterns = np.zeros((size, _CW_BYTES), dtype=np.uint8)
    counts = np.full(size, -1, dtype=np.int8)
    counts[0] = 0
    for syndrome, error in correctable_errors(ADDRESSED_CODE).items():
        patterns[syndrome] = np.frombuffer(error.to_bytes(_CW_BYTES, "big"), dtype=np.uint8)
        counts[syndrome] = error.bit_count()
    return patterns, counts


_ERR_PATTERN, _ERR_COUNT = _error_tables()


@dataclass(frozen=True)
class AddressedBatchResult(BatchResult):
    """:class:`codec.batch.BatchResult` of addressed frames (``message``: the 64-bit one;
    statuses of :data:`ADDRESSED_STATUS_NAMES`) and the address each carried after
    correction (-1: no address word, or not decoded)."""

    address: NDArray[np.int8]


def addressed_messages(addresses: NDArray[np.integer], payloads: U64) -> U64:
    """64-bit messages (address word, payload, CRC-4) for addresses 0-15 and 52-bit payloads."""
    words = _WORDS[np.asarray(addresses, dtype=np.intp)]
    covered = (words << np.uint64(PAYLOAD_BITS)) | np.asarray(payloads, dtype=np.uint64)
    crc = _remainder(_CRC_T, covered << np.uint64(4)).astype(np.uint64)
    return (covered << np.uint64(4)) | crc


def encode_addressed(messages: U64) -> U8:
    """Addressed frames (N, 14) for 64-bit messages."""
    messages = np.asarray(messages, dtype=np.uint64)
    n = messages.shape[0]
    parity = _remainder(_PARITY_T, messages)
    frames = np.zeros((n, ADDRESSED_FRAME_BYTES), dtype=np.uint8)
    frames[:, :3] = _SYNC_BYTES
    frames[:, 3:11] = messages.astype(">u8").view(np.uint8).reshape(n, 8)
    frames[:, 11] = (parity >> 8).astype(np.uint8)
    frames[:, 12] = (parity & 0xFF).astype(np.uint8)
    return frames


def decode_addressed_frames(
    frames: U8,
    *,
    vehicle: int | NDArray[np.integer] | None = None,
    sync_tolerance: int = DEFAULT_SYNC_TOLERANCE,
    dictionary: CommandDictionary = DICTIONARY,
) -> AddressedBatchResult:
    """Decode aligned addressed frames with the checks of :func:`codec.decode_frame` as
    ``vehicle`` (1-15, or one per frame; ``None``: as the console, any address accepted)."""
    if isinstance(vehicle, int):
        check_vehicle_address(vehicle)
    elif vehicle is not None and not np.all((vehicle >= 1) & (vehicle <= MAX_ADDRESS)):
        raise ValueError(f"a vehicle's own address is 1 to {MAX_ADDRESS}")
    frames = np.asarray(frames, dtype=np.uint8)
    if frames.ndim != 2 or frames.shape[1] != ADDRESSED_FRAME_BYTES:
        raise ValueError(f"frames must have shape (N, {ADDRESSED_FRAME_BYTES})")
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
    message = _bytes_to_u64(fixed[:, :_MESSAGE_BYTES])
    crc_ok = _remainder(_CRC_T, message) == 0
    address = _ADDRESS_OF[(message >> np.uint64(56)).astype(np.intp)]
    for_us = address >= 0
    if vehicle is not None:
        for_us &= (address == vehicle) | (address == BROADCAST_ADDRESS)
    payload = (message >> np.uint64(4)) & np.uint64((1 << PAYLOAD_BITS) - 1)
    known_ok, range_ok, unused_ok = _dictionary_checks(payload, dictionary)
    status = np.select(
        [
            sync_errors > sync_tolerance,
            corrected < 0,
            ~crc_ok,
            ~for_us,
            ~known_ok,
            ~range_ok,
            ~unused_ok,
        ],
        [_NO_SYNC, _UNCORRECTABLE, _CRC, OTHER_VEHICLE, _UNKNOWN, _RANGE, _UNUSED],
        default=ACCEPTED,
    ).astype(np.uint8)
    corrected = np.where(status == _NO_SYNC, np.int8(-1), corrected).astype(np.int8)
    address = np.where((status == ACCEPTED) | (status >= _UNKNOWN), address, np.int8(-1))
    return AddressedBatchResult(status, corrected, sync_errors, message, address.astype(np.int8))
