"""The one edge from NED to Foxglove's scene frame (backend/foxglove_live/frames.py): ENU about
the datum, the same frame as the console's own 3D view."""

from __future__ import annotations

import math

import numpy as np
import pytest

from backend.foxglove_live.clock import to_ns
from backend.foxglove_live.frames import attitude_xyzw, enu, heading_rad, stamp
from backend.viewer.draw import attitude_to_view_wxyz, ned_to_view


def rotate(q: tuple[float, float, float, float], v: tuple[float, float, float]) -> np.ndarray:
    """``v`` rotated by the unit quaternion ``q`` = (x, y, z, w)."""
    x, y, z, w = q
    u = np.array([x, y, z])
    vec = np.array(v, dtype=float)
    return np.asarray(2 * u.dot(vec) * u + (w * w - u.dot(u)) * vec + 2 * w * np.cross(u, vec))


def test_north_east_down_is_east_north_up() -> None:
    assert enu(10.0, 3.0, 2.5) == (3.0, 10.0, -2.5)  # north 10, east 3, 2.5 m deep
    assert math.copysign(1.0, enu(0.0, 0.0, 0.0)[2]) == 1.0  # the surface is 0.0, not -0.0


@pytest.mark.parametrize(
    ("heading_deg", "nose_enu"),
    [(0.0, (0, 1, 0)), (90.0, (1, 0, 0)), (180.0, (0, -1, 0)), (270.0, (-1, 0, 0))],
)
def test_the_nose_points_where_the_heading_says(
    heading_deg: float, nose_enu: tuple[int, int, int]
) -> None:
    nose = rotate(attitude_xyzw(heading_deg), (1.0, 0.0, 0.0))  # body +x: forward
    assert nose == pytest.approx(nose_enu, abs=1e-12)


def test_roll_puts_the_starboard_side_down() -> None:
    port = rotate(attitude_xyzw(0.0, 30.0), (0.0, 1.0, 0.0))  # body +y: port
    assert port[2] == pytest.approx(math.sin(math.radians(30.0)))  # port side up


@pytest.mark.parametrize(("heading_deg", "roll_deg"), [(0, 0), (37, -12), (271.5, 40), (-45, 5)])
def test_the_same_frame_as_the_console_3d_view(heading_deg: float, roll_deg: float) -> None:
    x, y, z, w = attitude_xyzw(heading_deg, roll_deg)
    assert (w, x, y, z) == pytest.approx(attitude_to_view_wxyz(heading_deg, roll_deg))
    assert enu(4.0, -2.0, 7.0) == tuple(ned_to_view(4.0, -2.0, 7.0))


def test_location_fix_heading_is_radians_clockwise_from_north() -> None:
    assert heading_rad(90.0) == pytest.approx(math.pi / 2)
    assert heading_rad(-90.0) == pytest.approx(3 * math.pi / 2)
    assert heading_rad(360.0) == 0.0


def test_stamp_splits_nanoseconds_and_never_goes_negative() -> None:
    t = stamp(to_ns(12.345678901))
    assert (t.sec, t.nsec) == (12, 345678901)
    t = stamp(-5)
    assert (t.sec, t.nsec) == (0, 0)
