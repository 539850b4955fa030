"""The analytic side of ``nemesys analyze ber``: the codes' sizes, the closed-form success
curves the Monte Carlo is compared with, Wilson intervals and the coding-efficiency table.

Success means the frame is accepted and carries the command that was sent. With bounded
distance decoding that happens exactly when the sync word has at most 2 wrong bits and the
codeword at most T, so the exact prediction is ``P(sync ok) * P(<= T errors in n bits)``
(:func:`analytic_frame_success`); the paper's curve is the codeword term alone
(:func:`analytic_success`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

from analysis.efficiency import whole_frame_efficiency
from codec import (
    DEFAULT_SYNC_TOLERANCE,
    GUARD_BITS,
    MESSAGE_BITS,
    SYNC_BITS,
    binomial_cdf,
    frame_success_probability,
)

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
#: Two-sided 95 % normal quantile of the Wilson intervals.
Z95: Final = 1.959963984540054


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
