"""Which command runs on a one-way link: P(i) = p_i prod_{j newer} (1 - p_j), and the rest
is the last known state (hand-computed)."""

from __future__ import annotations

import math

import pytest

from backend.belief.odds import running_odds


def test_the_newest_delivered_wins() -> None:
    odds, none = running_odds([0.9, 0.5])  # oldest first
    assert odds == pytest.approx([0.9 * 0.5, 0.5])
    assert none == pytest.approx(0.1 * 0.5)
    assert sum(odds) + none == pytest.approx(1.0)


def test_three_commands() -> None:
    odds, none = running_odds([0.99, 0.6, 0.8])
    assert odds == pytest.approx([0.99 * 0.4 * 0.2, 0.6 * 0.2, 0.8])
    assert none == pytest.approx(0.01 * 0.4 * 0.2)
    assert sum(odds) + none == pytest.approx(1.0)


def test_a_sure_newer_command_leaves_nothing_to_the_older() -> None:
    assert running_odds([0.7, 1.0]) == ([0.0, 1.0], 0.0)


def test_no_command_leaves_the_last_known_state() -> None:
    assert running_odds([]) == ([], 1.0)


def test_a_command_none_of_whose_copies_left_counts_nothing() -> None:
    odds, none = running_odds([0.9, 0.0])
    assert odds == pytest.approx([0.9, 0.0]) and none == pytest.approx(0.1)


@pytest.mark.parametrize("bad", [1.5, -0.1, math.nan, math.inf])
def test_a_bad_probability_is_named(bad: float) -> None:
    with pytest.raises(ValueError, match=r"p_delivered\[1\] must be a probability in \[0, 1\]"):
        running_odds([0.5, bad])
