"""The geo-referenced vehicle: latitude/longitude to metres, the odometry -> map_ned edge (origin
and declination), the datum from parameters or the first fix at the surface, the datum
message. (The conversion against PROJ, the console's: tests/backend/chart/test_vehicle_datum.)"""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from nemesys_vehicle.frames import EnuPose, MapOrigin, NedPose, map_to_odometry, odometry_to_map
from nemesys_vehicle.geo import WGS84_A_M, WGS84_F, geodetic_to_ned
from tests.nemesys_vehicle.helpers import CIRCLE, DATUM, T0_S, frame_bytes, make_core, odometry
from vehicle_contract.codes import NO_NAVIGATION
from vehicle_contract.contract import DATUM_REPEAT_S
from vehicle_contract.payloads import validate_datum

E2 = WGS84_F * (2.0 - WGS84_F)

# --- latitude and longitude to metres --------------------------------------------------------


@pytest.mark.parametrize("lat_deg", [-60.0, 0.0, 29.5316, 45.0, 70.0])
def test_small_steps_match_the_ellipsoids_radii_of_curvature(lat_deg: float) -> None:
    """A small step north is the meridian's radius times the angle, a step east the prime
    vertical's radius times the parallel's: WGS84's own figures, not a sphere's."""
    phi = math.radians(lat_deg)
    w = math.sqrt(1.0 - E2 * math.sin(phi) ** 2)
    meridian_m = WGS84_A_M * (1.0 - E2) / w**3
    prime_m = WGS84_A_M / w
    step_deg = 1e-4  # about 11 m
    north, east = geodetic_to_ned(lat_deg, 10.0, lat_deg + step_deg, 10.0)
    assert north == pytest.approx(meridian_m * math.radians(step_deg), rel=1e-6)
    assert abs(east) < 1e-6
    north, east = geodetic_to_ned(lat_deg, 10.0, lat_deg, 10.0 + step_deg)
    assert east == pytest.approx(prime_m * math.cos(phi) * math.radians(step_deg), rel=1e-6)
    assert abs(north) < 1e-3  # the parallel curves away from the tangent plane: 1e-5 m here


def test_the_datum_is_the_origin_and_bad_values_are_named() -> None:
    assert geodetic_to_ned(*DATUM, *DATUM) == (0.0, 0.0)
    with pytest.raises(ValueError, match="lat_deg"):
        geodetic_to_ned(*DATUM, 91.0, 0.0)
    with pytest.raises(ValueError, match="lon_deg"):
        geodetic_to_ned(*DATUM, 0.0, math.nan)


# --- the odometry -> map_ned edge -------------------------------------------------------------


def test_the_edge_adds_the_origin_and_turns_by_the_declination() -> None:
    # 10 m along the odometry's north, facing it (ENU yaw 90), 2 m deep
    enu = EnuPose(0.0, 10.0, -2.0, 90.0)
    assert odometry_to_map(enu, MapOrigin()) == NedPose(10.0, 0.0, 2.0, 0.0)
    shifted = odometry_to_map(enu, MapOrigin(100.0, -50.0, 0.0))
    assert shifted == NedPose(110.0, -50.0, 2.0, 0.0)
    # a magnetic frame, declination 10 deg east: its north is 10 deg east of true north
    turned = odometry_to_map(enu, MapOrigin(0.0, 0.0, 10.0))
    assert turned.x_north_m == pytest.approx(10.0 * math.cos(math.radians(10.0)))
    assert turned.y_east_m == pytest.approx(10.0 * math.sin(math.radians(10.0)))
    assert turned.heading_deg == pytest.approx(10.0)
    assert turned.z_down_m == 2.0


@given(
    x=st.floats(-1e4, 1e4),
    y=st.floats(-1e4, 1e4),
    z=st.floats(-100, 100),
    yaw=st.floats(-179.9, 179.9),
    origin=st.tuples(st.floats(-1e4, 1e4), st.floats(-1e4, 1e4), st.floats(-180, 180)),
)
def test_map_to_odometry_undoes_the_edge(
    x: float, y: float, z: float, yaw: float, origin: tuple[float, float, float]
) -> None:
    enu = EnuPose(x, y, z, yaw)
    back = map_to_odometry(odometry_to_map(enu, MapOrigin(*origin)), MapOrigin(*origin))
    assert back.x_east_m == pytest.approx(x, abs=1e-6)
    assert back.y_north_m == pytest.approx(y, abs=1e-6)
    assert back.z_up_m == pytest.approx(z, abs=1e-9)
    assert math.remainder(back.yaw_deg - yaw, 360.0) == pytest.approx(0.0, abs=1e-9)


# --- the datum --------------------------------------------------------------------------------

FROM_FIX = {"datum_source": "navsatfix", "odometry_origin_at_datum": False}
CIRCLE_BYTES = frame_bytes("circle", **CIRCLE)


def test_from_the_first_fix_at_the_surface() -> None:
    core, rec = make_core(**FROM_FIX)
    # navigation started 30 m south-west of where the vehicle now is, at the surface
    core.on_odometry(odometry(T0_S, east_m=30.0, north_m=30.0, up_m=0.0))
    ack = core.on_frame(CIRCLE_BYTES, T0_S)
    assert ack["reason"] == NO_NAVIGATION
    assert "/fix" in ack["detail"] and "geo-referenced" in ack["detail"]
    assert core.tick_pose(T0_S) is None
    assert core.tick_status(T0_S)["nav_valid"] is False
    assert rec.datums == []  # no datum yet: nothing sent
    # no fix in the status, a fix while the odometry is stale: not used
    assert not core.on_navsatfix(T0_S, 29.5, -82.3, False)
    assert not core.on_navsatfix(T0_S + 5.0, 29.5, -82.3, True)
    assert core.on_navsatfix(T0_S + 0.5, 29.5, -82.3, True)
    assert len(rec.datums) == 1
    datum = rec.datums[0]
    assert validate_datum(datum) == []
    assert datum == {
        "t_s": T0_S + 0.5,
        "lat_deg": 29.5,
        "lon_deg": -82.3,
        "source": "navsatfix",
        "odometry_origin": {"north_m": -30.0, "east_m": -30.0},
    }
    # the vehicle is at the datum; 10 m north of there is 10 m north
    pose = core.tick_pose(T0_S + 0.6)
    assert pose is not None
    assert pose["pose"]["position"] == {"x": 0.0, "y": 0.0, "z": 0.0}
    core.on_odometry(odometry(T0_S + 1.0, east_m=30.0, north_m=40.0, up_m=-2.0))
    assert core.map_pose() == NedPose(10.0, 0.0, 2.0, 90.0)
    # setpoints go back to the odometry's own frame
    ack = core.on_frame(CIRCLE_BYTES, T0_S + 1.0)
    assert ack["outcome"] == "accepted"
    assert ack["from"]["x_m"] == 10.0
    # later fixes move nothing
    assert not core.on_navsatfix(T0_S + 1.0, 10.0, 10.0, True)
    assert core.map_pose() == NedPose(10.0, 0.0, 2.0, 90.0)


def test_a_fix_below_the_surface_is_not_used() -> None:
    core, _rec = make_core(**FROM_FIX)
    core.on_odometry(odometry(T0_S, up_m=-0.6))
    assert not core.on_navsatfix(T0_S, 29.5, -82.3, True)
    core.on_odometry(odometry(T0_S + 0.1, up_m=-0.4))
    assert core.on_navsatfix(T0_S + 0.1, 29.5, -82.3, True)
    assert not core.on_navsatfix(T0_S + 0.1, 95.0, 0.0, True)  # out of range: no fix anyway


def test_datum_parameters_with_the_origin_from_a_fix() -> None:
    core, rec = make_core(odometry_origin_at_datum=False)
    assert core.georef.datum == DATUM and not core.georef.referenced
    # a fix 0.001 deg north of the datum, with the odometry at its own origin
    core.on_odometry(odometry(T0_S, east_m=0.0, north_m=0.0, up_m=0.0))
    assert core.on_navsatfix(T0_S, DATUM[0] + 0.001, DATUM[1], True)
    north_m, east_m = geodetic_to_ned(*DATUM, DATUM[0] + 0.001, DATUM[1])
    assert north_m == pytest.approx(110.8, abs=0.1)
    pose = core.map_pose()
    assert pose is not None
    assert (pose.x_north_m, pose.y_east_m) == pytest.approx((north_m, east_m))
    assert rec.datums[-1]["source"] == "parameters"
    assert rec.datums[-1]["lat_deg"] == DATUM[0]


def test_datum_parameters_at_the_navigation_origin_repeat_with_the_status() -> None:
    core, rec = make_core()
    core.tick_status(T0_S)
    assert len(rec.datums) == 1
    first = rec.datums[0]
    assert validate_datum(first) == []
    assert first["odometry_origin"] == {"north_m": 0.0, "east_m": 0.0}
    core.tick_status(T0_S + DATUM_REPEAT_S - 0.5)
    assert len(rec.datums) == 1
    core.tick_status(T0_S + DATUM_REPEAT_S)
    assert len(rec.datums) == 2
    assert rec.datums[1] == first  # the same datum, set at the same time


def test_a_magnetic_odometry_is_turned_to_true_north() -> None:
    core, _rec = make_core(magnetic_declination_deg=-5.0)
    # facing the odometry's north (ENU yaw 90): 5 deg west of true north
    core.on_odometry(odometry(T0_S, east_m=0.0, north_m=10.0, yaw_enu_deg=90.0))
    pose = core.map_pose()
    assert pose is not None
    assert pose.heading_deg == pytest.approx(355.0)
    assert pose.x_north_m == pytest.approx(10.0 * math.cos(math.radians(5.0)))
    assert pose.y_east_m == pytest.approx(-10.0 * math.sin(math.radians(5.0)))
    status = core.tick_status(T0_S)
    assert status["heading_deg"] == pytest.approx(355.0)
