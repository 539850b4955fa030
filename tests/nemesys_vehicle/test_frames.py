"""ENU (ROS, REP-103) <-> NED (the contract's map_ned): points, headings, quaternions."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from nemesys_vehicle.frames import (
    EnuPose,
    NedPose,
    Quaternion,
    enu_to_ned,
    ned_to_enu,
    quaternion_enu_to_ned,
    quaternion_product,
    yaw_deg_of,
    yaw_quaternion,
)

coords = st.floats(-1e4, 1e4, allow_nan=False)
angles = st.floats(-720.0, 720.0, allow_nan=False)


def _angle_diff_deg(a: float, b: float) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


def _same_rotation(a: Quaternion, b: Quaternion) -> bool:
    return abs(abs(sum(x * y for x, y in zip(a, b, strict=True))) - 1.0) < 1e-9


def _rotate(q: Quaternion, v: tuple[float, float, float]) -> tuple[float, float, float]:
    x, y, z, w = quaternion_product(quaternion_product(q, (*v, 0.0)), (-q[0], -q[1], -q[2], q[3]))
    assert abs(w) < 1e-9
    return (x, y, z)


@pytest.mark.parametrize(
    ("yaw_enu_deg", "heading_deg"),
    [(0.0, 90.0), (90.0, 0.0), (180.0, 270.0), (-90.0, 180.0), (270.0, 180.0), (45.0, 45.0)],
)
def test_known_headings(yaw_enu_deg: float, heading_deg: float) -> None:
    # facing east: ENU yaw 0 -> heading 90; facing north: ENU yaw 90 -> heading 0
    ned = enu_to_ned(EnuPose(0.0, 0.0, 0.0, yaw_enu_deg))
    assert ned.heading_deg == pytest.approx(heading_deg)
    back = ned_to_enu(NedPose(0.0, 0.0, 0.0, heading_deg))
    assert _angle_diff_deg(back.yaw_deg, yaw_enu_deg) < 1e-9
    assert -180.0 <= back.yaw_deg < 180.0


def test_known_points() -> None:
    # 3 m east, 4 m north, 5 m below the surface
    ned = enu_to_ned(EnuPose(x_east_m=3.0, y_north_m=4.0, z_up_m=-5.0, yaw_deg=0.0))
    assert ned == NedPose(x_north_m=4.0, y_east_m=3.0, z_down_m=5.0, heading_deg=90.0)
    enu = ned_to_enu(NedPose(x_north_m=1.0, y_east_m=-2.0, z_down_m=0.5, heading_deg=0.0))
    assert enu == EnuPose(x_east_m=-2.0, y_north_m=1.0, z_up_m=-0.5, yaw_deg=90.0)


def test_no_negative_zero() -> None:
    ned = enu_to_ned(EnuPose(0.0, 0.0, 0.0, 90.0))
    assert all(math.copysign(1.0, v) == 1.0 for v in ned)
    enu = ned_to_enu(NedPose(0.0, 0.0, 0.0, 90.0))
    assert all(math.copysign(1.0, v) == 1.0 for v in enu)


@given(coords, coords, coords, angles)
def test_round_trips(a: float, b: float, c: float, angle: float) -> None:
    enu = EnuPose(a, b, c, angle)
    back = ned_to_enu(enu_to_ned(enu))
    assert back[:3] == enu[:3]
    assert _angle_diff_deg(back.yaw_deg, angle) < 1e-9
    ned = enu_to_ned(enu)
    assert 0.0 <= ned.heading_deg < 360.0
    again = enu_to_ned(ned_to_enu(ned))
    assert again[:3] == ned[:3]
    assert _angle_diff_deg(again.heading_deg, ned.heading_deg) < 1e-9


@given(angles)
def test_yaw_quaternion_round_trip(yaw_deg: float) -> None:
    q = yaw_quaternion(yaw_deg)
    assert q[0] == q[1] == 0.0
    assert q[3] >= 0.0
    assert math.fsum(c * c for c in q) == pytest.approx(1.0)
    assert _angle_diff_deg(yaw_deg_of(q), yaw_deg) < 1e-9


def test_yaw_of_a_scaled_quaternion() -> None:
    q = yaw_quaternion(30.0)
    assert yaw_deg_of(tuple(3.0 * c for c in q)) == pytest.approx(30.0)  # type: ignore[arg-type]


@given(angles)
def test_the_yaw_path_agrees_with_the_full_attitude_conversion(yaw_enu_deg: float) -> None:
    q_enu = yaw_quaternion(yaw_enu_deg)
    q_ned = quaternion_enu_to_ned(q_enu)
    heading = enu_to_ned(EnuPose(0.0, 0.0, 0.0, yaw_deg_of(q_enu))).heading_deg
    assert _same_rotation(q_ned, yaw_quaternion(heading))


def test_full_attitude_conversion_maps_the_axes() -> None:
    # identity ENU/FLU: nose east, left north, up up -> in NED/FRD: nose (0, 1, 0) east,
    # right (-1, 0, 0) south, down (0, 0, 1)
    q = quaternion_enu_to_ned((0.0, 0.0, 0.0, 1.0))
    for body, world in (
        ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
        ((0.0, 1.0, 0.0), (-1.0, 0.0, 0.0)),
        ((0.0, 0.0, 1.0), (0.0, 0.0, 1.0)),
    ):
        assert _rotate(q, body) == pytest.approx(world, abs=1e-12)
    # nose 30 deg up (FLU: -30 deg about +y, the left axis) while facing north: in NED the
    # nose points north and up (negative z), and the heading is still 0
    half = math.radians(-30.0) / 2
    pitch_up = (0.0, math.sin(half), 0.0, math.cos(half))
    face_north = yaw_quaternion(90.0)
    q_ned = quaternion_enu_to_ned(quaternion_product(face_north, pitch_up))
    nose = _rotate(q_ned, (1.0, 0.0, 0.0))
    assert nose == pytest.approx((math.cos(math.radians(30)), 0.0, -0.5), abs=1e-12)
    assert yaw_deg_of(q_ned) == pytest.approx(0.0, abs=1e-9)
