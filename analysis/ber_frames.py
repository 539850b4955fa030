"""The frame layout of ``nemesys analyze ber`` for any T, with a numpy BCH decoder.

T = 2 is the real frame and goes through :mod:`codec.batch`; T = 1, 3, 4 use the same layout
with that code's parity: sync word (24) + the ``n = 56 + 8T`` bit codeword of ``BCHCode(T)``
over GF(2^8) + 4 guard bits. :class:`BitFrames` encodes them and decodes them with a numpy
transcription of :meth:`codec.BCHCode.decode` (syndromes, Berlekamp-Massey, Chien search over
the shortened length, the same acceptance rule), many frames at a time.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from analysis.ber_analytic import M_FIELD, K, code_length, frame_bits
from codec import SYNC_BITS, SYNC_WORD, BCHCode

U8 = NDArray[np.uint8]
U64 = NDArray[np.uint64]
Bool = NDArray[np.bool_]

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
