"""The online BER estimate (station/channel_estimate.py) against independent oracles: the
closed-form binomial estimate when nothing is censored, a pure-Python likelihood built on
:func:`codec.binomial_cdf`, frames simulated with numpy at a known BER (the interval's
coverage), and the real onboard agent's acknowledgements of frames with known errors."""

from __future__ import annotations

import math
import random
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from codec import CODEWORD_BITS, FRAME_BITS, GUARD_BITS, SYNC_BITS, binomial_cdf, encode_frame
from onboard.agent import OnboardAgent
from onboard.guidance import Guidance
from planner import Limits, VehicleState
from station.channel_estimate import (
    MAX_BER,
    MIN_FRAMES,
    ChannelCounts,
    ChannelEstimator,
    FrameEvidence,
    estimate_ber,
    evidence_of,
    log_likelihood,
)

CHI2_95 = 3.841458820694124  # 1.959963984540054 ** 2
FRAME = encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw").frame
HOLDING = VehicleState(0.0, 0.0, 2.0)
#: Bit positions (0 = first on the wire) of each section.
SYNC = range(0, SYNC_BITS)
CODEWORD = range(SYNC_BITS, SYNC_BITS + CODEWORD_BITS)
GUARD = range(FRAME_BITS - GUARD_BITS, FRAME_BITS)


def simulated_counts(rng: np.random.Generator, p: float, frames: int) -> ChannelCounts:
    """``frames`` frames at BER ``p`` as the receiver sees them (numpy, not the codec): a
    frame decodes when its 24 sync bits hold <= 2 errors and its 72 codeword bits <= 2."""
    sync, codeword = rng.binomial(SYNC_BITS, p, frames), rng.binomial(CODEWORD_BITS, p, frames)
    decoded = (sync <= 2) & (codeword <= 2)
    n = int(decoded.sum())
    errors = int((sync + codeword)[decoded].sum())
    return ChannelCounts(decoded=n, not_decoded=frames - n, bits=96 * n, errors=errors)


def oracle_log_likelihood(c: ChannelCounts, p: float) -> float:
    """The likelihood of the module's doc, in pure Python on codec.binomial_cdf."""
    f_cw, f_sync = binomial_cdf(CODEWORD_BITS, 2, p), binomial_cdf(SYNC_BITS, 2, p)
    ll = c.errors * math.log(p) + (c.bits - c.errors) * math.log1p(-p)
    ll += c.codeword_censored * math.log(f_cw) + c.sync_censored * math.log(f_sync)
    return ll + c.not_decoded * math.log(1.0 - f_sync * f_cw)


def golden_max(f: Callable[[float], float], a: float, b: float) -> float:
    g = (math.sqrt(5) - 1) / 2
    for _ in range(200):
        c, d = b - g * (b - a), a + g * (b - a)
        if f(c) >= f(d):
            b = d
        else:
            a = c
    return (a + b) / 2


def root(f: Callable[[float], float], a: float, b: float) -> float:
    """Bisection: f(a) and f(b) of opposite signs."""
    fa = f(a)
    for _ in range(200):
        m = (a + b) / 2
        if (f(m) > 0) == (fa > 0):
            a, fa = m, f(m)
        else:
            b = m
    return (a + b) / 2


# --- the estimate against independent computations ---------------------------------------


@pytest.mark.parametrize(("bits", "errors"), [(96 * 200, 190), (96 * 50, 3), (96 * 30, 1)])
def test_uncensored_counts_give_the_binomial_estimate_and_its_likelihood_ratio_interval(
    bits: int, errors: int
) -> None:
    counts = ChannelCounts(decoded=bits // 96, bits=bits, errors=errors)
    est = estimate_ber(counts)
    assert est is not None and est.frames == bits // 96 and est.confidence == 0.95
    p_hat = errors / bits
    assert est.ber == pytest.approx(p_hat, rel=1e-4)

    def ll(q: float) -> float:
        return errors * math.log(q) + (bits - errors) * math.log1p(-q)

    def drop(p: float) -> float:  # 2 (l(p_hat) - l(p)) - chi2: zero at the interval's ends
        return 2 * (ll(p_hat) - ll(p)) - CHI2_95

    assert est.low == pytest.approx(root(drop, 1e-12, p_hat), rel=1e-3)
    assert est.high == pytest.approx(root(drop, p_hat, 0.5), rel=1e-3)


@pytest.mark.parametrize(
    "counts",
    [
        ChannelCounts(decoded=180, not_decoded=20, bits=96 * 180, errors=250),
        ChannelCounts(decoded=40, not_decoded=2, bits=72 * 40, errors=30, sync_censored=40),
        ChannelCounts(decoded=60, not_decoded=9, bits=24 * 60, errors=5, codeword_censored=60),
        ChannelCounts(decoded=3, not_decoded=30, bits=96 * 3, errors=4),
    ],
)
def test_censored_likelihood_and_estimate_match_a_pure_python_oracle(
    counts: ChannelCounts,
) -> None:
    ps = [1e-3, 3e-3, 0.01, 0.04, 0.2]  # (at 1e-4 the oracle's 1 - F F loses digits)
    ours = log_likelihood(counts, ps)
    theirs = [oracle_log_likelihood(counts, p) for p in ps]
    # the same function up to a constant
    assert np.allclose(ours - ours[0], np.array(theirs) - theirs[0], rtol=1e-9, atol=1e-7)

    est = estimate_ber(counts)
    assert est is not None
    # from 1e-5 up: below it 1 - F_sync F_cw cancels to nothing in the oracle's plain formula
    p_hat = golden_max(lambda p: oracle_log_likelihood(counts, p), 1e-5, MAX_BER)
    assert est.ber == pytest.approx(p_hat, rel=1e-3)
    top = oracle_log_likelihood(counts, p_hat)

    def drop(p: float) -> float:
        return 2 * (top - oracle_log_likelihood(counts, p)) - CHI2_95

    assert est.low == pytest.approx(root(drop, 1e-5, p_hat), rel=1e-3)
    assert est.high == pytest.approx(root(drop, p_hat, MAX_BER), rel=1e-3)


def test_no_frame_is_no_estimate_and_the_edges_of_the_range() -> None:
    assert estimate_ber(ChannelCounts()) is None
    clean = estimate_ber(ChannelCounts(decoded=100, bits=9600))
    assert clean is not None and clean.ber == 0.0 and clean.low == 0.0
    # 9600 clean bits: l(p) = 9600 log(1 - p) falls by chi2 / 2 at the upper end
    assert clean.high == pytest.approx(-math.expm1(-CHI2_95 / 2 / 9600), rel=1e-3)
    hopeless = estimate_ber(ChannelCounts(not_decoded=50))
    assert hopeless is not None and hopeless.ber == hopeless.high == MAX_BER
    assert 0.05 < hopeless.low < MAX_BER
    with pytest.raises(ValueError, match="confidence"):
        estimate_ber(ChannelCounts(decoded=1, bits=96), confidence=1.0)


# --- coverage on frames simulated at a known BER -----------------------------------------


def coverage(p: float, frames: int, runs: int, seed: int) -> tuple[float, float]:
    """(share of runs whose interval holds ``p``, mean estimate)."""
    rng = np.random.default_rng(seed)
    hits, estimates = 0, []
    for _ in range(runs):
        est = estimate_ber(simulated_counts(rng, p, frames))
        assert est is not None and est.low <= est.ber <= est.high
        hits += est.low <= p <= est.high
        estimates.append(est.ber)
    return hits / runs, float(np.mean(estimates))


@pytest.mark.slow  # 1 200 estimates, ~5 s
@pytest.mark.parametrize("p", [0.005, 0.01, 0.02])
@pytest.mark.parametrize("frames", [200, MIN_FRAMES])
def test_the_interval_holds_the_true_ber_about_95_percent_of_the_time(
    p: float, frames: int
) -> None:
    runs = 200
    share, mean = coverage(p, frames, runs, seed=int(p * 1e4) + frames)
    # 200 runs: the share's standard error is 1.5 %; at MIN_FRAMES the count is small and
    # discrete (a handful of errors), so the nominal 95 % holds only roughly
    assert (0.91 if frames == 200 else 0.87) <= share <= 0.99, share
    if frames == 200:
        assert mean == pytest.approx(p, rel=0.05)


def test_leaving_the_refused_frames_out_would_bias_the_estimate_low() -> None:
    """The censored term is what keeps the estimate honest at high BER: the decoded frames
    alone hold at most 2 + 2 errors each."""
    counts = simulated_counts(np.random.default_rng(3), 0.02, 4000)
    est = estimate_ber(counts)
    assert est is not None and est.low <= 0.02 <= est.high
    naive = counts.errors / counts.bits
    assert naive < 0.9 * 0.02 < est.ber


# --- what an acknowledgement says (the real onboard agent) --------------------------------


def ack_of(flips: list[int], *, limits: Limits | None = None, n_bits: int = FRAME_BITS) -> Any:
    """The onboard agent's acknowledgement of the circle frame with bits ``flips`` flipped
    (positions from the first bit on the wire)."""
    value = FRAME.value
    for i in flips:
        value ^= 1 << (FRAME_BITS - 1 - i)
    return OnboardAgent(Guidance(), limits).receive(value, n_bits, HOLDING)[0]


@pytest.mark.parametrize("codeword", [0, 1, 2])
@pytest.mark.parametrize("sync", [0, 1, 2])
def test_a_decoded_frame_counts_its_codeword_and_sync_errors_exactly(
    codeword: int, sync: int
) -> None:
    rng = random.Random(codeword * 10 + sync)
    flips = rng.sample(SYNC, sync) + rng.sample(CODEWORD, codeword) + rng.sample(GUARD, 2)
    ack = ack_of(flips)
    assert ack["outcome"] == "accepted"
    # the guard bits the receiver ignores are not seen
    assert evidence_of(ack) == FrameEvidence(True, codeword, sync)


@pytest.mark.parametrize(
    "flips",
    [
        list(CODEWORD)[:3],  # three codeword errors: beyond t = 2
        list(SYNC)[5:8],  # three sync errors: beyond the tolerance
        list(SYNC)[:3] + list(CODEWORD)[10:13],
    ],
)
def test_a_frame_the_decoder_refused_counts_as_not_decoded(flips: list[int]) -> None:
    ack = ack_of(flips)
    assert ack["outcome"] == "rejected" and ack["reason"] != "malformed"
    assert evidence_of(ack) == FrameEvidence(False)


def test_frames_decoded_then_refused_by_the_agent_count_and_malformed_ones_do_not() -> None:
    refused = ack_of([30], limits=Limits(max_depth_m=1.0))  # decoded, beyond the vehicle's limits
    assert refused["reason"] == "limit_violation"
    assert evidence_of(refused) == FrameEvidence(True, 1, 0)
    assert evidence_of(ack_of([], n_bits=99)) is None  # not a frame: no bit errors to count


def test_reported_counts_match_the_bits_that_differ_in_the_echoed_frame() -> None:
    """``frame_hex`` echoes the bits received: for every decoded frame the counts are the
    sync and codeword bits that differ from those sent (an oracle outside the decoder)."""
    rng = random.Random(7)
    seen = 0
    for _ in range(300):
        flips = [i for i in range(FRAME_BITS) if rng.random() < 0.02]
        ack = ack_of(flips)
        evidence = evidence_of(ack)
        assert evidence is not None
        diff = int(ack["frame_hex"], 16) ^ FRAME.value
        sync = (diff >> (CODEWORD_BITS + GUARD_BITS)).bit_count()
        codeword = ((diff >> GUARD_BITS) & ((1 << CODEWORD_BITS) - 1)).bit_count()
        assert evidence.decoded == (sync <= 2 and codeword <= 2)
        if evidence.decoded:
            seen += 1
            assert (evidence.codeword_errors, evidence.sync_errors) == (codeword, sync)
    assert seen > 200


@pytest.mark.parametrize(
    ("ack", "expected"),
    [
        ({"outcome": "accepted", "corrected_bits": 1}, FrameEvidence(True, 1, None)),
        ({"outcome": "accepted"}, FrameEvidence(True, None, None)),
        ({"outcome": "accepted", "corrected_bits": 3, "sync_errors": 0}, None),  # not this code
        ({"outcome": "accepted", "corrected_bits": True, "sync_errors": 0}, None),
        ({"outcome": "rejected", "reason": "crc_mismatch"}, FrameEvidence(False)),
        ({"outcome": "rejected", "reason": "no_sync"}, FrameEvidence(False)),
        ({"outcome": "rejected", "reason": "something_new"}, None),
        ({"reason": "uncorrectable"}, None),
    ],
)
def test_evidence_of_acknowledgements_that_leave_something_out(
    ack: dict[str, Any], expected: FrameEvidence | None
) -> None:
    assert evidence_of(ack) == expected


def test_the_estimator_waits_for_min_frames_and_starts_again_on_reset() -> None:
    estimator = ChannelEstimator()
    for i in range(MIN_FRAMES):
        assert estimator.estimate() is None
        estimator.observe(ack_of([SYNC_BITS + i]))  # one codeword error each
    estimator.observe({"outcome": "rejected", "reason": "malformed"})
    est = estimator.estimate()
    assert est is not None and est.frames == MIN_FRAMES and estimator.ignored == 1
    assert est.ber == pytest.approx(MIN_FRAMES / (96 * MIN_FRAMES), rel=1e-3)
    # censored: the counts left out are known only to be within reach
    estimator.observe({"outcome": "accepted"})
    assert estimator.counts.codeword_censored == estimator.counts.sync_censored == 1
    assert estimator.estimate() is not est  # recomputed after a new frame
    estimator.reset()
    assert estimator.counts == ChannelCounts() and estimator.ignored == 0
    assert estimator.estimate() is None
