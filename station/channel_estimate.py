"""The link's bit-error rate, estimated online from the vehicle's acknowledgements. Sans-IO.

On a two-way link the onboard agent acknowledges every 100-bit frame it receives
(:mod:`onboard.agent`), and the acknowledgement says what the decoder saw. With the frame's
layout (:mod:`codec._frame`: a 24-bit sync word of preamble and delimiter, tolerated with up to
``sync_tolerance`` = 2 wrong bits; a BCH(72, 56) codeword correcting ``t`` = 2; 4 guard bits
the receiver ignores) each acknowledgement is one of:

* **decoded** (accepted, or decoded and then refused as ``invalid_plan`` / ``limit_violation``):
  the codeword held exactly ``corrected_bits`` errors (0..t) and the sync word exactly
  ``sync_errors`` (0..tolerance): 96 bits observed exactly. A count the vehicle leaves out is
  known only to be within its section's reach (censored: the section's binomial CDF).
* **not decoded** (every codec reason but ``malformed`` and ``other_vehicle``: ``no_sync``,
  ``uncorrectable``, ``crc_mismatch``, ``unknown_pattern``, ``field_out_of_range``,
  ``unused_field_set``): more than ``tolerance`` sync errors *or* more than ``t`` codeword
  errors, nothing more. The reasons are pooled on purpose: the receiver searches other bit
  offsets after a failed sync, so a frame with 3 sync errors is sometimes reported
  ``uncorrectable`` at another offset, and the station sends only valid frames, so a CRC or
  dictionary failure is a miscorrection of a codeword with more than ``t`` errors. Their union
  is exactly "not (sync <= tolerance and codeword <= t)".
* **says nothing of the channel**: ``malformed`` (not 100 bits: a transport fault, not bit errors),
  ``other_vehicle`` (a fleet's vehicle heard a frame for another: it decoded, but its counts are of
  the addressed frame's longer code, not this layout's), an unknown reason, counts outside the
  code's reach (another code); counted in ``ignored`` and left out.

With independent bit errors at rate ``p`` (``F(n, k; p)`` = P(Binomial(n, p) <= k)) the
log-likelihood of the dive's frames is::

    l(p) = E log p + (B - E) log(1 - p)                 exact counts: E errors in B bits
         + C_cw log F(72, 2; p) + C_sync log F(24, 2; p)    censored counts
         + N log(1 - F(24, 2; p) F(72, 2; p))               frames not decoded

The estimate is its maximum over [0, 0.5] and the 95 % interval the likelihood-ratio set
``2 (l(p_hat) - l(p)) <= chi2_1(0.95)`` (one parameter, so the profile is l itself). Every
piece is log-concave in ``p`` but the last, which rises with ``p``; ``l`` is taken to be
unimodal over the range (the tests compare it with an independent search): ``l`` on a
log-spaced grid of [0, 0.5], a fine grid around its best point, and each end of the interval
where ``l`` crosses the level between the estimate and the nearest grid point below it.

**Lost frames (no acknowledgement) are left out.** The agent acknowledges every frame it
receives, a failed sync included, so under the model a frame that bit errors spoil still
comes back as "not decoded"; a missing acknowledgement is a whole-frame loss (out of range,
the acknowledgement's own path) that says nothing of ``p``, and counting it as an error event
would bias the estimate upwards. A link whose receiver drops frames it cannot sync would
bias it (slightly) downwards: the reason is named where the estimate is shown.

Not modelled: miscorrections the CRC and the dictionary let through (a codeword with more than
``t`` errors accepted with a count <= t: about 1e-5 of frames at p = 1e-2), and bursts (the
errors are assumed independent; a burst looks like a higher ``p``).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from statistics import NormalDist
from typing import Any, Final

import numpy as np
import numpy.typing as npt

from codec import CODE, CODEWORD_BITS, DEFAULT_SYNC_TOLERANCE, SYNC_BITS, RejectReason
from vehicle_contract.codes import INVALID_PLAN, LIMIT_VIOLATION

__all__ = [
    "CONFIDENCE",
    "LAYOUT",
    "MAX_BER",
    "MIN_FRAMES",
    "BerEstimate",
    "ChannelCounts",
    "ChannelEstimator",
    "FrameEvidence",
    "FrameLayout",
    "estimate_ber",
    "evidence_of",
    "log_likelihood",
]

#: The interval's confidence.
CONFIDENCE: Final = 0.95
#: Fewest frames an estimate is given from: below it the chi-square calibration of the
#: likelihood-ratio interval is not trusted (tests/station/test_channel_estimate.py measures
#: its coverage there).
MIN_FRAMES: Final = 10
#: The largest bit-error rate (at 0.5 a bit carries nothing): the top of the search.
MAX_BER: Final = 0.5
#: Reasons of a frame that decoded and was then refused by the agent.
_DECODED_REASONS: Final = frozenset({INVALID_PLAN, LIMIT_VIOLATION})
#: Reasons of a frame the decoder refused (see the module's doc).
#: ``other_vehicle`` is not one: such a frame decoded fine (it was for another vehicle of a fleet).
_NOT_DECODED_REASONS: Final = frozenset(r.value for r in RejectReason) - {
    RejectReason.MALFORMED,
    RejectReason.OTHER_VEHICLE,
}
#: The search grid: 0, then log-spaced up to MAX_BER (1.1 % steps).
_GRID: Final = np.concatenate([[0.0], np.geomspace(1e-10, MAX_BER, 2000)])
#: Points of the fine grids between two points of the search grid (the estimate and each end
#: of the interval to ~3e-5 of their value).
_REFINE_POINTS: Final = 401

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class FrameLayout:
    """What the receiver checks: the sync word and the codeword, and what each tolerates."""

    codeword_bits: int = CODEWORD_BITS
    #: Codeword errors the BCH decoder corrects.
    t: int = CODE.t
    sync_bits: int = SYNC_BITS
    #: Wrong sync bits the receiver tolerates (the onboard agent's receiver: the default).
    sync_tolerance: int = DEFAULT_SYNC_TOLERANCE


#: The NemeSys frame (:mod:`codec._frame`).
LAYOUT: Final = FrameLayout()


@dataclass(frozen=True, slots=True)
class FrameEvidence:
    """What one acknowledgement says of the channel."""

    decoded: bool
    #: Decoded: the codeword's errors (the bits corrected); ``None``: not reported (<= t).
    codeword_errors: int | None = None
    #: Decoded: the sync word's wrong bits; ``None``: not reported (<= the tolerance).
    sync_errors: int | None = None


def _count(value: object, top: int) -> int | bool | None:
    """A reported count in 0..top; ``None`` when not reported; ``False`` when out of reach."""
    if value is None:
        return None
    if type(value) is not int or not 0 <= value <= top:
        return False
    return value


def evidence_of(ack: Mapping[str, Any], layout: FrameLayout = LAYOUT) -> FrameEvidence | None:
    """The channel evidence of an acknowledgement (``None``: it says nothing of the channel)."""
    outcome, reason = ack.get("outcome"), ack.get("reason")
    if outcome == "rejected" and reason in _NOT_DECODED_REASONS:
        return FrameEvidence(decoded=False)
    if outcome != "accepted" and not (outcome == "rejected" and reason in _DECODED_REASONS):
        return None
    codeword = _count(ack.get("corrected_bits"), layout.t)
    sync = _count(ack.get("sync_errors"), layout.sync_tolerance)
    if codeword is False or sync is False:
        return None
    return FrameEvidence(decoded=True, codeword_errors=codeword, sync_errors=sync)


@dataclass(frozen=True, slots=True)
class ChannelCounts:
    """The sufficient statistics of a set of frames (see the module's doc)."""

    decoded: int = 0
    not_decoded: int = 0
    #: Bits whose errors were counted exactly, and the errors among them.
    bits: int = 0
    errors: int = 0
    #: Decoded frames whose codeword (sync) count was not reported.
    codeword_censored: int = 0
    sync_censored: int = 0

    @property
    def frames(self) -> int:
        """Frames the estimate rests on."""
        return self.decoded + self.not_decoded

    def plus(self, evidence: FrameEvidence, layout: FrameLayout = LAYOUT) -> ChannelCounts:
        """These counts and one more frame."""
        if not evidence.decoded:
            return replace(self, not_decoded=self.not_decoded + 1)
        bits, errors = self.bits, self.errors
        cw_cens, sync_cens = self.codeword_censored, self.sync_censored
        if evidence.codeword_errors is None:
            cw_cens += 1
        else:
            bits, errors = bits + layout.codeword_bits, errors + evidence.codeword_errors
        if evidence.sync_errors is None:
            sync_cens += 1
        else:
            bits, errors = bits + layout.sync_bits, errors + evidence.sync_errors
        return ChannelCounts(self.decoded + 1, self.not_decoded, bits, errors, cw_cens, sync_cens)


@dataclass(frozen=True, slots=True)
class BerEstimate:
    """A bit-error rate estimate: ``ber`` in [``low``, ``high``] at ``confidence``."""

    ber: float
    low: float
    high: float
    #: Frames it rests on.
    frames: int
    confidence: float = CONFIDENCE


@functools.cache
def _log_comb(n: int) -> FloatArray:
    return np.array([math.log(math.comb(n, j)) for j in range(n + 1)])


def _cdf_and_tail(n: int, k: int, p: FloatArray) -> tuple[FloatArray, FloatArray]:
    """P(Binomial(n, p) <= k) and P(> k), each summed from its own terms (no cancellation:
    the tail is ~1e-13 at p = 1e-6)."""
    i = np.arange(n + 1, dtype=np.float64)
    log_comb = _log_comb(n)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_p, log_q = np.log(p)[:, None], np.log1p(-p)[:, None]
        # 0 * log 0 is 0 here (the p = 0 row: only i = 0 has mass)
        terms = log_comb + np.where(i == 0, 0.0, i * log_p) + np.where(i == n, 0.0, (n - i) * log_q)
    pmf = np.exp(terms)
    return pmf[:, : k + 1].sum(axis=1), pmf[:, k + 1 :].sum(axis=1)


def log_likelihood(
    counts: ChannelCounts, p: npt.ArrayLike, layout: FrameLayout = LAYOUT
) -> FloatArray:
    """``l(p)`` of the module's doc (up to a constant), at each of ``p`` (in [0, 0.5])."""
    ps = np.atleast_1d(np.asarray(p, dtype=np.float64))
    out = np.zeros_like(ps)
    with np.errstate(divide="ignore"):
        if counts.errors:
            out += counts.errors * np.log(ps)
        if counts.bits > counts.errors:
            out += (counts.bits - counts.errors) * np.log1p(-ps)
        if counts.codeword_censored or counts.sync_censored or counts.not_decoded:
            cw_cdf, cw_tail = _cdf_and_tail(layout.codeword_bits, layout.t, ps)
            sync_cdf, sync_tail = _cdf_and_tail(layout.sync_bits, layout.sync_tolerance, ps)
            if counts.codeword_censored:
                out += counts.codeword_censored * np.log(cw_cdf)
            if counts.sync_censored:
                out += counts.sync_censored * np.log(sync_cdf)
            if counts.not_decoded:
                # 1 - F_sync F_cw: summed from the tails where the product is near 1 (no
                # cancellation at small p), log1p of the product where it is small (the
                # likelihood keeps rising to p = 0.5, not flat in rounding)
                decodes = sync_cdf * cw_cdf
                refused = np.where(
                    decodes < 0.5,
                    np.log1p(-np.minimum(decodes, 0.5)),
                    np.log(sync_tail + sync_cdf * cw_tail),
                )
                out += counts.not_decoded * refused
    return out


def _refine(
    counts: ChannelCounts, a: float, b: float, layout: FrameLayout
) -> tuple[FloatArray, FloatArray]:
    """``l`` on a fine grid from ``a`` to ``b``."""
    ps = np.linspace(a, b, _REFINE_POINTS)
    return ps, log_likelihood(counts, ps, layout)


def _argmax(counts: ChannelCounts, values: FloatArray, layout: FrameLayout) -> tuple[float, float]:
    """(p_hat, l(p_hat)): the grid's best point, then the best of a fine grid between its
    neighbours."""
    best = int(np.argmax(values))
    if best == 0 or best == len(_GRID) - 1:  # on the edge of [0, 0.5]: a boundary maximum
        return float(_GRID[best]), float(values[best])
    ps, fine = _refine(counts, float(_GRID[best - 1]), float(_GRID[best + 1]), layout)
    top = int(np.argmax(fine))
    return float(ps[top]), float(fine[top])


def _crossing(
    counts: ChannelCounts, inside: float, outside: float, level: float, layout: FrameLayout
) -> float:
    """The ``p`` between ``inside`` (l >= level) and ``outside`` (l < level) where l crosses
    ``level``: a fine grid, then linear interpolation between the two points around it."""
    ps, fine = _refine(counts, outside, inside, layout)
    j = int(np.argmax(fine >= level))  # the first point inside, counting from outside
    if j == 0:
        return float(ps[0])
    (p0, p1), (l0, l1) = ps[j - 1 : j + 1], fine[j - 1 : j + 1]
    if not np.isfinite(l0):
        return float(p1)
    return float(p0 + (level - l0) / (l1 - l0) * (p1 - p0))


def chi2_1(confidence: float) -> float:
    """The ``confidence`` quantile of chi-square with one degree of freedom (z^2)."""
    return NormalDist().inv_cdf((1.0 + confidence) / 2.0) ** 2


def estimate_ber(
    counts: ChannelCounts, confidence: float = CONFIDENCE, layout: FrameLayout = LAYOUT
) -> BerEstimate | None:
    """The maximum-likelihood bit-error rate and its likelihood-ratio interval; ``None`` when
    there is no frame.

    Raises:
        ValueError: ``confidence`` outside (0, 1).
    """
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), got {confidence!r}")
    if counts.frames == 0:
        return None
    values = log_likelihood(counts, _GRID, layout)
    p_hat, top = _argmax(counts, values, layout)
    level = top - chi2_1(confidence) / 2.0
    outside = values < level
    # the last grid point outside the set below the estimate, the first above it
    below = np.flatnonzero(outside & (p_hat > _GRID))
    above = np.flatnonzero(outside & (p_hat < _GRID))
    low = _crossing(counts, p_hat, float(_GRID[below[-1]]), level, layout) if below.size else 0.0
    high = (
        _crossing(counts, p_hat, float(_GRID[above[0]]), level, layout) if above.size else MAX_BER
    )
    return BerEstimate(p_hat, min(low, p_hat), max(high, p_hat), counts.frames, confidence)


class ChannelEstimator:
    """The dive's frames so far and their estimate (computed when asked, kept for the counts
    it was computed from). No I/O: the command manager feeds it every acknowledgement.

    Frames are taken on one thread (the console's event loop); the estimate may be asked from
    others (the API's worker threads): the counts are immutable and replaced whole, and the
    kept estimate is paired with the counts it belongs to.
    """

    def __init__(self, *, min_frames: int = MIN_FRAMES, layout: FrameLayout = LAYOUT) -> None:
        self.min_frames = min_frames
        self.layout = layout
        self.reset()

    def reset(self) -> None:
        """A new dive: no frame yet."""
        self.counts = ChannelCounts()
        #: Acknowledgements that said nothing of the channel (see :func:`evidence_of`).
        self.ignored = 0
        self._kept: tuple[ChannelCounts, BerEstimate | None] | None = None

    def observe(self, ack: Mapping[str, Any]) -> FrameEvidence | None:
        """Take one acknowledgement; returns its evidence (``None``: ignored)."""
        evidence = evidence_of(ack, self.layout)
        if evidence is None:
            self.ignored += 1
            return None
        self.counts = self.counts.plus(evidence, self.layout)
        return evidence

    def estimate(self) -> BerEstimate | None:
        """The estimate, or ``None`` below :attr:`min_frames` frames."""
        counts = self.counts
        if counts.frames < max(1, self.min_frames):
            return None
        kept = self._kept
        if kept is None or kept[0] != counts:
            kept = self._kept = (counts, estimate_ber(counts, layout=self.layout))
        return kept[1]
