"""Decode success and wrong-command acceptance against bit error rate (``nemesys analyze ber``).

Redoes the paper's Fig. ``fig:encoding_eval`` (decoding success rate against BER for
T = 1..4, and the coding efficiency that motivates T = 2) by Monte Carlo through the real frame
and decoder, with Wilson 95 % intervals, against the analytic curve; and measures how often a
frame is accepted as a *different* valid command, with and without the CRC-4, for independent
and for burst errors.

Frames and decoders:

* **T = 2 is the real frame**: :mod:`codec.batch` encodes, injects the bit errors into and
  decodes ``(N, 13)`` packed frames with exactly the checks of :func:`codec.decode_frame`
  (sync word within :data:`codec.DEFAULT_SYNC_TOLERANCE` bits, BCH(72, 56) syndrome-table
  decoder, CRC-4, pattern ID, field codes, unused fields zero).
* **T = 1, 3, 4** use the same layout with that code's parity: sync word (24) + the
  ``n = 56 + 8T`` bit codeword of ``BCHCode(T)`` over GF(2^8) + 4 guard bits, the same
  message (pattern ID, six fields, CRC-4) and the same checks in the same order. They are
  decoded by :class:`BitFrames`, a numpy transcription of :meth:`codec.BCHCode.decode`
  (syndromes, Berlekamp-Massey, Chien search over the shortened length, the same acceptance
  rule); the tests check it against the scalar decoder word by word, and at T = 2 against
  :mod:`codec.batch` frame by frame.

Every frame carries a random valid command (uniform pattern, uniform valid code per used
field), seeded. Independent errors flip every transmitted bit (sync, codeword and guard) with
probability ``ber``; a burst of ``L`` bits is a window of ``L`` consecutive codeword bits at a
uniform position in which every bit flips with probability 1/2.

Success means the frame is accepted and carries the command that was sent. With bounded
distance decoding that happens exactly when the sync word has at most 2 wrong bits and the
codeword at most T, so the exact prediction is ``P(sync ok) * P(<= T errors in n bits)``
(:func:`analytic_frame_success`). The paper's curve (and the research note's 0.964 at BER
1e-2 for T = 2) is the codeword term alone (:func:`analytic_success`); both are reported.
"""

from __future__ import annotations

import csv
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Final, Literal, TextIO

import numpy as np
from numpy.typing import NDArray

from analysis.efficiency import whole_frame_efficiency
from codec import (
    DEFAULT_SYNC_TOLERANCE,
    DICTIONARY,
    FIELD_BITS,
    FIELDS_PER_FRAME,
    GUARD_BITS,
    MESSAGE_BITS,
    SYNC_BITS,
    SYNC_WORD,
    BCHCode,
    CommandDictionary,
    binomial_cdf,
    frame_success_probability,
)
from codec import batch as codec_batch

if TYPE_CHECKING:
    from matplotlib.axes import Axes

U8 = NDArray[np.uint8]
U64 = NDArray[np.uint64]
Bool = NDArray[np.bool_]

#: Message bits of every code (pattern ID 4 + six 8-bit fields + CRC-4).
K: Final = MESSAGE_BITS
#: Our field: GF(2^8), so ``BCHCode(T)`` has ``r = 8T`` parity bits and ``n = 56 + 8T``.
M_FIELD: Final = 8
#: The paper's "m is 7 for 56-bit payload" (inconsistent with its own n - k = 16 at T = 2).
PAPER_M: Final = 7
#: The code of the real frame.
REAL_T: Final = 2
TS: Final = (1, 2, 3, 4)
#: 1-2-3-5 per decade from 1e-4 to 1e-1: log-spaced, and the research note's BERs are points.
BERS: Final = (
    1e-4, 2e-4, 3e-4, 5e-4, 1e-3, 2e-3, 3e-3, 5e-3, 1e-2, 2e-2, 3e-2, 5e-2, 1e-1,
)  # fmt: skip
#: The paper's operating point quoted in the research note: T = 2, BER 1e-2, success 0.964.
PAPER_POINT: Final = (1e-2, 0.964)
#: Where ``nemesys analyze ber`` writes by default (the results page's image directory).
DEFAULT_OUT_DIR: Final = Path(__file__).resolve().parents[1] / "docs" / "results"
#: Two-sided 95 % normal quantile of the Wilson intervals.
Z95: Final = 1.959963984540054

ErrorKind = Literal["independent", "burst"]


# --- results ------------------------------------------------------------------------------


@dataclass(frozen=True)
class SuccessPoint:
    """Decode success at one BER for one T.

    ``analytic`` is the paper's curve, P(at most T errors among the n codeword bits);
    ``analytic_frame`` multiplies it by P(at most 2 of the 24 sync bits wrong), the exact
    prediction for the Monte Carlo, which flips the sync bits too.
    """

    t: int
    n: int
    ber: float
    frames: int
    successes: int
    rate: float
    ci_low: float
    ci_high: float
    analytic: float
    analytic_frame: float


@dataclass(frozen=True)
class Efficiency:
    """Coding efficiency of the T-error-correcting code with k = 56.

    ``paper_efficiency`` is the paper's k / (k + 2mT) with our field's m = 8;
    ``paper_efficiency_m7`` the same with the paper's stated m = 7 (0.667 at T = 2);
    ``code_rate`` is the true k / n; ``frame_efficiency`` the whole-frame efficiency, payload
    bits (52) / frame bits (sync + n + guard), as defined once in :mod:`analysis.efficiency`.
    """

    t: int
    n: int
    k: int
    m: int
    paper_efficiency: float
    code_rate: float
    frame_efficiency: float
    paper_efficiency_m7: float


@dataclass(frozen=True)
class WrongAcceptance:
    """How often a frame is accepted as a different valid command.

    ``errors`` is ``"independent"`` (``level`` = BER over every frame bit) or ``"burst"``
    (``level`` = burst length in codeword bits); ``crc`` says whether the receiver checks the
    CRC-4 (without it every other check stays). ``ci_high`` is the Wilson 95 % upper bound
    (3.84 / frames when nothing was seen).
    """

    t: int
    errors: ErrorKind
    level: float
    crc: bool
    frames: int
    wrong: int
    rate: float
    ci_high: float


@dataclass(frozen=True)
class BerReport:
    points: tuple[SuccessPoint, ...]
    efficiency: tuple[Efficiency, ...]
    wrong: tuple[WrongAcceptance, ...]
    csv_path: Path
    png_path: Path
    wrong_csv_path: Path
    seconds: float


# --- run sizes ----------------------------------------------------------------------------


@dataclass(frozen=True)
class BerConfig:
    """What to simulate, and how many frames.

    T = 2 goes through :mod:`codec.batch` (about 1 s per 10^6 frames); the other codes through
    the numpy Berlekamp-Massey decoder, several times slower, so they get fewer frames.
    """

    name: str
    success_frames_real: int
    success_frames_other: int
    wrong_frames_real: int
    wrong_frames_other: int
    ts: tuple[int, ...] = TS
    bers: tuple[float, ...] = BERS
    wrong_ts: tuple[int, ...] = TS
    wrong_bers: tuple[float, ...] = (3e-3, 1e-2, 3e-2, 1e-1)
    burst_lengths: tuple[int, ...] = (8, 16, 24)

    def success_frames(self, t: int) -> int:
        return self.success_frames_real if t == REAL_T else self.success_frames_other

    def wrong_frames(self, t: int) -> int:
        return self.wrong_frames_real if t == REAL_T else self.wrong_frames_other


FULL: Final = BerConfig("full", 2_000_000, 1_000_000, 20_000_000, 2_000_000)
QUICK: Final = BerConfig("quick", 200_000, 30_000, 2_000_000, 100_000)
#: For the test suite: a few seconds, still 50 000 T = 2 frames per BER (sd 0.0008 at 0.964).
TEST: Final = BerConfig(
    "test", 50_000, 10_000, 200_000, 10_000, wrong_bers=(1e-2, 1e-1), burst_lengths=(8, 24)
)


# --- analytic -----------------------------------------------------------------------------


def code_length(t: int) -> int:
    """n of ``BCHCode(t)`` over GF(2^8) with k = 56: 56 + 8t (checked against the codec)."""
    return K + M_FIELD * t


def frame_bits(t: int) -> int:
    """Sync word + codeword + guard."""
    return SYNC_BITS + code_length(t) + GUARD_BITS


def analytic_success(t: int, ber: float) -> float:
    """The paper's curve: P(at most t errors among the n = 56 + 8t codeword bits)."""
    return binomial_cdf(code_length(t), t, ber)


def analytic_sync(ber: float, tolerance: int = DEFAULT_SYNC_TOLERANCE) -> float:
    """P(the sync word arrives with at most ``tolerance`` wrong bits)."""
    return binomial_cdf(SYNC_BITS, tolerance, ber)


def analytic_frame_success(t: int, ber: float) -> float:
    """Exact success probability of the simulated frame: sync term times codeword term
    (:func:`codec.frame_success_probability`, the one place it is computed)."""
    return frame_success_probability(ber, codeword_bits=code_length(t), t=t)


def wilson(successes: int, trials: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion."""
    if trials <= 0:
        return 0.0, 1.0
    p = successes / trials
    z2 = z * z
    denom = 1.0 + z2 / trials
    centre = (p + z2 / (2 * trials)) / denom
    half = z * math.sqrt(p * (1 - p) / trials + z2 / (4 * trials * trials)) / denom
    low = 0.0 if successes == 0 else max(0.0, centre - half)
    high = 1.0 if successes == trials else min(1.0, centre + half)
    return low, high


def efficiency_table(ts: Sequence[int] = TS) -> tuple[Efficiency, ...]:
    out = []
    for t in ts:
        n = code_length(t)
        out.append(
            Efficiency(
                t=t,
                n=n,
                k=K,
                m=M_FIELD,
                paper_efficiency=K / (K + 2 * M_FIELD * t),
                code_rate=K / n,
                frame_efficiency=whole_frame_efficiency(n),
                paper_efficiency_m7=K / (K + 2 * PAPER_M * t),
            )
        )
    return tuple(out)


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


# --- frames of any T ------------------------------------------------------------------------

_SYNC_BYTES: Final = np.array(
    [(SYNC_WORD >> 16) & 0xFF, (SYNC_WORD >> 8) & 0xFF, SYNC_WORD & 0xFF], dtype=np.uint8
)
_POPCOUNT8: Final = np.array([bin(i).count("1") for i in range(256)], dtype=np.uint8)
_SYNC_BYTE_COUNT: Final = SYNC_BITS // 8
_MSG_BYTES: Final = K // 8


def _bytes_to_u64(columns: U8) -> U64:
    """Up to 8 big-endian bytes per row as uint64."""
    wide = np.zeros((columns.shape[0], 8), dtype=np.uint8)
    wide[:, 8 - columns.shape[1] :] = columns
    out: U64 = wide.view(">u8").reshape(-1).astype(np.uint64)
    return out


@dataclass(frozen=True)
class Decision:
    """Per-frame receiver outcome, before the CRC and dictionary checks."""

    sync_errors: NDArray[np.uint8]
    bch_ok: Bool
    message: U64


class BitFrames:
    """The frame layout with ``BCHCode(t)``, packed MSB first like :meth:`codec.Frame.to_bytes`.

    Bytes 0-2 sync word, then the 7 message bytes, the ``t`` parity bytes and the 4 guard
    bits (plus zero padding to a whole byte). Decoding is :meth:`codec.BCHCode.decode`
    vectorised: remainder by byte tables, S_1..S_2t, Berlekamp-Massey, Chien search over the
    ``n`` positions, accepted when deg(Lambda) <= t and Lambda has exactly deg(Lambda) roots.
    """

    def __init__(self, t: int) -> None:
        code = BCHCode(t, k=K, m=M_FIELD)
        if code.n != code_length(t) or code.r % 8:
            raise ValueError(f"BCHCode({t}) is not byte-aligned: n = {code.n}")
        self.code = code
        self.t = t
        self.n = code.n
        self.frame_bits = frame_bits(t)
        self.frame_bytes = (self.frame_bits + 7) // 8
        self.cw_bytes = code.n // 8
        self.parity_bytes = code.r // 8
        self._parity_t = np.array(code.parity_tables, dtype=np.uint64)
        self._remainder_t = np.array(code.remainder_tables, dtype=np.uint64)
        field_ = code.field
        order = field_.order
        exp = np.array(field_.exp[:order], dtype=np.intp)
        log = np.array(field_.log, dtype=np.intp)
        values = np.arange(256)
        mul = exp[(log[:, None] + log[None, :]) % order].astype(np.uint8)
        mul[0, :] = 0
        mul[:, 0] = 0
        self._mul: U8 = mul
        inv = exp[(-log) % order].astype(np.uint8)
        inv[0] = 0
        self._inv: U8 = inv
        self._square: U8 = mul[values, values]
        # Column c of the codeword (0 = sent first) is the coefficient of x^(n-1-c).
        degrees = self.n - 1 - np.arange(self.n)
        # Odd syndromes S_j, j = 1, 3, .., 2t-1, by byte tables over the codeword bytes.
        self._syndrome_t = np.zeros((t, self.cw_bytes, 256), dtype=np.uint8)
        for u in range(t):
            j = 2 * u + 1
            for b in range(self.cw_bytes):
                units = [int(exp[(j * degrees[8 * b + q]) % order]) for q in range(8)]
                table = self._syndrome_t[u, b]
                for v in range(1, 256):
                    low = v & -v
                    q = 7 - (low.bit_length() - 1)  # bit 7 of the byte is its column 0
                    table[v] = table[v ^ low] ^ units[q]
        # Chien: the power alpha^(-j * degree) that multiplies Lambda_j at each column.
        self._chien = np.array([exp[(-j * degrees) % order] for j in range(t + 1)], dtype=np.uint8)

    def encode(self, messages: U64) -> U8:
        """Packed frames for 56-bit messages."""
        messages = np.asarray(messages, dtype=np.uint64)
        n = messages.shape[0]
        msg_bytes = messages.astype(">u8").view(np.uint8).reshape(n, 8)[:, 8 - _MSG_BYTES :]
        parity = np.zeros(n, dtype=np.uint64)
        for b in range(_MSG_BYTES):
            parity ^= self._parity_t[b][msg_bytes[:, b]]
        frames = np.zeros((n, self.frame_bytes), dtype=np.uint8)
        frames[:, :_SYNC_BYTE_COUNT] = _SYNC_BYTES
        start = _SYNC_BYTE_COUNT
        frames[:, start : start + _MSG_BYTES] = msg_bytes
        start += _MSG_BYTES
        for b in range(self.parity_bytes):
            shift = np.uint64(8 * (self.parity_bytes - 1 - b))
            frames[:, start + b] = ((parity >> shift) & np.uint64(0xFF)).astype(np.uint8)
        return frames

    def decode(self, frames: U8) -> Decision:
        """Sync distance, BCH outcome and corrected message of every frame."""
        sync_errors = _POPCOUNT8[frames[:, 0] ^ _SYNC_BYTES[0]]
        for b in range(1, _SYNC_BYTE_COUNT):
            sync_errors = sync_errors + _POPCOUNT8[frames[:, b] ^ _SYNC_BYTES[b]]
        cw = frames[:, _SYNC_BYTE_COUNT : _SYNC_BYTE_COUNT + self.cw_bytes]
        remainder = np.zeros(frames.shape[0], dtype=np.uint64)
        for b in range(self.cw_bytes):
            remainder ^= self._remainder_t[b][cw[:, b]]
        message = _bytes_to_u64(cw[:, :_MSG_BYTES])
        bch_ok = remainder == 0
        dirty = np.flatnonzero(~bch_ok)
        if dirty.size:
            ok, flips = self._correct(cw[dirty])
            bch_ok[dirty] = ok
            message[dirty] ^= flips
        return Decision(sync_errors.astype(np.uint8), bch_ok, message)

    def _correct(self, cw: U8) -> tuple[Bool, U64]:
        """Berlekamp-Massey + Chien for words with a non-zero syndrome: (ok, message flips)."""
        t, mul = self.t, self._mul
        rows = cw.shape[0]
        synd = np.zeros((rows, 2 * t), dtype=np.uint8)
        for u in range(t):
            s = np.zeros(rows, dtype=np.uint8)
            for b in range(self.cw_bytes):
                s ^= self._syndrome_t[u, b][cw[:, b]]
            synd[:, 2 * u] = s
        for j in range(2, 2 * t + 1, 2):  # binary code: S_2j = S_j^2
            synd[:, j - 1] = self._square[synd[:, j // 2 - 1]]
        lam = self._berlekamp_massey(synd)
        width = lam.shape[1]
        nonzero = lam != 0
        degree = width - 1 - np.argmax(nonzero[:, ::-1], axis=1)
        value = np.broadcast_to(lam[:, :1], (rows, self.n)).copy()
        for j in range(1, t + 1):
            value ^= mul[lam[:, j]][:, self._chien[j]]
        roots = value == 0
        ok: Bool = (degree <= t) & (roots.sum(axis=1) == degree) & ~nonzero[:, t + 1 :].any(1)
        flips = _bytes_to_u64(np.packbits(roots[:, :K], axis=1))
        flips[~ok] = 0
        return ok, flips

    def _berlekamp_massey(self, synd: U8) -> U8:
        """Lambda (constant term first) of every row; the codec's recurrence, row-parallel."""
        t, mul, inv = self.t, self._mul, self._inv
        rows = synd.shape[0]
        width = 4 * t + 2  # deg(x^shift * prev) <= 2t + 2t + 1 never overflows
        cols = np.arange(width)
        lam = np.zeros((rows, width), dtype=np.uint8)
        lam[:, 0] = 1
        prev = lam.copy()
        length = np.zeros(rows, dtype=np.intp)
        shift = np.ones(rows, dtype=np.intp)
        prev_disc = np.ones(rows, dtype=np.uint8)
        for step in range(2 * t):
            disc = synd[:, step].copy()
            for i in range(1, step + 1):
                disc ^= mul[lam[:, i], synd[:, step - i]]
            nz = disc != 0
            coef = mul[disc, inv[prev_disc]]
            src = cols[None, :] - shift[:, None]
            moved = np.take_along_axis(prev, np.clip(src, 0, width - 1), axis=1)
            moved[src < 0] = 0
            updated = lam ^ mul[coef[:, None], moved]
            change = nz & (2 * length <= step)
            prev = np.where(change[:, None], lam, prev)
            prev_disc = np.where(change, disc, prev_disc)
            length = np.where(change, step + 1 - length, length)
            shift = np.where(change, 1, shift + 1)
            lam = np.where(nz[:, None], updated, lam)
        return lam


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


# --- progress ---------------------------------------------------------------------------------


@dataclass
class ProgressBar:
    """``\\r[#########...........] 45 %  12 s  T=3 BER 2e-02`` on a text stream."""

    stream: TextIO | None
    total: float
    width: int = 30
    done: float = 0.0
    label: str = ""
    _shown: int = -1
    _drawn: float = -math.inf
    _start: float = field(default_factory=time.perf_counter)

    def advance(self, amount: float) -> None:
        self.done += amount
        self._draw()

    def advancer(self, weight: float) -> Callable[[int], None]:
        """``advance(weight * frames)`` as a callback taking the frames done."""

        def advance(frames: int) -> None:
            self.advance(weight * frames)

        return advance

    def describe(self, label: str) -> None:
        self.label = label
        self._draw(force=True)

    def _draw(self, force: bool = False) -> None:
        if self.stream is None:
            return
        pct = min(100, int(100 * self.done / self.total)) if self.total > 0 else 100
        now = time.perf_counter()
        if pct == self._shown and not (force and now - self._drawn >= 0.25):
            return
        self._shown = pct
        self._drawn = now
        filled = self.width * pct // 100
        bar = "#" * filled + "." * (self.width - filled)
        elapsed = now - self._start
        self.stream.write(f"\r[{bar}] {pct:3d} %  {elapsed:4.0f} s  {self.label:<28}")
        self.stream.flush()

    def close(self) -> None:
        if self.stream is None:
            return
        self.done = self.total
        self.label = "done"
        self._drawn = -math.inf
        self._draw(force=True)
        self.stream.write("\n")
        self.stream.flush()


#: Rough time per frame against T = 2 (codec.batch), for the progress bar only.
_COST: Final = {1: 1.5, 2: 1.0, 3: 3.5, 4: 5.0}


def _seed(seed: int, *key: int) -> np.random.Generator:
    return np.random.default_rng([seed, *key])


def analyze_config(
    out_dir: Path,
    config: BerConfig,
    *,
    seed: int = 0,
    progress: TextIO | None = None,
) -> BerReport:
    """:func:`analyze` with explicit run sizes (the test suite uses :data:`TEST`)."""
    start = time.perf_counter()
    commands = CommandTables()
    sims = {t: Simulator(t, commands) for t in sorted({*config.ts, *config.wrong_ts})}

    def cost(t: int) -> float:
        return _COST.get(t, 6.0)

    wrong_levels: list[tuple[ErrorKind, float]] = [("independent", b) for b in config.wrong_bers]
    wrong_levels += [("burst", float(length)) for length in config.burst_lengths]
    total = sum(cost(t) * config.success_frames(t) * len(config.bers) for t in config.ts)
    total += sum(cost(t) * config.wrong_frames(t) * len(wrong_levels) for t in config.wrong_ts)
    bar = ProgressBar(progress, total)

    points: list[SuccessPoint] = []
    for t in config.ts:
        sim = sims[t]
        for i, ber in enumerate(config.bers):
            bar.describe(f"T={t} BER {ber:.0e}")
            c = sim.run(
                config.success_frames(t),
                "independent",
                ber,
                _seed(seed, 1, t, i),
                bar.advancer(cost(t)),
            )
            low, high = wilson(c.success, c.frames)
            points.append(
                SuccessPoint(
                    t=t,
                    n=sim.n,
                    ber=ber,
                    frames=c.frames,
                    successes=c.success,
                    rate=c.success / c.frames,
                    ci_low=low,
                    ci_high=high,
                    analytic=analytic_success(t, ber),
                    analytic_frame=analytic_frame_success(t, ber),
                )
            )

    wrong: list[WrongAcceptance] = []
    for t in config.wrong_ts:
        sim = sims[t]
        for i, (kind, level) in enumerate(wrong_levels):
            what = f"BER {level:.0e}" if kind == "independent" else f"burst {level:.0f}"
            bar.describe(f"T={t} wrong, {what}")
            c = sim.run(
                config.wrong_frames(t),
                kind,
                level,
                _seed(seed, 2, t, i),
                bar.advancer(cost(t)),
            )
            for crc, count in ((True, c.wrong_crc), (False, c.wrong_nocrc)):
                wrong.append(
                    WrongAcceptance(
                        t=t,
                        errors=kind,
                        level=level,
                        crc=crc,
                        frames=c.frames,
                        wrong=count,
                        rate=count / c.frames,
                        ci_high=wilson(count, c.frames)[1],
                    )
                )
    bar.close()

    out_dir.mkdir(parents=True, exist_ok=True)
    csv_path = out_dir / "ber.csv"
    wrong_csv_path = out_dir / "ber_wrong.csv"
    png_path = out_dir / "ber.png"
    efficiency = efficiency_table(config.ts)
    write_csv(csv_path, SUCCESS_COLUMNS, points)
    write_csv(wrong_csv_path, WRONG_COLUMNS, wrong)
    plot(png_path, points, efficiency, wrong)
    return BerReport(
        points=tuple(points),
        efficiency=efficiency,
        wrong=tuple(wrong),
        csv_path=csv_path,
        png_path=png_path,
        wrong_csv_path=wrong_csv_path,
        seconds=time.perf_counter() - start,
    )


def analyze(
    out_dir: Path, *, quick: bool = False, seed: int = 0, progress: TextIO | None = None
) -> BerReport:
    """Run the BER analysis, write ``ber.csv``, ``ber_wrong.csv`` and ``ber.png`` into
    ``out_dir`` and return the figures. ``quick``: about 10x fewer frames (under a minute)."""
    return analyze_config(out_dir, QUICK if quick else FULL, seed=seed, progress=progress)


# --- output -----------------------------------------------------------------------------------

SUCCESS_COLUMNS: Final = (
    "t", "n", "ber", "frames", "successes", "rate", "ci_low", "ci_high", "analytic",
    "analytic_frame",
)  # fmt: skip
WRONG_COLUMNS: Final = ("t", "errors", "level", "crc", "frames", "wrong", "rate", "ci_high")


def _cell(value: object) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return f"{value:.9g}"
    return str(value)


def write_csv(path: Path, columns: Sequence[str], rows: Sequence[object]) -> None:
    """One line per row: its attributes named by ``columns``, under a header of them."""
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(columns)
        for row in rows:
            writer.writerow([_cell(getattr(row, col)) for col in columns])


_COLOURS: Final = {1: "tab:blue", 2: "tab:red", 3: "tab:green", 4: "tab:purple"}


def plot(
    path: Path,
    points: Sequence[SuccessPoint],
    efficiency: Sequence[Efficiency],
    wrong: Sequence[WrongAcceptance],
) -> None:
    """Success vs BER (the paper's figure, redone), then wrong-command acceptance for
    independent and for burst errors when there are any."""
    from matplotlib.figure import Figure  # no pyplot: no global state, no GUI backend

    kinds = [k for k in ("independent", "burst") if any(w.errors == k for w in wrong)]
    panels = 1 + len(kinds)
    fig = Figure(figsize=(6.2 * panels, 4.8), layout="constrained")
    axes = fig.subplots(1, panels, squeeze=False)[0]
    _success_panel(axes[0], points, efficiency)
    for axis, kind in zip(axes[1:], kinds, strict=True):
        _wrong_panel(axis, [w for w in wrong if w.errors == kind])
        if kind == "independent":
            axis.set_xscale("log")
            axis.set_xlabel("bit error rate (independent errors, every frame bit)")
            axis.set_title("Wrong command accepted (v: 95 % bound, none seen)")
        else:
            axis.set_xlabel("burst length in the codeword (bits, each flipped w.p. 1/2)")
            axis.set_title("Wrong command accepted, burst errors")
    fig.savefig(path, dpi=120)


def _success_panel(
    ax: Axes, points: Sequence[SuccessPoint], efficiency: Sequence[Efficiency]
) -> None:
    eff = {e.t: e for e in efficiency}
    bers = [p.ber for p in points]
    lo, hi = math.log10(min(bers)), math.log10(max(bers))
    if hi - lo < 0.5:  # a single BER (or a narrow range): show a decade around it
        lo, hi = (lo + hi) / 2 - 0.5, (lo + hi) / 2 + 0.5
    fine = np.logspace(lo, hi, 200)
    for t in sorted({p.t for p in points}):
        colour = _COLOURS.get(t, "black")
        mine = sorted((p for p in points if p.t == t), key=lambda p: p.ber)
        label = f"T={t}, n={mine[0].n}"
        e = eff.get(t)
        if e is not None:
            label += f" (k/n {e.code_rate:.3f}, paper eff. {e.paper_efficiency_m7:.3f})"
        ax.plot(fine, [analytic_frame_success(t, b) for b in fine], color=colour, lw=1.2)
        ax.plot(fine, [analytic_success(t, b) for b in fine], color=colour, lw=0.8, ls=":")
        err = [
            [max(0.0, p.rate - p.ci_low) for p in mine],
            [max(0.0, p.ci_high - p.rate) for p in mine],
        ]
        ax.errorbar(
            [p.ber for p in mine],
            [p.rate for p in mine],
            yerr=err,
            fmt="o",
            ms=3.5,
            color=colour,
            capsize=2,
            label=label,
        )
    ber0, rate0 = PAPER_POINT
    ax.axvline(ber0, color="grey", lw=0.6, ls="--")
    paper = f"paper / research: T=2, BER {ber0:g}: {rate0}"
    ax.plot([ber0], [rate0], marker="*", ms=12, color="gold", mec="black", ls="", label=paper)
    ax.plot([], [], color="black", lw=1.2, label="analytic, P(sync ok) x P(<= T in n)")
    ax.plot([], [], color="black", lw=0.8, ls=":", label="analytic, P(<= T in n) (paper)")
    ax.set_xscale("log")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("bit error rate")
    ax.set_ylabel("decoding success rate")
    ax.set_title("Decoding success vs BER (Monte Carlo, Wilson 95 %)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="lower left")


def _wrong_panel(ax: Axes, rows: Sequence[WrongAcceptance]) -> None:
    """Measured rates with Wilson bars; a 'v' at the 95 % upper bound where none was seen."""
    for t in sorted({w.t for w in rows}):
        colour = _COLOURS.get(t, "black")
        for crc, style in ((True, "-"), (False, "--")):
            mine = sorted((w for w in rows if w.t == t and w.crc == crc), key=lambda w: w.level)
            label = f"T={t} {'with' if crc else 'without'} CRC-4"
            seen = [w for w in mine if w.wrong]
            xs, ys = [w.level for w in seen], [w.rate for w in seen]
            ax.plot(xs, ys, color=colour, ls=style, lw=1.0, label=label)
            for w in mine:
                if not w.wrong:
                    ax.plot([w.level], [w.ci_high], marker="v", ms=6, color=colour)
                    continue
                low = wilson(w.wrong, w.frames)[0]
                ax.errorbar(
                    [w.level],
                    [w.rate],
                    yerr=[[max(0.0, w.rate - low)], [max(0.0, w.ci_high - w.rate)]],
                    fmt="o" if crc else "s",
                    ms=3.5,
                    color=colour,
                    mfc=colour if crc else "white",
                    capsize=2,
                )
    ax.set_yscale("log")
    ax.set_ylabel("wrong command accepted, per frame")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")


def _rate_ci(p: SuccessPoint) -> str:
    return f"{p.rate:.5f} [{p.ci_low:.5f}, {p.ci_high:.5f}]"


def format_report(report: BerReport) -> str:
    """The tables ``nemesys analyze ber`` prints."""
    lines: list[str] = []
    ts = sorted({p.t for p in report.points})
    bers = sorted({p.ber for p in report.points})
    by_key = {(p.t, p.ber): p for p in report.points}
    lines.append(
        "Decode success vs BER (Monte Carlo through the frame; analytic = "
        "P(sync ok) x P(<= T errors in n))"
    )
    lines.append("        " + "".join(f"  {f'T={t}, n={code_length(t)}':<19}" for t in ts))
    lines.append("BER     " + "  MC       analytic  " * len(ts))
    for ber in bers:
        cells = []
        for t in ts:
            p = by_key.get((t, ber))
            cells.append(f"  {p.rate:.6f} {p.analytic_frame:.6f}  " if p else " " * 21)
        lines.append(f"{ber:<8.0e}" + "".join(cells).rstrip())
    frames = sorted({(p.t, p.frames) for p in report.points})
    lines.append("frames per point: " + ", ".join(f"T={t} {n:,}" for t, n in frames))
    ber0, rate0 = PAPER_POINT
    p0 = by_key.get((REAL_T, ber0))
    if p0 is not None:
        lines.append(
            f"T=2 at BER {ber0:g}: {_rate_ci(p0)} (Wilson 95 %, {p0.frames:,} frames); "
            f"analytic {p0.analytic_frame:.6f} with the sync term, {p0.analytic:.6f} codeword "
            f"only (paper / research: {rate0})"
        )
    lines.append("")
    lines.append("Coding efficiency (k = 56)")
    lines.append("T   n   paper k/(k+2mT) m=8   paper's m=7   code rate k/n   frame 52/(n+28)")
    for e in report.efficiency:
        lines.append(
            f"{e.t}  {e.n:>3}   {e.paper_efficiency:18.4f}   {e.paper_efficiency_m7:11.4f}   "
            f"{e.code_rate:13.4f}   {e.frame_efficiency:14.4f}"
        )
    lines.append(
        "(the paper: k/(k+2mT) with m = 7, but n - k = 16 at T = 2; a binary BCH code over "
        "GF(2^m) has at most mT parity bits, here exactly 8T)"
    )
    if report.wrong:
        lines.append("")
        lines.append("Wrong command accepted (per frame; '<' = none seen, Wilson 95 % upper bound)")
        lines.append("T  errors        level       frames      with CRC-4            without CRC-4")
        keys = sorted({(w.t, w.errors != "independent", w.errors, w.level) for w in report.wrong})
        by_w = {(w.t, w.errors, w.level, w.crc): w for w in report.wrong}
        for t, _, kind, level in keys:
            cells = []
            for crc in (True, False):
                w = by_w[(t, kind, level, crc)]
                if w.wrong:
                    cells.append(f"{w.rate:9.2e} ({w.wrong:>6})")
                else:
                    cells.append(f"< {w.ci_high:7.1e} (     0)")
            lvl = f"{level:.0e}" if kind == "independent" else f"{level:.0f} bits"
            frames_n = by_w[(t, kind, level, True)].frames
            lines.append(f"{t}  {kind:<12}  {lvl:<9} {frames_n:>10,}      {cells[0]}    {cells[1]}")
    lines.append("")
    lines.append(f"wrote {report.csv_path}")
    lines.append(f"wrote {report.wrong_csv_path}")
    lines.append(f"wrote {report.png_path}")
    lines.append(f"{report.seconds:.1f} s")
    return "\n".join(lines) + "\n"
