"""The ROS-free core of the vehicle node: every agent outcome through it, one ack each."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.codec.helpers import crafted_frame
from tests.nemesys_vehicle.helpers import (
    CIRCLE,
    T0_S,
    bytes_of,
    circle_codes,
    flip,
    frame_bytes,
    make_core,
    no_header,
    odometry,
    receive_checked,
    running_core,
    soon,
)
from vehicle_contract.codes import INVALID_PLAN, LIMIT_VIOLATION, Mode

# --- accepted ------------------------------------------------------------------------------


def test_an_accepted_frame_replans_from_the_odometry_and_sets_a_setpoint_at_once() -> None:
    core, rec = make_core()
    # 10 m east, 20 m north, 2 m deep, facing east (ENU yaw 0)
    core.on_odometry(odometry(T0_S, east_m=10.0, north_m=20.0, up_m=-2.0, yaw_enu_deg=0.0))
    assert core.tick_guidance(T0_S) is None  # no command yet: the autopilot is left alone
    assert rec.setpoints == []
    ack = receive_checked(core, rec, frame_bytes("circle", **CIRCLE), T0_S + 0.5)
    assert ack["outcome"] == "accepted"
    assert ack["duplicate"] is False
    assert ack["t_s"] == T0_S + 0.5
    assert ack["from"] == {
        "x_m": 20.0,
        "y_m": 10.0,
        "z_m": 2.0,
        "heading_deg": 90.0,
        "speed_mps": 0.1,
        "t_s": T0_S + 0.5,
        "segment": None,
    }
    assert core.guidance.mode is Mode.RUNNING
    assert len(rec.setpoints) == 1  # guidance's first new setpoint, in the same call
    assert rec.setpoints[0]["header"]["stamp"]["sec"] == int(T0_S)
    status = core.tick_status(T0_S + 1)
    assert status["pattern"] == "circle"
    assert status["active"] == ack["active"] == ack["command"]


def test_duplicate_is_acknowledged_and_not_replanned() -> None:
    core, rec = running_core()
    g = core.guidance
    before = (core.agent.active, g.plan, g.segment, g.mode)
    n_setpoints = len(rec.setpoints)
    ack = receive_checked(core, rec, flip(frame_bytes("circle", **CIRCLE), 40), soon(core))
    assert ack["outcome"] == "accepted"
    assert ack["duplicate"] is True
    assert ack["corrected_bits"] == 1
    assert (core.agent.active, g.plan, g.segment, g.mode) == before
    assert core.agent.active is before[0]
    assert len(rec.setpoints) == n_setpoints


# --- rejected: nothing changes -------------------------------------------------------------

REJECTS: dict[str, tuple[Callable[[], bytes], str, str | None]] = {
    "empty message": (lambda: b"", "malformed", None),
    "12 bytes": (lambda: frame_bytes("circle", **CIRCLE)[:12], "malformed", None),
    "14 bytes": (lambda: frame_bytes("circle", **CIRCLE) + b"\0", "malformed", None),
    "header zeroed": (lambda: no_header(frame_bytes("circle", **CIRCLE)), "no_sync", None),
    "three sync errors": (
        lambda: flip(frame_bytes("circle", **CIRCLE), 0, 9, 20),
        "no_sync",
        None,
    ),
    "three codeword errors": (
        lambda: flip(frame_bytes("circle", **CIRCLE), 30, 50, 70),
        "uncorrectable",
        None,
    ),
    "crc mismatch": (
        lambda: bytes_of(crafted_frame(3, circle_codes(), crc_xor=1)),
        "crc_mismatch",
        None,
    ),
    "pattern 9": (lambda: bytes_of(crafted_frame(9, ())), "unknown_pattern", None),
    "direction code 2": (
        lambda: bytes_of(crafted_frame(3, (*circle_codes()[:3], 2))),
        "field_out_of_range",
        "direction",
    ),
    "j5 set on a circle": (
        lambda: bytes_of(crafted_frame(3, (*circle_codes(), 1))),
        "unused_field_set",
        "j5",
    ),
    "circle radius 0": (
        lambda: frame_bytes("circle", speed=0.2, depth=2, radius=0, direction="cw"),
        INVALID_PLAN,
        "radius",
    ),
    "speed 1.5 m/s": (
        lambda: frame_bytes("straight", speed=1.5, depth=2, duration=30, heading=0),
        LIMIT_VIOLATION,
        "speed",
    ),
    "depth 20 m (limit 10 m)": (
        lambda: frame_bytes("straight", speed=0.5, depth=20, duration=30, heading=0),
        LIMIT_VIOLATION,
        "depth",
    ),
}


@pytest.mark.parametrize("case", list(REJECTS))
def test_every_reject_gives_one_ack_and_changes_nothing(case: str) -> None:
    make, reason, field = REJECTS[case]
    core, rec = running_core(max_depth_m=10.0)
    g = core.guidance
    before = (core.agent.active, g.plan, g.mode, g.segment, g.hold, core.agent.accepted)
    n_setpoints = len(rec.setpoints)
    ack = receive_checked(core, rec, make(), soon(core))
    assert ack["outcome"] == "rejected"
    assert ack["reason"] == reason
    assert ack["field"] == field
    assert ack["active"] is not None
    assert ack["active"]["pattern"] == "circle"
    assert (core.agent.active, g.plan, g.mode, g.segment, g.hold, core.agent.accepted) == before
    assert core.agent.active is before[0]
    assert g.plan is before[1]
    assert len(rec.setpoints) == n_setpoints  # no new setpoint from a rejected frame
    assert core.agent.rejected == 1


def test_surface_overrides_the_limits_and_repeats_as_a_duplicate() -> None:
    # the vehicle is outside the geofence: every pattern but surface is refused
    core, rec = make_core(geofence_radius_m=1.0, geofence_north_m=50.0, geofence_east_m=50.0)
    core.on_odometry(odometry(T0_S))
    ack = receive_checked(core, rec, frame_bytes("circle", **CIRCLE), T0_S)
    assert ack["reason"] == LIMIT_VIOLATION
    assert core.agent.active is None
    assert rec.setpoints == []
    ack = receive_checked(core, rec, frame_bytes("surface"), T0_S + 1)
    assert ack["outcome"] == "accepted"
    assert ack["command"] == {"pattern": "surface", "pattern_id": 15, "params": {}}
    assert core.guidance.mode is Mode.SURFACING
    assert len(rec.setpoints) == 1
    ack = receive_checked(core, rec, frame_bytes("surface"), T0_S + 2)
    assert ack["duplicate"] is True
    assert core.guidance.mode is Mode.SURFACING
    # the setpoint: the hold point where surfacing began, at the surface
    sp = core.tick_guidance(T0_S + 3)
    assert sp is not None
    assert (sp.x_north_m, sp.y_east_m, sp.depth_m, sp.speed_mps) == (20.0, 10.0, 0.0, 0.0)
    assert rec.setpoints[-1]["pose"]["position"] == {"x": 10.0, "y": 20.0, "z": 0.0}  # ENU
    # at the surface: vertical thrusters off
    core.on_odometry(odometry(T0_S + 4, up_m=0.0))
    sp = core.tick_guidance(T0_S + 4)
    assert sp is not None
    assert sp.vertical is False
    assert core.tick_status(T0_S + 4)["mode"] == "surfaced"


def test_seq_counts_every_frame_whatever_the_outcome() -> None:
    core, rec = make_core()
    core.on_odometry(odometry(T0_S))
    circle = frame_bytes("circle", **CIRCLE)
    for data in (circle, b"\1\2", circle, no_header(circle)):
        receive_checked(core, rec, data, T0_S)
    assert [a["seq"] for a in rec.acks] == [1, 2, 3, 4]
    assert [a["outcome"] for a in rec.acks] == ["accepted", "rejected", "accepted", "rejected"]
    assert core.frames_in == 4


def test_odometry_that_is_not_finite_is_ignored() -> None:
    core, _ = make_core()
    assert core.on_odometry(odometry(T0_S, east_m=float("nan"))) is False
    assert core.odometry is None
    assert core.odometry_rejected == 1
    assert core.on_odometry(odometry(T0_S)) is True
    assert core.on_odometry(odometry(T0_S, speed_mps=float("inf"))) is False
    assert core.odometry == odometry(T0_S)


# --- the path's end: done only at its depth (issue 20) --------------------------------------


def test_at_the_path_end_above_its_depth_the_status_says_running_and_it_aims_at_the_end() -> None:
    """A straight whose depth ramp outlasts its line: at the horizontal end the vehicle is
    still flying the last depth change, in place. The status says ``running`` (the command is
    not done) and the setpoint is the end point at the path's depth, not a line-of-sight point
    ahead; ``holding`` once the vehicle is at that depth."""
    core, rec = make_core()
    core.on_odometry(odometry(T0_S, up_m=-2.0))
    ack = receive_checked(
        core, rec, frame_bytes("straight", speed=0.3, depth=6, duration=10, heading=0), T0_S
    )
    assert ack["outcome"] == "accepted"
    active = core.agent.active
    assert active is not None
    path = active.path
    end_n, end_e, end_z = path.xs[-1], path.ys[-1], path.zs[-1]
    assert end_z == pytest.approx(6.0) and (path.xs[-2], path.ys[-2]) == (end_n, end_e)
    for i in range(len(path)):  # along the line, level at 3 m, to its end
        core.on_odometry(odometry(T0_S + 1 + i, east_m=path.ys[i], north_m=path.xs[i], up_m=-3.0))
        core.tick_guidance(T0_S + 1 + i)
    core.on_odometry(odometry(T0_S + 20, east_m=end_e, north_m=end_n, up_m=-3.0))
    sp = core.tick_guidance(T0_S + 20)
    assert sp is not None and sp.mode == "running"
    assert core.guidance.at_end
    assert (sp.x_north_m, sp.y_east_m, sp.depth_m) == (end_n, end_e, end_z)
    assert core.tick_status(T0_S + 20)["mode"] == "running"
    core.on_odometry(odometry(T0_S + 80, east_m=end_e, north_m=end_n, up_m=-5.95))
    sp = core.tick_guidance(T0_S + 80)
    assert sp is not None and sp.mode == "holding"
    assert core.tick_status(T0_S + 80)["mode"] == "holding"
