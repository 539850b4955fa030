"""One-way delivery arithmetic: how likely a frame, and r copies of it, reach the vehicle.

A frame decodes when its :data:`SYNC_BITS` = 24 header bits (preamble + delimiter) have at
most the receiver's sync tolerance (:data:`DEFAULT_SYNC_TOLERANCE` = 2) wrong and its
:data:`CODEWORD_BITS` = 72-bit codeword at most ``t`` = 2. At an independent bit-error rate
``p``::

    P1 = P(Bin(24, p) <= 2) * P(Bin(72, p) <= 2)

(0.9625 at p = 1e-2), the analytic frame curve of ``docs/results.md``. With ``r`` copies spaced
in time (longer than a burst, so their errors are independent) the vehicle gets at least one::

    P(delivered) = 1 - (1 - P1)^r

A frame the link loses whole (probability ``loss``) decodes with probability 0, so ``P1`` is
scaled by ``1 - loss``. This module is the one place these numbers are computed: the console's
choice of ``r``, the ``p_delivered`` of every record and the BER analysis all call it.
"""

from __future__ import annotations

import math

from codec._frame import CODE, CODEWORD_BITS, DEFAULT_SYNC_TOLERANCE, SYNC_BITS

TYPE_CHECKING = False
if TYPE_CHECKING:  # the onboard path imports no typing (tests/codec/test_imports.py)
    from typing import Final

#: Largest number of copies of one command (the operator's ``copies`` range is 1..20).
MAX_COPIES: Final = 20
#: Largest bit-error rate (at 0.5 a bit carries no information; the emulated channel goes
#: that far, a real link's ``link_ber`` setting stops short of it).
MAX_BER: Final = 0.5


def _check_ber(ber: float) -> None:
    if isinstance(ber, bool) or not isinstance(ber, int | float) or not 0 <= ber <= MAX_BER:
        raise ValueError(f"ber must be a number in [0, {MAX_BER}], got {ber!r}")


def binomial_cdf(n: int, k: int, p: float) -> float:
    """P(Binomial(n, p) <= k)."""
    if k < 0:
        return 0.0
    if k >= n:
        return 1.0
    q = 1.0 - p
    return math.fsum(math.comb(n, i) * p**i * q ** (n - i) for i in range(k + 1))


def frame_success_probability(
    ber: float,
    *,
    loss: float = 0.0,
    codeword_bits: int = CODEWORD_BITS,
    t: int = CODE.t,
    sync_bits: int = SYNC_BITS,
    sync_tolerance: int = DEFAULT_SYNC_TOLERANCE,
) -> float:
    """P1: one frame, sent at bit-error rate ``ber`` (and whole-frame ``loss``), decodes.

    ``codeword_bits`` and ``t`` describe another BCH code (the BER analysis sweeps t = 1..4).

    Raises:
        ValueError: ``ber`` outside [0, 0.5] or ``loss`` outside [0, 1].
    """
    _check_ber(ber)
    if not 0.0 <= loss <= 1.0:
        raise ValueError(f"loss must be in [0, 1], got {loss!r}")
    sync = binomial_cdf(sync_bits, sync_tolerance, ber)
    codeword = binomial_cdf(codeword_bits, t, ber)
    return (1.0 - loss) * sync * codeword


def delivery_probability(ber: float, copies: int, *, loss: float = 0.0) -> float:
    """P(at least one of ``copies`` independent copies decodes): 1 - (1 - P1)^copies.

    Raises:
        ValueError: ``copies`` negative, or ``ber`` / ``loss`` out of range.
    """
    if isinstance(copies, bool) or not isinstance(copies, int) or copies < 0:
        raise ValueError(f"copies must be an int >= 0, got {copies!r}")
    p1 = frame_success_probability(ber, loss=loss)
    return 1.0 - (1.0 - p1) ** copies


def copies_for(
    ber: float, target: float, *, loss: float = 0.0, minimum: int = 1, maximum: int = MAX_COPIES
) -> int:
    """The fewest copies (at least ``minimum``) that reach ``target`` delivery probability;
    ``maximum`` when even that many do not (the caller reports the probability it reaches).

    Raises:
        ValueError: ``target`` outside (0, 1), ``minimum`` / ``maximum`` out of order, or
            ``ber`` / ``loss`` out of range.
    """
    if not 0.0 < target < 1.0:
        raise ValueError(f"target must be in (0, 1), got {target!r}")
    if not 1 <= minimum <= maximum:
        raise ValueError(f"need 1 <= minimum <= maximum, got {minimum}, {maximum}")
    miss = 1.0 - frame_success_probability(ber, loss=loss)
    for r in range(minimum, maximum + 1):
        if 1.0 - miss**r >= target:
            return r
    return maximum
