"""The vehicle's top speed: estimates at the speed it can fly, and the named, overridable
violation of a command faster than that."""

from __future__ import annotations

import math
from itertools import pairwise

import pytest

from codec import DICTIONARY, encode_frame, make_command
from planner import Plan, VehicleState, compare, estimate, plan
from planner._checks import top_speed
from planner._estimate import flyable_times, planned_speed_mps
from planner._plan import HOVER_APPROACH_MPS

#: Level with the patterns' depth and facing north: a straight north is one segment.
LEVEL = VehicleState(0.0, 0.0, 2.0, 0.0)


def planned(name: str, state: VehicleState = LEVEL, **params: float | str) -> Plan:
    command, _ = make_command(name, {**DICTIONARY[name].defaults, **params})
    return plan(command, state)


def test_the_example_wording_for_0_8_m_s_against_0_18() -> None:
    p = planned("straight", speed=0.8, depth=2, duration=60, heading=0)
    v = top_speed(p, 0.18)
    assert v is not None
    assert v.message == (
        "speed 0.8 m/s exceeds the vehicle's 0.18 m/s top speed: it will fly at 0.18 m/s, "
        "4.4x the planned duration"
    )
    assert (v.param, v.value, v.limit, v.unit) == ("speed", 0.8, 0.18, "m/s")
    assert v.overridable is True


def test_a_circle_at_0_8_names_its_ratio_from_the_durations() -> None:
    p = planned("circle", speed=0.8, depth=2, radius=5, direction="cw")
    v = top_speed(p, 0.18)
    assert v is not None and v.message.endswith("4.4x the planned duration")
    assert "top speed" in v.message


@pytest.mark.parametrize("speed", [0.1, 0.18])
def test_at_or_below_the_top_speed_nothing_is_reported(speed: float) -> None:
    p = planned("circle", speed=speed, depth=2, radius=5, direction="cw")
    assert top_speed(p, 0.18) is None


def test_an_unknown_top_speed_checks_nothing() -> None:
    p = planned("circle", speed=0.8, depth=2, radius=5, direction="cw")
    assert top_speed(p, None) is None


def test_patterns_without_a_speed_are_not_checked() -> None:
    hover = planned("hover", duration=30, depth=3, heading=0)
    assert planned_speed_mps(hover) is None
    assert top_speed(hover, 0.05) is None
    # a hover with an approach (the planner's 0.2 m/s) asks the operator for nothing
    away = plan(
        encode_frame("hover", {"duration": 30, "depth": 3, "heading": 0}).command,
        VehicleState(20.0, 0.0, 3.0),
    )
    assert top_speed(away, HOVER_APPROACH_MPS / 2) is None
    surface = planned("surface")
    assert top_speed(surface, 0.01) is None


def test_estimates_are_at_the_flyable_speed_and_keep_the_planned() -> None:
    p = planned("straight", speed=0.8, depth=2, duration=60, heading=0)
    e = estimate(p, 0.18)
    assert e.planned_duration_s == pytest.approx(60.0)
    assert e.duration_s == pytest.approx(60.0 * 0.8 / 0.18)
    assert (e.planned_speed_mps, e.flyable_speed_mps) == (0.8, 0.18)
    slow = estimate(planned("straight", speed=0.15, depth=2, duration=60, heading=0), 0.18)
    assert slow.duration_s == slow.planned_duration_s
    assert slow.flyable_speed_mps == 0.15


def test_repeating_estimates_stretch_the_join_and_the_lap() -> None:
    p = planned("circle", speed=0.8, depth=2, radius=5, direction="cw")
    fast, slow = estimate(p), estimate(p, 0.2)
    assert fast.lap_duration_s is not None and slow.lap_duration_s is not None
    assert slow.lap_duration_s == pytest.approx(fast.lap_duration_s * 4.0)
    assert slow.transit_duration_s == pytest.approx(fast.transit_duration_s * 4.0)


def test_the_diff_compares_flyable_durations() -> None:
    a = planned("circle", speed=0.8, depth=2, radius=5, direction="cw")
    b = planned("circle", speed=0.4, depth=2, radius=5, direction="cw")
    # both above a 0.2 m/s top speed: both flown at 0.2, the difference is the geometry's
    d = compare(a, b, 0.2)
    flown = estimate(b, 0.2).duration_s - estimate(a, 0.2).duration_s
    assert d.delta("duration_s") == pytest.approx(flown)
    assert d.new.duration_s > d.new.planned_duration_s
    assert (compare(a, b).delta("duration_s") or 0.0) > 0  # planned: 0.4 is slower


@pytest.mark.parametrize("name", list(DICTIONARY))
def test_flyable_times_never_shorten_a_segment(name: str) -> None:
    p = planned(name, VehicleState(3.0, -2.0, 4.0, 45.0, 0.5))
    path = p.path
    assert flyable_times(path) == path.times
    times = flyable_times(path, 0.1, 0.02)
    for (a, b), (c, d), i in zip(
        pairwise(path.times), pairwise(times), range(len(times) - 1), strict=True
    ):
        assert d - c >= b - a - 1e-9
        h = math.hypot(path.xs[i + 1] - path.xs[i], path.ys[i + 1] - path.ys[i])
        dz = abs(path.zs[i + 1] - path.zs[i])
        assert d - c >= max(h / 0.1, dz / 0.02) - 1e-9


def test_a_heave_rate_at_the_planners_leaves_depth_changes_alone() -> None:
    p = planned("surface", VehicleState(0.0, 0.0, 5.0))
    path = p.path
    assert flyable_times(path, None, 0.07309) == path.times  # the twin's 73.1 mm/s
    slow = flyable_times(path, None, 0.03)
    assert slow[-1] == pytest.approx(5.0 / 0.03)
