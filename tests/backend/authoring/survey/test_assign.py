"""The blocks and who takes which: lane pairs shared evenly, the odd lane at an edge, and the
assignment exactly the best by (largest, then total) distance, against brute force."""

from __future__ import annotations

import itertools
import random

import pytest

from backend.authoring.survey.area import SurveyArea, check_area, frame_of
from backend.authoring.survey.assign import (
    block_sizes,
    blocks_of,
    bottleneck_assignment,
    entries,
    min_cost_assignment,
)


@pytest.mark.parametrize(
    ("lanes", "vehicles", "sizes"),
    [
        (12, 3, (4, 4, 4)),
        (14, 3, (6, 4, 4)),
        (13, 3, (4, 4, 5)),
        (17, 3, (6, 6, 5)),
        (2, 1, (2,)),
        (3, 1, (3,)),
        (30, 15, (2,) * 15),
    ],
)
def test_block_sizes(lanes: int, vehicles: int, sizes: tuple[int, ...]) -> None:
    assert block_sizes(lanes, vehicles) == sizes
    blocks = blocks_of(sizes)
    assert [b.first_lane for b in blocks] == [sum(sizes[:i]) for i in range(len(sizes))]
    assert blocks[-1].last_lane == lanes - 1


def test_an_odd_block_is_entered_only_where_its_extra_lane_leaves_the_area() -> None:
    area = SurveyArea(0.0, 0.0, 0.0, 130.0, 100.0, 10.0, 3.0, 0.2)
    sent, frame = check_area(area), frame_of(area)
    lanes = [5.0 + 10.0 * i for i in range(13)]
    last = blocks_of((4, 4, 5))
    assert [e.from_end for e in entries(last[2], 3, lanes, area, sent, frame)] == [False]
    assert [e.from_end for e in entries(last[0], 3, lanes, area, sent, frame)] == [False, True]
    first = blocks_of((5, 4, 4))
    assert [e.from_end for e in entries(first[0], 3, lanes, area, sent, frame)] == [True]
    alone = blocks_of((13,))
    assert [e.from_end for e in entries(alone[0], 1, lanes, area, sent, frame)] == [False, True]


def _brute(costs: list[list[float]]) -> tuple[float, float]:
    n = len(costs)
    return min(
        (max(costs[i][p[i]] for i in range(n)), sum(costs[i][p[i]] for i in range(n)))
        for p in itertools.permutations(range(n))
    )


def test_min_cost_assignment_is_the_least_sum() -> None:
    rng = random.Random(23)
    for n in range(1, 7):
        for _ in range(20):
            costs = [[rng.uniform(0, 100) for _ in range(n)] for _ in range(n)]
            cols = min_cost_assignment(costs)
            assert sorted(cols) == list(range(n))
            best = min(
                sum(costs[i][p[i]] for i in range(n)) for p in itertools.permutations(range(n))
            )
            assert sum(costs[i][cols[i]] for i in range(n)) == pytest.approx(best)


def test_bottleneck_assignment_is_the_least_largest_then_the_least_sum() -> None:
    rng = random.Random(6)
    for n in range(1, 7):
        for _ in range(20):
            # few distinct values: many assignments share the least largest cost
            costs = [[float(rng.randint(1, 6)) for _ in range(n)] for _ in range(n)]
            cols = bottleneck_assignment(costs)
            assert sorted(cols) == list(range(n))
            got = (
                max(costs[i][cols[i]] for i in range(n)),
                sum(costs[i][cols[i]] for i in range(n)),
            )
            assert got == pytest.approx(_brute(costs))


def test_fifteen_vehicles_are_assigned_at_once() -> None:
    rng = random.Random(15)
    costs = [[rng.uniform(0, 1000) for _ in range(15)] for _ in range(15)]
    cols = bottleneck_assignment(costs)
    assert sorted(cols) == list(range(15))
