"""Estimates agree with the path they describe; the diff names what a retask changes."""

from __future__ import annotations

import math
from itertools import pairwise

import pytest

from codec import DICTIONARY, make_command
from planner import Plan, VehicleState, compare, estimate, plan

START = VehicleState(3.0, -2.0, 4.0, 45.0, 0.5)


def default_plan(name: str, state: VehicleState = START, current: Plan | None = None) -> Plan:
    command, _ = make_command(name, DICTIONARY[name].defaults)
    return plan(command, state, current)


@pytest.mark.parametrize("name", list(DICTIONARY))
def test_estimate_agrees_with_the_waypoints(name: str) -> None:
    p = default_plan(name)
    e = estimate(p)
    path = p.path
    pts = list(zip(path.xs, path.ys, path.zs, strict=True))
    length = sum(math.dist(a, b) for a, b in pairwise(pts))
    assert e.waypoints == len(pts)
    assert e.length_m == pytest.approx(length)
    assert e.duration_s == pytest.approx(path.times[-1])
    assert (e.depth_min_m, e.depth_max_m) == (min(path.zs), max(path.zs))
    assert (e.x_min_m, e.x_max_m) == (min(path.xs), max(path.xs))
    assert (e.y_min_m, e.y_max_m) == (min(path.ys), max(path.ys))
    body = path.body_start
    transit = sum(math.dist(a, b) for a, b in pairwise(pts[: body + 1]))
    assert e.transit_length_m == pytest.approx(transit)
    assert e.transit_duration_s == pytest.approx(path.times[body])
    assert e.repeats == (name in ("square", "circle"))


def test_circle_lap_is_one_sampled_circumference_at_the_commanded_speed() -> None:
    e = estimate(default_plan("circle"))
    r, speed = 5.0, 0.5
    assert e.lap_length_m is not None and e.lap_duration_s is not None
    assert 2 * math.pi * r * 0.99 < e.lap_length_m < 2 * math.pi * r
    assert e.lap_duration_s == pytest.approx(e.lap_length_m / speed)


def test_lawnmower_duration_is_length_over_speed_at_constant_depth() -> None:
    level = VehicleState(0.0, 0.0, 5.0, 0.0, 0.5)
    e = estimate(default_plan("lawnmower", level))
    # 4 lanes of 20 m and 3 cross legs of 5 m at 0.5 m/s
    assert e.length_m == pytest.approx(4 * 20 + 3 * 5)
    assert e.duration_s == pytest.approx(e.length_m / 0.5)
    assert e.depth_min_m == e.depth_max_m == 5.0


def test_diff_lists_changed_parameters_only_for_the_same_pattern() -> None:
    running = default_plan("circle")
    faster, _ = make_command("circle", {**DICTIONARY["circle"].defaults, "speed": 0.8})
    new = plan(faster, START, running)
    d = compare(running, new)
    assert not d.pattern_changed
    assert [(c.param, c.old, c.new, c.unit) for c in d.changes] == [("speed", 0.5, 0.8, "m/s")]
    assert d.anchor_moved_m == 0.0
    assert d.old is not None and d.delta("duration_s") == pytest.approx(
        d.new.duration_s - d.old.duration_s
    )


def test_diff_across_patterns_lists_every_parameter_that_differs() -> None:
    running = default_plan("helix")
    new = default_plan("square", START, running)
    d = compare(running, new)
    assert d.pattern_changed and (d.old_pattern, d.new_pattern) == ("helix", "square")
    names = [c.param for c in d.changes]
    old, new_params = running.command.params, new.command.params
    differ = {k for k in {*old, *new_params} if old.get(k) != new_params.get(k)}
    assert set(names) == differ
    assert differ != set(old) | set(new_params)  # a shared, equal value (speed) is no change
    side = next(c for c in d.changes if c.param == "side_span")
    assert (side.old, side.new, side.unit) == (None, 10.0, "m")
    assert d.anchor_moved_m == 0.0  # orbit patterns share the anchor


def test_diff_without_a_running_plan() -> None:
    d = compare(None, default_plan("hover"))
    assert d.old is None and d.old_pattern is None and d.delta("length_m") is None
    assert {c.param for c in d.changes} == {"duration", "depth", "heading"}


def test_delta_is_none_for_a_lap_figure_missing_on_one_side() -> None:
    d = compare(default_plan("circle"), default_plan("helix", START, default_plan("circle")))
    assert d.delta("lap_length_m") is None
    assert d.delta("waypoints") == d.new.waypoints - (d.old.waypoints if d.old else 0)


def test_a_motion_models_times_give_the_durations() -> None:
    """The console times a path by its motion model (the kinematic twin): the estimate's
    durations are those times, the planned one stays the path's own."""
    p = default_plan("circle")
    path = p.path
    times = [1.5 * t for t in path.times]
    e = estimate(p, times=times)
    assert e.duration_s == pytest.approx(times[-1])
    assert e.transit_duration_s == pytest.approx(times[path.body_start])
    assert path.loop_start is not None and e.lap_duration_s is not None
    assert e.lap_duration_s == pytest.approx(times[-1] - times[path.loop_start])
    assert e.planned_duration_s == path.duration_s
    with pytest.raises(ValueError, match="times has 2 values for a path of"):
        estimate(p, times=[0.0, 1.0])


def test_the_diff_takes_given_estimates() -> None:
    running, new = default_plan("circle"), default_plan("helix", START, default_plan("circle"))
    old_e, new_e = estimate(running, times=[2 * t for t in running.path.times]), estimate(new)
    d = compare(running, new, estimates=(old_e, new_e))
    assert d.old is old_e and d.new is new_e
    assert d.delta("duration_s") == pytest.approx(new_e.duration_s - old_e.duration_s)
