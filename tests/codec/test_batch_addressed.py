"""The numpy twin of the addressed frame (codec.batch_addressed) against the scalar path, and a
vehicle never executing another's frame: 10^5 corrupted frames at BER 1e-2 through the real
receiver (the one the onboard agent runs) in the fast tier. The 10^7-frame run through the
numpy twin is tests/analysis/test_addressing.py's (slow tier: ~10 s)."""

from __future__ import annotations

import numpy as np
import pytest

from codec import (
    ADDRESSED_FRAME_BITS,
    DICTIONARY,
    FIELD_BITS,
    FIELDS_PER_FRAME,
    Accepted,
    AddressedReceiver,
    DecodeError,
    decode_frame,
)
from codec.batch import ACCEPTED, inject_errors
from codec.batch_addressed import (
    ADDRESSED_STATUS_NAMES,
    OTHER_VEHICLE,
    addressed_messages,
    decode_addressed_frames,
    encode_addressed,
)


def valid_payloads(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` random valid commands as 52-bit payloads: uniform pattern, uniform valid codes."""
    patterns = list(DICTIONARY.values())
    out = np.zeros(n, dtype=np.uint64)
    which = rng.integers(0, len(patterns), n)
    for i, p in enumerate(patterns):
        rows = np.flatnonzero(which == i)
        value = np.full(rows.shape[0], p.id, dtype=np.uint64)
        for j in range(FIELDS_PER_FRAME):
            codes = (
                [c for c in range(256) if p.fields[j].scale.is_valid_code(c)]
                if j < len(p.fields)
                else [0]
            )
            pick = np.asarray(codes, dtype=np.uint64)[rng.integers(0, len(codes), rows.shape[0])]
            value = (value << np.uint64(FIELD_BITS)) | pick
        out[rows] = value
    return out


def corrupted(
    seed: int, n: int, ber: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Frames from random vehicles 1-15 (and to all, one in 16), corrupted at ``ber``; with each
    a random vehicle it is not for."""
    rng = np.random.default_rng(seed)
    senders = rng.integers(0, 16, n)
    others = np.where(
        senders == 0, rng.integers(1, 16, n), (senders + rng.integers(0, 14, n)) % 15 + 1
    )
    payloads = valid_payloads(rng, n)
    frames = encode_addressed(addressed_messages(senders, payloads))
    inject_errors(frames, ber, rng, n_bits=ADDRESSED_FRAME_BITS)
    return frames, senders, others, payloads


@pytest.mark.parametrize("ber", [0.01, 0.05])
def test_the_twin_decides_as_the_scalar_path(ber: float) -> None:
    frames, senders, others, _ = corrupted(1, 4000, ber)
    for vehicle in (others, senders):
        result = decode_addressed_frames(frames, vehicle=np.where(vehicle == 0, 1, vehicle))
        for i in range(frames.shape[0]):
            v = int(vehicle[i]) or 1
            try:
                dec = decode_frame(frames[i].tobytes(), vehicle=v)
            except DecodeError as err:
                assert ADDRESSED_STATUS_NAMES[result.status[i]] == err.reason.value, i
                continue
            assert result.status[i] == ACCEPTED and result.address[i] == dec.address  # type: ignore[attr-defined]


@pytest.mark.slow
def test_a_vehicle_never_executes_another_vehicles_frame_real_receiver() -> None:
    """10^5 frames at BER 1e-2, each through a fresh AddressedReceiver of a vehicle it is not
    for (frames to all excepted: those are every vehicle's): none accepted."""
    frames, senders, others, _ = corrupted(2023, 100_000, 0.01)
    taken = 0
    refused_as_other = 0
    for i in np.flatnonzero(senders != 0):
        events = AddressedReceiver(int(others[i])).feed_bytes(frames[i].tobytes())
        taken += any(isinstance(e, Accepted) for e in events)
        refused_as_other += any(
            e.error.reason == "other_vehicle" for e in events if not isinstance(e, Accepted)
        )
    assert taken == 0
    assert refused_as_other > 0.9 * np.count_nonzero(senders)  # the check did run: most decoded
    # and the twin agrees on the same frames
    result = decode_addressed_frames(frames, vehicle=others)
    assert not np.any((result.status == ACCEPTED) & (senders != 0))
    assert np.count_nonzero(result.status == OTHER_VEHICLE) == refused_as_other + np.count_nonzero(
        (senders == 0) & (result.status == OTHER_VEHICLE)
    )
