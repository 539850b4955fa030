"""Path.sample, locate and the other Path accessors."""

from __future__ import annotations

import math

import pytest

from planner import Path, plan
from tests.planner.helpers import TOL, command, vehicle


def _finite() -> Path:
    return Path(
        (0.0, 10.0, 10.0),
        (0.0, 0.0, 5.0),
        (1.0, 1.0, 2.0),
        (0.5, 0.25, 0.0),
        (0.0, 20.0, 40.0),
        (0.0, 1.0, 2.0),
    )


def test_sample_at_zero_and_before_is_the_first_waypoint() -> None:
    path = _finite()
    for t in (0.0, -5.0):
        sp = path.sample(t)
        assert (sp.x_m, sp.y_m, sp.z_m) == (0.0, 0.0, 1.0)
        assert sp.speed_mps == 0.5
        assert sp.course_deg == pytest.approx(0.0)


def test_sample_interpolates() -> None:
    path = _finite()
    sp = path.sample(10.0)
    assert (sp.x_m, sp.y_m, sp.z_m) == pytest.approx((5.0, 0.0, 1.0))
    assert sp.speed_mps == 0.5
    sp = path.sample(30.0)
    assert (sp.x_m, sp.y_m, sp.z_m) == pytest.approx((10.0, 2.5, 1.5))
    assert sp.speed_mps == 0.25
    assert sp.course_deg == pytest.approx(90.0)


def test_finite_path_holds_its_end_at_speed_zero() -> None:
    path = _finite()
    for t in (40.0, 41.0, 1e6):
        sp = path.sample(t)
        assert (sp.x_m, sp.y_m, sp.z_m) == (10.0, 5.0, 2.0)
        assert sp.speed_mps == 0.0
    assert path.duration_s == 40.0
    assert path.length_m() == pytest.approx(10.0 + math.hypot(5.0, 1.0))
    assert path.length_m(1) == pytest.approx(math.hypot(5.0, 1.0))


def test_single_waypoint_path() -> None:
    path = Path((1.0,), (2.0,), (3.0,), (0.0,), (0.0,), (0.0,))
    sp = path.sample(12.0)
    assert (sp.x_m, sp.y_m, sp.z_m, sp.speed_mps) == (1.0, 2.0, 3.0, 0.0)
    assert path.locate(5.0, 5.0, 5.0) == 0.0


def test_path_rejects_ragged_columns() -> None:
    with pytest.raises(ValueError):
        Path((0.0, 1.0), (0.0,), (0.0, 0.0), (0.0, 0.0), (0.0, 1.0), (0.0, 0.0))
    with pytest.raises(ValueError):
        Path((), (), (), (), (), ())
    with pytest.raises(ValueError):
        Path((0.0,), (0.0,), (0.0,), (0.0,), (0.0,), (0.0,), body_start=1)


def test_repeating_path_wraps_into_its_lap() -> None:
    p = plan(
        command("square", speed=0.5, depth=2, side_span=8, direction="cw"),
        vehicle(0.0, 0.0, 2.0, 90.0, 0.5),
    )
    path = p.path
    ls = path.loop_start
    assert ls is not None
    t_loop, t_end = path.times[ls], path.times[-1]
    lap = t_end - t_loop
    assert lap == pytest.approx(4 * 8 / 0.5)
    for dt in (0.0, 3.3, 17.0, 40.0, lap - 0.1):
        for k in (1, 2, 7):
            a = path.sample(t_loop + dt)
            b = path.sample(t_loop + dt + k * lap)
            assert (b.x_m, b.y_m, b.z_m) == pytest.approx((a.x_m, a.y_m, a.z_m), abs=TOL)
            assert b.speed_mps == pytest.approx(0.5)
    # never holds: still moving long after the first lap
    assert path.sample(t_end + 1e4).speed_mps == pytest.approx(0.5)


def test_circle_sample_stays_on_the_circle_forever() -> None:
    p = plan(
        command("circle", speed=0.5, depth=3, radius=5, direction="ccw"),
        vehicle(0.0, 0.0, 3.0, 0.0, 0.5),
    )
    for t in (200.0, 1234.5, 99999.0):
        sp = p.path.sample(t)
        r = math.hypot(sp.x_m - p.anchor[0], sp.y_m - p.anchor[1])
        assert 5.0 * math.cos(math.pi / 8) - TOL <= r <= 5.0 + TOL
        assert sp.z_m == pytest.approx(3.0)
        assert sp.speed_mps == pytest.approx(0.5)


def test_locate_finds_the_nearest_point() -> None:
    path = _finite()
    assert path.locate(5.0, 1.0, 1.0) == pytest.approx(0.5)
    assert path.locate(11.0, 2.5, 1.5) == pytest.approx(1.5)
    assert path.locate(-3.0, 0.0, 1.0) == 0.0
    # with a hint only that segment is searched
    assert path.locate(11.0, 2.5, 1.5, hint=0) == pytest.approx(1.0)


def test_course_of_a_vertical_segment_is_the_previous_one() -> None:
    path = Path(
        (0.0, 0.0, 0.0),
        (0.0, 3.0, 3.0),
        (1.0, 1.0, 4.0),
        (0.5, 0.0, 0.0),
        (0.0, 6.0, 26.0),
        (0.0, 0.0, 0.0),
    )
    assert path.course_deg(0) == pytest.approx(90.0)
    assert path.course_deg(1) == pytest.approx(90.0)
