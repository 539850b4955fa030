"""The Monte Carlo runs of ``nemesys analyze ber``: random valid commands through a frame of
any T, a noisy channel and the receiver's checks, counted.

Every frame carries a random valid command (uniform pattern, uniform valid code per used
field), seeded. Independent errors flip every transmitted bit (sync, codeword and guard) with
probability ``ber``; a burst of ``L`` bits is a window of ``L`` consecutive codeword bits at a
uniform position in which every bit flips with probability 1/2. T = 2 is encoded, corrupted
and decoded by :mod:`codec.batch`; the other codes by :class:`analysis.ber_frames.BitFrames`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Final, Literal

import numpy as np
from numpy.typing import NDArray

from analysis.ber_analytic import REAL_T, code_length, frame_bits
from analysis.ber_frames import U8, U64, BitFrames, Bool, Decision
from codec import (
    DEFAULT_SYNC_TOLERANCE,
    DICTIONARY,
    FIELD_BITS,
    FIELDS_PER_FRAME,
    SYNC_BITS,
    CommandDictionary,
)
from codec import batch as codec_batch

ErrorKind = Literal["independent", "burst"]


# --- random commands and the dictionary checks ----------------------------------------------


class CommandTables:
    """Draws random valid commands as 52-bit payloads and applies the dictionary checks."""

    def __init__(self, dictionary: CommandDictionary = DICTIONARY) -> None:
        patterns = list(dictionary.values())
        n_pat = len(patterns)
        self.ids = np.array([p.id for p in patterns], dtype=np.uint64)
        self.codes = np.zeros((n_pat, FIELDS_PER_FRAME, 256), dtype=np.uint64)
        self.counts = np.ones((n_pat, FIELDS_PER_FRAME), dtype=np.int64)
        self.known = np.zeros(16, dtype=np.bool_)
        self.valid = np.zeros((16, FIELDS_PER_FRAME, 256), dtype=np.bool_)
        for i, pattern in enumerate(patterns):
            self.known[pattern.id] = True
            for j in range(FIELDS_PER_FRAME):
                if j < len(pattern.fields):
                    scale = pattern.fields[j].scale
                    ok = [c for c in range(256) if scale.is_valid_code(c)]
                else:
                    ok = [0]  # unused fields must be zero
                self.codes[i, j, : len(ok)] = ok
                self.counts[i, j] = len(ok)
                self.valid[pattern.id, j, ok] = True

    def draw(self, rng: np.random.Generator, n: int) -> U64:
        """``n`` payloads: uniform pattern, uniform valid code in every used field."""
        which = rng.integers(0, len(self.ids), n)
        index = (rng.random((n, FIELDS_PER_FRAME)) * self.counts[which]).astype(np.intp)
        payload = self.ids[which]
        for j in range(FIELDS_PER_FRAME):
            payload = (payload << np.uint64(FIELD_BITS)) | self.codes[which, j, index[:, j]]
        return payload

    def check(self, payloads: U64) -> Bool:
        """Pattern ID known, every field code valid, unused fields zero."""
        pattern_id = (payloads >> np.uint64(FIELDS_PER_FRAME * FIELD_BITS)).astype(np.intp)
        ok: Bool = self.known[pattern_id]
        for j in range(FIELDS_PER_FRAME):
            shift = np.uint64((FIELDS_PER_FRAME - 1 - j) * FIELD_BITS)
            code = ((payloads >> shift) & np.uint64(0xFF)).astype(np.intp)
            ok &= self.valid[pattern_id, j, code]
        return ok


# --- error injection ------------------------------------------------------------------------


def inject_independent(frames: U8, n_bits: int, ber: float, rng: np.random.Generator) -> None:
    """Flip each of the first ``n_bits`` bits of every packed frame with probability ``ber``."""
    n = frames.shape[0]
    if ber > codec_batch.SPARSE_BER_LIMIT:
        flips = rng.random((n, n_bits), dtype=np.float32) < np.float32(ber)
        frames ^= np.packbits(flips, axis=1)
        return
    total = n * n_bits
    count = int(rng.binomial(total, ber))
    positions = np.unique(rng.integers(0, total, size=count, dtype=np.int64))
    while positions.shape[0] < count:  # a uniform subset of exactly ``count`` positions
        extra = rng.integers(0, total, size=count - positions.shape[0], dtype=np.int64)
        positions = np.unique(np.concatenate([positions, extra]))
    rows, bits = positions // n_bits, positions % n_bits
    flat = rows * frames.shape[1] + bits // 8
    masks = (0x80 >> (bits % 8)).astype(np.float64)
    flipped = np.bincount(flat, weights=masks, minlength=frames.size).astype(np.uint8)
    frames ^= flipped.reshape(frames.shape)


def inject_burst(frames: U8, n_codeword: int, length: int, rng: np.random.Generator) -> None:
    """A window of ``length`` codeword bits at a uniform position; each bit flips w.p. 1/2."""
    if not 1 <= length <= n_codeword:
        raise ValueError(f"burst length must be 1..{n_codeword}")
    n, width = frames.shape
    high = SYNC_BITS + n_codeword - length + 1
    start: NDArray[np.int64] = rng.integers(SYNC_BITS, high, size=(n,), dtype=np.int64)
    cols = np.arange(8 * width)
    window = (cols[None, :] >= start[:, None]) & (cols[None, :] < start[:, None] + length)
    frames ^= np.packbits(window, axis=1) & rng.integers(0, 256, (n, width), dtype=np.uint8)


# --- simulation -------------------------------------------------------------------------------


@dataclass
class Counts:
    frames: int = 0
    success: int = 0
    wrong_crc: int = 0
    wrong_nocrc: int = 0


#: Frames per numpy batch (memory: a few tens of MB at most).
CHUNK_REAL: Final = 1 << 17
CHUNK_OTHER: Final = 1 << 15


class Simulator:
    """Runs batches of frames for one T and counts the outcomes."""

    def __init__(self, t: int, commands: CommandTables) -> None:
        self.t = t
        self.commands = commands
        self.n = code_length(t)
        self.bits = frame_bits(t)
        self.model = None if t == REAL_T else BitFrames(t)
        self.chunk = CHUNK_REAL if t == REAL_T else CHUNK_OTHER

    def run(
        self,
        frames: int,
        errors: ErrorKind,
        level: float,
        rng: np.random.Generator,
        advance: Callable[[int], None] | None = None,
    ) -> Counts:
        counts = Counts()
        while counts.frames < frames:
            size = min(self.chunk, frames - counts.frames)
            self._batch(size, errors, level, rng, counts)
            if advance is not None:
                advance(size)
        return counts

    def _batch(
        self, size: int, errors: ErrorKind, level: float, rng: np.random.Generator, c: Counts
    ) -> None:
        payloads = self.commands.draw(rng, size)
        messages = codec_batch.messages_of_payloads(payloads)
        if self.model is None:
            frames = codec_batch.encode_messages(messages)
        else:
            frames = self.model.encode(messages)
        if errors == "independent":
            if self.model is None:
                codec_batch.inject_errors(frames, level, rng)
            else:
                inject_independent(frames, self.bits, level, rng)
        else:
            inject_burst(frames, self.n, int(level), rng)
        accepted_crc, accepted_nocrc, received = self.receive(frames)
        same = received == payloads
        c.frames += size
        c.success += int(np.count_nonzero(accepted_crc & same))
        c.wrong_crc += int(np.count_nonzero(accepted_crc & ~same))
        c.wrong_nocrc += int(np.count_nonzero(accepted_nocrc & ~same))

    def receive(self, frames: U8) -> tuple[Bool, Bool, U64]:
        """(accepted with the CRC-4, accepted without it, received payload) per frame."""
        real: Bool | None = None
        if self.model is None:  # the real frame: codec.batch's verdict, and its parts
            result = codec_batch.decode_frames(frames)
            decision = Decision(result.sync_errors, result.corrected >= 0, result.message)
            real = result.accepted
        else:
            decision = self.model.decode(frames)
        payload = decision.message >> np.uint64(4)
        crc_ok = codec_batch.crc4_batch(payload) == (decision.message & np.uint64(0xF))
        nocrc = (
            (decision.sync_errors <= DEFAULT_SYNC_TOLERANCE)
            & decision.bch_ok
            & self.commands.check(payload)
        )
        with_crc = nocrc & crc_ok if real is None else real
        return with_crc, nocrc, payload
