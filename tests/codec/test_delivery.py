"""One-way delivery arithmetic (``codec/_delivery.py``): the research note's figures, an exact
oracle written differently, ``copies_for``, loss, and the refusals."""

from __future__ import annotations

import math
from fractions import Fraction
from functools import cache

import pytest

from codec import (
    CODEWORD_BITS,
    DEFAULT_SYNC_TOLERANCE,
    MAX_COPIES,
    SYNC_BITS,
    binomial_cdf,
    copies_for,
    delivery_probability,
    frame_success_probability,
)

BERS = (0.0, 1e-4, 1e-3, 5e-3, 1e-2, 2e-2, 3e-2, 5e-2, 0.1, 0.25, 0.49)


@cache
def exact_p1(
    ber: Fraction, sync_bits: int = SYNC_BITS, codeword_bits: int = CODEWORD_BITS
) -> Fraction:
    """P1 exactly, by dynamic programming over the frame's bits one at a time: the
    distribution of (sync errors, codeword errors), each capped at "too many" (3), in rational
    arithmetic. Shares nothing with the module's closed form but the definition."""
    too_many = 3
    dist = {(0, 0): Fraction(1)}
    for index in range(sync_bits + codeword_bits):
        in_sync = index < sync_bits
        step: dict[tuple[int, int], Fraction] = {}
        for (s, c), prob in dist.items():
            flipped = (min(s + 1, too_many), c) if in_sync else (s, min(c + 1, too_many))
            step[(s, c)] = step.get((s, c), Fraction(0)) + prob * (1 - ber)
            step[flipped] = step.get(flipped, Fraction(0)) + prob * ber
        dist = step
    return sum(
        (prob for (s, c), prob in dist.items() if s <= DEFAULT_SYNC_TOLERANCE and c <= 2),
        Fraction(0),
    )


# --- the research note's figures (../shared/research/rosbridge-real.md) ----------------------


def test_research_note_figures_at_ber_1e_2() -> None:
    assert round(frame_success_probability(1e-2), 4) == 0.9625
    assert round(delivery_probability(1e-2, 1), 4) == 0.9625
    assert round(delivery_probability(1e-2, 2), 4) == 0.9986
    assert round(delivery_probability(1e-2, 3), 5) == 0.99995


# --- oracle ------------------------------------------------------------------------------------


@pytest.mark.parametrize("ber", BERS)
def test_p1_matches_an_exact_enumeration(ber: float) -> None:
    exact = exact_p1(Fraction(ber))
    assert frame_success_probability(ber) == pytest.approx(float(exact), rel=1e-12, abs=1e-300)


@pytest.mark.parametrize("ber", BERS)
@pytest.mark.parametrize("copies", [0, 1, 2, 3, 7])
def test_delivery_matches_the_exact_complement(ber: float, copies: int) -> None:
    exact = 1 - (1 - exact_p1(Fraction(ber))) ** copies
    assert delivery_probability(ber, copies) == pytest.approx(float(exact), rel=1e-12, abs=1e-15)


def test_binomial_cdf_edges_and_sum() -> None:
    assert binomial_cdf(10, -1, 0.3) == 0.0
    assert binomial_cdf(10, 10, 0.3) == 1.0
    assert binomial_cdf(10, 12, 0.3) == 1.0
    assert binomial_cdf(72, 2, 0.0) == 1.0
    # P(Bin(n, p) <= n - 1) = 1 - p^n
    assert binomial_cdf(5, 4, 0.3) == pytest.approx(1 - 0.3**5, rel=1e-14)


def test_no_copies_deliver_nothing_and_a_clean_link_everything() -> None:
    assert delivery_probability(1e-2, 0) == 0.0
    assert delivery_probability(0.0, 1) == 1.0
    assert frame_success_probability(0.0) == 1.0


# --- copies_for --------------------------------------------------------------------------------


def test_copies_for_known_points() -> None:
    assert copies_for(1e-2, 0.95) == 1
    assert copies_for(1e-2, 0.99) == 2
    assert copies_for(1e-2, 0.9999) == 3
    assert copies_for(0.0, 0.999) == 1


@pytest.mark.parametrize("ber", [1e-3, 1e-2, 2e-2, 5e-2, 0.1])
@pytest.mark.parametrize("target", [0.5, 0.9, 0.99, 0.999, 0.99999])
def test_copies_for_is_the_fewest_reaching_the_target(ber: float, target: float) -> None:
    r = copies_for(ber, target)
    if r == MAX_COPIES and delivery_probability(ber, r) < target:
        return  # unreachable (checked below)
    assert delivery_probability(ber, r) >= target
    assert r == 1 or delivery_probability(ber, r - 1) < target


def test_copies_for_returns_max_copies_when_unreachable() -> None:
    assert delivery_probability(0.3, MAX_COPIES) < 0.99
    assert copies_for(0.3, 0.99) == MAX_COPIES
    assert copies_for(1e-2, 0.9999, loss=0.999) == MAX_COPIES
    assert copies_for(0.3, 0.99, maximum=5) == 5


def test_copies_for_respects_minimum() -> None:
    assert copies_for(0.0, 0.5, minimum=3) == 3
    assert copies_for(1e-2, 0.99, minimum=1, maximum=2) == 2


# --- loss --------------------------------------------------------------------------------------


@pytest.mark.parametrize("loss", [0.0, 0.1, 0.5, 1.0])
def test_loss_scales_p1(loss: float) -> None:
    for ber in (0.0, 1e-2, 2e-2):
        p1 = frame_success_probability(ber)
        assert frame_success_probability(ber, loss=loss) == pytest.approx((1 - loss) * p1)
        expected = 1 - (1 - (1 - loss) * p1) ** 3
        assert delivery_probability(ber, 3, loss=loss) == pytest.approx(expected)


def test_loss_needs_more_copies() -> None:
    assert copies_for(1e-2, 0.999, loss=0.2) > copies_for(1e-2, 0.999)


# --- refusals ----------------------------------------------------------------------------------


@pytest.mark.parametrize("ber", [-1e-9, 0.5000001, 0.7, math.nan, math.inf, True])
def test_ber_out_of_range_is_refused(ber: float) -> None:
    with pytest.raises(ValueError, match="ber"):
        frame_success_probability(ber)
    with pytest.raises(ValueError, match="ber"):
        delivery_probability(ber, 1)
    with pytest.raises(ValueError, match="ber"):
        copies_for(ber, 0.9)


@pytest.mark.parametrize("loss", [-0.1, 1.1, math.nan])
def test_loss_out_of_range_is_refused(loss: float) -> None:
    with pytest.raises(ValueError, match="loss"):
        frame_success_probability(1e-2, loss=loss)
    with pytest.raises(ValueError, match="loss"):
        delivery_probability(1e-2, 2, loss=loss)
    with pytest.raises(ValueError, match="loss"):
        copies_for(1e-2, 0.9, loss=loss)


@pytest.mark.parametrize("target", [0.0, 1.0, -0.5, 1.5, math.nan])
def test_target_out_of_range_is_refused(target: float) -> None:
    with pytest.raises(ValueError, match="target"):
        copies_for(1e-2, target)


@pytest.mark.parametrize("copies", [-1, True, False, 1.5])
def test_copies_negative_bool_or_not_int_is_refused(copies: int) -> None:
    with pytest.raises(ValueError, match="copies"):
        delivery_probability(1e-2, copies)
