"""The numpy batch path agrees with the scalar decoder frame by frame, and injects errors
with the statistics it claims."""

from __future__ import annotations

import random

import numpy as np
import pytest
from numpy.typing import NDArray

from codec import Command, DecodeError, crc4, decode_frame, frame_of, message_of
from codec.batch import (
    ACCEPTED,
    SPARSE_BER_LIMIT,
    STATUS_NAMES,
    crc4_batch,
    decode_frames,
    encode_messages,
    inject_errors,
    inject_weight,
    messages_of_payloads,
)
from tests.codec.helpers import random_command


def _commands_and_frames(seed: int, n: int) -> tuple[list[Command], NDArray[np.uint8]]:
    rng = random.Random(seed)
    commands = [random_command(rng) for _ in range(n)]
    messages = np.array([message_of(c) for c in commands], dtype=np.uint64)
    return commands, encode_messages(messages)


def test_encode_messages_equals_scalar_frames_byte_for_byte() -> None:
    commands, frames = _commands_and_frames(1, 500)
    for command, row in zip(commands, frames, strict=True):
        assert bytes(row) == frame_of(command).to_bytes()


def test_crc_and_messages_of_payloads_match_scalar() -> None:
    rng = np.random.default_rng(3)
    payloads = rng.integers(0, 1 << 52, 2000, dtype=np.uint64)
    crcs = crc4_batch(payloads)
    assert [int(c) for c in crcs] == [crc4(int(p)) for p in payloads]
    messages = messages_of_payloads(payloads)
    pairs = zip(messages, payloads, strict=True)
    assert all(int(m) == (int(p) << 4) | crc4(int(p)) for m, p in pairs)


@pytest.mark.parametrize("ber", [0.0, 1e-3, 1e-2, 3e-2, 0.1, 0.3])
def test_decode_frames_matches_decode_frame(ber: float) -> None:
    _, frames = _commands_and_frames(int(ber * 1e4), 3000)
    inject_errors(frames, ber, np.random.default_rng(11))
    result = decode_frames(frames)
    for i, row in enumerate(frames):
        try:
            decoded = decode_frame(bytes(row))
        except DecodeError as err:
            assert STATUS_NAMES[result.status[i]] == err.reason.value
            continue
        assert result.status[i] == ACCEPTED
        assert int(result.message[i]) == message_of(decoded.command)
        assert result.corrected[i] == decoded.corrected
        assert result.sync_errors[i] == decoded.sync_errors


@pytest.mark.slow  # a large batch at high BER, ~1.5 s
def test_every_reject_reason_appears_at_high_ber_and_matches() -> None:
    """At BER 0.1 every status occurs in a large batch, so the comparison above covers them."""
    _, frames = _commands_and_frames(5, 20000)
    inject_errors(frames, 0.1, np.random.default_rng(2))
    seen = set(decode_frames(frames).status.tolist())
    assert seen == set(range(len(STATUS_NAMES)))


@pytest.mark.parametrize("weight", [0, 1, 2])
def test_correctable_weights_are_all_corrected(weight: int) -> None:
    commands, frames = _commands_and_frames(7, 2000)
    inject_weight(frames, weight, np.random.default_rng(weight), first_bit=24, end_bit=96)
    result = decode_frames(frames)
    assert result.accepted.all()
    assert (result.corrected == weight).all()
    expected = [message_of(c) for c in commands]
    assert [int(m) for m in result.message] == expected


def test_inject_weight_flips_exactly_weight_distinct_bits_in_range() -> None:
    _, frames = _commands_and_frames(8, 1000)
    before = np.unpackbits(frames.copy(), axis=1)[:, :100]
    inject_weight(frames, 5, np.random.default_rng(0), first_bit=30, end_bit=60)
    diff = np.unpackbits(frames, axis=1)[:, :100] ^ before
    assert (diff.sum(axis=1) == 5).all()
    assert not diff[:, :30].any() and not diff[:, 60:].any()


@pytest.mark.parametrize("ber", [1e-3, SPARSE_BER_LIMIT / 2, 2e-2, 0.2])
def test_inject_errors_statistics(ber: float) -> None:
    """Mean flips per frame is 100 * ber (within 5 sigma); counts match the frames' diff;
    pad bits stay zero; both the sparse and the dense branch are exercised."""
    n = 200_000
    frames = np.zeros((n, 13), dtype=np.uint8)
    counts = inject_errors(frames, ber, np.random.default_rng(42))
    flipped = np.unpackbits(frames, axis=1)
    assert not flipped[:, 100:].any()
    assert (flipped.sum(axis=1) == counts).all()
    mean, sigma = 100 * ber, np.sqrt(100 * ber * (1 - ber) / n)
    assert abs(counts.mean() - mean) < 5 * sigma
    per_bit = flipped[:, :100].mean(axis=0)
    assert abs(per_bit.mean() - ber) < 5 * np.sqrt(ber * (1 - ber) / (n * 100))


def test_bad_arguments_are_refused() -> None:
    frames = np.zeros((2, 13), dtype=np.uint8)
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="ber"):
        inject_errors(frames, 1.5, rng)
    with pytest.raises(ValueError, match="weight"):
        inject_weight(frames, 101, rng)
    with pytest.raises(ValueError, match="shape"):
        decode_frames(np.zeros((2, 12), dtype=np.uint8))
