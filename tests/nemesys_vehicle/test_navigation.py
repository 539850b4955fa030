"""Navigation health in the node's core: every frame acknowledged at once (never held, never
dropped), ``no_navigation`` when there is nothing to plan from, stale odometry -> no pose,
``nav_valid: false``, ``nav_fault`` and the fault action, the deadline and ``late``."""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nemesys_vehicle.core import VehicleCore
from nemesys_vehicle.messages import Recorder
from tests.nemesys_vehicle.helpers import (
    CIRCLE,
    T0_S,
    frame_bytes,
    make_core,
    odometry,
    running_core,
    soon,
)
from vehicle_contract.codes import NO_NAVIGATION, RECENT_ACKS_MAX, RECENT_ACKS_S, Mode
from vehicle_contract.contract import ACK_DEADLINE_S
from vehicle_contract.payloads import validate_ack, validate_status

CIRCLE_BYTES = frame_bytes("circle", **CIRCLE)
HOVER_BYTES = frame_bytes("hover", duration=60, depth=3, heading=90)
SURFACE_BYTES = frame_bytes("surface")
#: The node's default: odometry older than this (s) is stale.
TIMEOUT_S = 2.0


# --- before the first odometry ---------------------------------------------------------------


def test_frames_before_the_first_odometry_are_each_acknowledged_at_once() -> None:
    """The field report: 12 frames before the first odometry gave 2 dropped and 10 acks 115 s
    late. Now: 12 acks, each in the call that received its frame, none late."""
    core, rec = make_core()
    frames = [CIRCLE_BYTES, b"", HOVER_BYTES, SURFACE_BYTES] * 3
    for k, data in enumerate(frames):
        t_s = T0_S + 10.0 * k
        ack = core.on_frame(data, t_s)
        assert rec.acks[-1] is ack
        assert len(rec.acks) == k + 1
        assert ack["t_s"] == t_s
        assert ack["late"] is False
        assert validate_ack(ack) == []
        assert ack["outcome"] == "rejected"
        # a message that is no frame says so; a decoded command has nothing to plan from
        assert ack["reason"] == ("malformed" if data == b"" else NO_NAVIGATION)
        if ack["reason"] == NO_NAVIGATION:
            assert ack["command"] is not None
            assert "no odometry" in ack["detail"]
    assert core.agent.active is None
    assert core.tick_pose(T0_S + 200) is None
    assert core.tick_guidance(T0_S + 200) is None
    # the first odometry releases nothing: there is nothing held
    core.on_odometry(odometry(T0_S + 200))
    assert len(rec.acks) == len(frames)
    ack = core.on_frame(CIRCLE_BYTES, T0_S + 200.5)
    assert ack["outcome"] == "accepted"
    assert ack["seq"] == len(frames) + 1


def test_status_before_odometry_is_idle_with_navigation_not_valid() -> None:
    core, _ = make_core()
    status = core.tick_status(T0_S)
    assert (status["mode"], status["nav_valid"], status["nav_age_s"]) == ("idle", False, None)
    assert validate_status(status) == []


# --- stale odometry --------------------------------------------------------------------------


def _stale(action: str = "surface") -> tuple[VehicleCore, Recorder, float]:
    """A core flying a circle whose odometry then stops: (core, recorder, a stale time)."""
    core, rec = running_core(nav_fault_action=action)
    assert core.odometry is not None
    return core, rec, core.odometry.t_s + TIMEOUT_S + 0.5


def test_stale_odometry_stops_the_pose_and_says_so_in_the_status() -> None:
    core, rec, stale_s = _stale()
    last = core.odometry
    assert last is not None
    assert core.tick_pose(soon(core)) is not None
    n_poses = len(rec.poses)
    assert core.tick_pose(stale_s) is None
    assert len(rec.poses) == n_poses  # never a stale pose stamped as new
    status = core.tick_status(stale_s)
    assert validate_status(status) == []
    assert status["nav_valid"] is False
    assert status["nav_age_s"] == pytest.approx(stale_s - last.t_s)
    assert status["mode"] == Mode.NAV_FAULT.value == "nav_fault"
    for key in ("x_m", "y_m", "depth_m", "heading_deg", "speed_mps"):
        assert status[key] is None, key
    # the command it was given is reported (suspended), so the console sees no echo mismatch
    assert status["pattern"] == "circle"
    assert core.nav_faults == 1


def test_the_pose_is_stamped_with_the_odometry_time() -> None:
    core, _rec = make_core()
    core.on_odometry(odometry(T0_S))
    pose = core.tick_pose(T0_S + 1.5)
    assert pose is not None
    assert pose["header"]["stamp"] == {"sec": int(T0_S), "nanosec": 0}


@pytest.mark.parametrize(("action", "depth_m"), [("surface", 0.0), ("hold", None)])
def test_the_fault_action_from_the_last_known_position(action: str, depth_m: float | None) -> None:
    core, rec, stale_s = _stale(action)
    pose = core.map_pose()
    assert pose is not None
    sp = core.tick_guidance(stale_s)
    assert sp is not None
    assert sp.mode == "nav_fault"
    assert (sp.x_north_m, sp.y_east_m) == (pose.x_north_m, pose.y_east_m)
    assert sp.depth_m == (pose.z_down_m if depth_m is None else depth_m)
    assert (sp.speed_mps, sp.vertical) == (0.0, True)
    assert rec.setpoints[-1]["header"]["stamp"]["sec"] == int(stale_s)
    # it goes on while the navigation stays stale
    later = core.tick_guidance(stale_s + 10.0)
    assert later == replace(sp, t_s=stale_s + 10.0)


def test_frames_in_a_fault_are_acknowledged_and_only_surface_is_flown() -> None:
    core, rec, stale_s = _stale("hold")
    core.tick_status(stale_s)  # the fault begins
    last = core.map_pose()
    assert last is not None
    # the active command again: not a duplicate (it is not flown), nothing to plan from
    ack = core.on_frame(CIRCLE_BYTES, stale_s + 0.1)
    assert (ack["outcome"], ack["reason"], ack["duplicate"]) == ("rejected", NO_NAVIGATION, False)
    assert "stale" in ack["detail"]
    ack = core.on_frame(HOVER_BYTES, stale_s + 0.2)
    assert ack["reason"] == NO_NAVIGATION
    assert validate_ack(ack) == []
    # Surface: accepted, planned from the last known position; the fault ends
    ack = core.on_frame(SURFACE_BYTES, stale_s + 0.3)
    assert ack["outcome"] == "accepted"
    assert validate_ack(ack) == []
    assert (ack["from"]["x_m"], ack["from"]["y_m"]) == (last.x_north_m, last.y_east_m)
    assert core.fault is None
    status = core.tick_status(stale_s + 0.4)
    assert (status["mode"], status["nav_valid"]) == ("surfacing", False)
    sp = core.tick_guidance(stale_s + 0.5)
    assert sp is not None
    assert (sp.depth_m, sp.vertical, sp.mode) == (0.0, True, "surfacing")
    assert all(a["late"] is False for a in rec.acks)


def test_the_fault_lasts_until_a_command_is_accepted_with_navigation_back() -> None:
    core, _rec, stale_s = _stale()
    core.tick_status(stale_s)
    pose = core.map_pose()
    assert pose is not None
    back_s = stale_s + 5.0
    core.on_odometry(
        odometry(back_s, east_m=pose.y_east_m, north_m=pose.x_north_m, up_m=-pose.z_down_m)
    )
    status = core.tick_status(back_s + 0.1)
    assert (status["mode"], status["nav_valid"]) == ("nav_fault", True)
    assert status["x_m"] == pytest.approx(pose.x_north_m)
    assert core.tick_pose(back_s + 0.1) is not None
    held = core.tick_guidance(back_s + 0.1)
    assert held is not None and held.mode == "nav_fault"
    # the same command again is replanned from here (not a duplicate of a command not flown)
    ack = core.on_frame(CIRCLE_BYTES, back_s + 0.2)
    assert (ack["outcome"], ack["duplicate"]) == ("accepted", False)
    assert ack["from"]["t_s"] == back_s + 0.2
    assert core.fault is None
    assert core.tick_status(back_s + 0.3)["mode"] == "running"
    # and a duplicate is one again
    assert core.on_frame(CIRCLE_BYTES, back_s + 0.4)["duplicate"] is True


def test_a_commanded_surface_goes_on_without_a_fault() -> None:
    core, _rec = make_core(nav_fault_action="hold")
    core.on_odometry(odometry(T0_S, up_m=-3.0))
    assert core.on_frame(SURFACE_BYTES, T0_S + 0.5)["outcome"] == "accepted"
    stale_s = T0_S + TIMEOUT_S + 1.0
    status = core.tick_status(stale_s)
    assert (status["mode"], status["nav_valid"]) == ("surfacing", False)
    assert core.fault is None
    sp = core.tick_guidance(stale_s)
    assert sp is not None
    assert (sp.depth_m, sp.mode) == (0.0, "surfacing")


def test_before_any_command_a_fault_leaves_the_autopilot_alone() -> None:
    core, rec = make_core()
    core.on_odometry(odometry(T0_S))
    assert core.tick_status(T0_S + 0.1)["nav_valid"] is True
    status = core.tick_status(T0_S + TIMEOUT_S + 1.0)
    assert status["mode"] == "nav_fault"
    assert core.tick_guidance(T0_S + TIMEOUT_S + 1.0) is None
    assert rec.setpoints == []


# --- the deadline ----------------------------------------------------------------------------


def test_an_ack_made_after_the_deadline_says_late() -> None:
    core, rec = make_core()
    core.on_odometry(odometry(T0_S))
    # the frame reached the node 1.5 s before the core got to it (a stalled executor)
    ack = core.on_frame(CIRCLE_BYTES, T0_S, receipt_s=time.perf_counter() - 1.5)
    assert ack["late"] is True
    assert ack["outcome"] == "accepted"
    assert rec.acks == [ack]
    assert validate_ack(ack) == []
    assert ACK_DEADLINE_S == 1.0


#: One step of a node's life: a frame, odometry, or a clock tick (with the time it takes).
STEPS = st.lists(
    st.tuples(
        st.sampled_from(["frame", "frame", "bad frame", "surface", "odometry", "tick", "fix"]),
        st.floats(min_value=0.0, max_value=3.0),
    ),
    max_size=40,
)


@settings(max_examples=60, deadline=None)
@given(steps=STEPS, datum_source=st.sampled_from(["navsatfix", "parameters"]))
def test_every_frame_gets_one_ack_in_its_own_call_within_the_deadline(
    steps: list[tuple[str, float]], datum_source: str
) -> None:
    config: dict[str, Any] = {"datum_source": datum_source}
    if datum_source == "navsatfix":
        config["odometry_origin_at_datum"] = False
    core, rec = make_core(**config)
    t_s, frames = T0_S, 0
    for step, dt_s in steps:
        t_s += dt_s
        if step in ("frame", "bad frame", "surface"):
            data = {"frame": CIRCLE_BYTES, "bad frame": CIRCLE_BYTES[:5], "surface": SURFACE_BYTES}
            valid = core.navigation(t_s) is None
            started = time.perf_counter()
            ack = core.on_frame(data[step], t_s)
            frames += 1
            assert time.perf_counter() - started < ACK_DEADLINE_S
            assert rec.acks[-1] is ack and len(rec.acks) == frames
            assert ack["late"] is False
            assert validate_ack(ack) == []
            if ack["reason"] == NO_NAVIGATION:
                assert not valid
            if valid and step == "frame":
                assert ack["outcome"] == "accepted"
        elif step == "odometry":  # (no tick in between: its going stale is still seen)
            core.on_odometry(odometry(t_s, up_m=0.0))
        elif step == "fix":
            core.on_navsatfix(t_s, 29.5316, -82.3031, True)
        else:
            status = core.tick_status(t_s)
            assert validate_status(status) == []
            assert status["nav_valid"] is (core.navigation(t_s) is None)
            pose = core.tick_pose(t_s)
            assert (pose is not None) is status["nav_valid"]
            setpoint = core.tick_guidance(t_s)
            # guidance never runs on stale navigation, but to surface
            if setpoint is not None and not status["nav_valid"]:
                assert setpoint.mode in ("nav_fault", "surfacing", "surfaced"), setpoint
    assert [a["seq"] for a in rec.acks] == list(range(1, frames + 1))


# --- what the status carries ------------------------------------------------------------------


def test_the_status_carries_the_recent_acks_for_a_console_that_reconnects() -> None:
    core, rec = make_core()
    core.on_odometry(odometry(T0_S))
    for k in range(RECENT_ACKS_MAX + 2):
        core.on_frame(CIRCLE_BYTES if k % 2 else b"", T0_S + 0.1 * k)
    status = core.tick_status(T0_S + 1.5)
    recent = status["recent_acks"]
    assert len(recent) == RECENT_ACKS_MAX
    assert recent == rec.acks[-RECENT_ACKS_MAX:]  # as published, oldest first
    assert validate_status(status) == []
    # they age out
    later_s = T0_S + RECENT_ACKS_S + 1.05  # the last ack (at T0 + 1.1) is 29.95 s old
    core.on_odometry(odometry(later_s))
    assert core.tick_status(later_s)["recent_acks"] == [rec.acks[-1]]
    assert core.tick_status(T0_S + RECENT_ACKS_S + 2.0)["recent_acks"] == []


def test_battery_state_percentage_is_a_fraction() -> None:
    core, _ = make_core()
    assert core.on_battery_state(0.875)
    assert core.tick_status(T0_S)["battery_pct"] == 87.5
    assert core.on_battery_state(float("nan"))  # not measured: unknown
    assert core.tick_status(T0_S)["battery_pct"] is None
    assert core.on_battery_state(0.5)
    assert not core.on_battery_state(87.5)  # a driver that sends percent: refused, counted
    assert core.battery_rejected == 1
    assert core.tick_status(T0_S)["battery_pct"] == 50.0
