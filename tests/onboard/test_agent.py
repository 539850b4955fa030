"""The onboard agent: frame -> sync -> decode -> validate -> replan -> guidance -> ack."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from typing import Any

import pytest

from codec import (
    CODEWORD_BITS,
    FRAME_BITS,
    GUARD_BITS,
    SYNC_BITS,
    ParamValue,
    decode_frame,
    encode_frame,
)
from onboard.agent import NoNavigation, OnboardAgent
from onboard.guidance import Guidance, Reference
from planner import CircleFence, Limits, VehicleState, plan, validate
from tests.codec.helpers import crafted_frame, flip_frame
from vehicle_contract.codes import (
    INVALID_PLAN,
    LIMIT_VIOLATION,
    NO_NAVIGATION,
    RECENT_ACKS_MAX,
    RECENT_ACKS_S,
    Mode,
)

ACK_KEYS = {
    "seq",
    "t_s",
    "outcome",
    "frame_hex",
    "corrected_bits",
    "sync_errors",
    "reason",
    "detail",
    "field",
    "command",
    "duplicate",
    "decode_latency_ms",
    "replan_latency_ms",
    "waypoints",
    "active",
    "from",
}
STATE = VehicleState(0.0, 0.0, 2.0, 0.0, 0.0, 12.5)
CIRCLE: dict[str, ParamValue] = {"speed": 0.2, "depth": 2, "radius": 3, "direction": "cw"}


def _bits(pattern: str, **params: ParamValue) -> int:
    return encode_frame(pattern, params).frame.value


def _flip_codeword(bits: int, *positions: int) -> int:
    """Flip codeword bits counted on the wire (0 = the first codeword bit, frame bit 24)."""
    return flip_frame(bits, codeword=[CODEWORD_BITS - 1 - pos for pos in positions])


def _flip_sync(bits: int, *positions: int) -> int:
    return flip_frame(bits, header=positions)


def _circle_codes() -> tuple[int, ...]:
    return encode_frame("circle", CIRCLE).command.codes


def _agent(limits: Limits | None = None) -> OnboardAgent:
    return OnboardAgent(Guidance(), limits)


def _receive(agent: OnboardAgent, bits: int) -> tuple[dict[str, Any], Reference | None]:
    return agent.receive(bits, FRAME_BITS, STATE)


def _running_agent(limits: Limits | None = None) -> OnboardAgent:
    """An agent flying a circle, some way along it (guidance segment > 0)."""
    agent = _agent(limits)
    ack, _ = _receive(agent, _bits("circle", **CIRCLE))
    assert ack["outcome"] == "accepted"
    active = agent.active
    assert active is not None
    path = active.path
    for i in range(path.body_start + 3):
        agent.guidance.update(path.xs[i], path.ys[i], path.zs[i], STATE.t_s + i)
    assert agent.guidance.segment > 0
    return agent


# --- accepted frames -------------------------------------------------------------------------


def test_accepted_ack_has_every_field_with_its_type() -> None:
    agent = _agent()
    enc = encode_frame("circle", CIRCLE)
    ack, ref = agent.receive(enc.frame.value, FRAME_BITS, STATE)
    assert set(ack) == ACK_KEYS
    assert ack["seq"] == 1
    assert ack["t_s"] == STATE.t_s
    assert isinstance(ack["t_s"], float)
    assert ack["outcome"] == "accepted"
    assert ack["frame_hex"] == enc.frame.hex
    assert len(ack["frame_hex"]) == 25
    assert ack["corrected_bits"] == 0
    assert ack["sync_errors"] == 0
    assert type(ack["corrected_bits"]) is int
    assert type(ack["sync_errors"]) is int
    assert ack["reason"] is None
    assert ack["field"] is None
    assert isinstance(ack["detail"], str)
    assert "circle" in ack["detail"]
    assert ack["command"] == {
        "pattern": "circle",
        "pattern_id": 3,
        "params": {"speed": 0.2, "depth": 2.0, "radius": 3.0, "direction": "cw"},
    }
    assert ack["duplicate"] is False
    for key in ("decode_latency_ms", "replan_latency_ms"):
        assert isinstance(ack[key], float)
        assert ack[key] > 0.0
    active = agent.active
    assert active is not None
    assert active.command == enc.command
    assert type(ack["waypoints"]) is int
    assert ack["waypoints"] == len(active.path)
    assert ack["active"] == ack["command"]
    json.dumps(ack)
    # guidance switched and gave its first setpoint
    assert agent.guidance.plan is active
    assert agent.guidance.mode is Mode.RUNNING
    assert isinstance(ref, Reference)
    assert ref.speed_mps > 0.0
    assert agent.accepted == 1
    assert agent.rejected == 0


def test_decode_latency_is_measured_from_receipt() -> None:
    agent = _agent()
    ack, _ = agent.receive(
        _bits("circle", **CIRCLE), FRAME_BITS, STATE, receipt_s=time.perf_counter() - 0.25
    )
    assert ack["decode_latency_ms"] >= 250.0
    assert ack["replan_latency_ms"] < 250.0


@pytest.mark.parametrize("positions", [(0,), (71,), (30,), (0, 71), (5, 6), (40, 55)], ids=str)
def test_corrected_bits_counts_the_codeword_errors(positions: tuple[int, ...]) -> None:
    agent = _agent()
    enc = encode_frame("circle", CIRCLE)
    bits = _flip_codeword(enc.frame.value, *positions)
    ack, ref = _receive(agent, bits)
    assert ack["outcome"] == "accepted"
    assert ack["corrected_bits"] == len(positions)
    assert ack["sync_errors"] == 0
    assert ack["frame_hex"] == f"{bits:025x}"  # what was received, not what was meant
    assert ack["frame_hex"] != enc.frame.hex
    assert agent.active is not None
    assert agent.active.command == enc.command
    assert ref is not None


@pytest.mark.parametrize("positions", [(0,), (23,), (3, 20)])
def test_sync_errors_are_counted_apart_from_codeword_errors(positions: tuple[int, ...]) -> None:
    agent = _agent()
    bits = _flip_codeword(_flip_sync(_bits("circle", **CIRCLE), *positions), 10)
    ack, _ = _receive(agent, bits)
    assert ack["outcome"] == "accepted"
    assert ack["sync_errors"] == len(positions)
    assert ack["corrected_bits"] == 1


def test_guard_bits_are_ignored() -> None:
    agent = _agent()
    ack, _ = _receive(agent, _bits("circle", **CIRCLE) | 0b1111)
    assert ack["outcome"] == "accepted"
    assert ack["corrected_bits"] == 0


# --- rejected frames -------------------------------------------------------------------------


def _no_sync() -> int:
    return _bits("circle", **CIRCLE) & ~(((1 << SYNC_BITS) - 1) << (CODEWORD_BITS + GUARD_BITS))


REJECTS: dict[str, tuple[Callable[[], int | None], str, str | None]] = {
    "wrong length": (lambda: None, "malformed", None),
    "preamble destroyed": (_no_sync, "no_sync", None),
    "three sync errors": (
        lambda: _flip_sync(_bits("circle", **CIRCLE), 0, 9, 20),
        "no_sync",
        None,
    ),
    "three codeword errors": (
        lambda: _flip_codeword(_bits("circle", **CIRCLE), 3, 25, 45),
        "uncorrectable",
        None,
    ),
    "a burst of codeword errors": (
        lambda: _bits("circle", **CIRCLE) ^ (0b111111 << 40),
        "uncorrectable",
        None,
    ),
    "crc mismatch": (lambda: crafted_frame(3, _circle_codes(), crc_xor=1), "crc_mismatch", None),
    "pattern 9": (lambda: crafted_frame(9, ()), "unknown_pattern", None),
    "direction code 2": (
        lambda: crafted_frame(3, (*_circle_codes()[:3], 2)),
        "field_out_of_range",
        "direction",
    ),
    "zero laps": (lambda: crafted_frame(2, (20, 20, 70, 70, 0)), "field_out_of_range", "laps"),
    "j5 set on a circle": (
        lambda: crafted_frame(3, (*_circle_codes(), 1)),
        "unused_field_set",
        "j5",
    ),
    "j1 set on surface": (lambda: crafted_frame(15, (7,)), "unused_field_set", "j1"),
    "circle radius 0": (
        lambda: _bits("circle", speed=0.2, depth=2, radius=0, direction="cw"),
        INVALID_PLAN,
        "radius",
    ),
    "circle speed 0": (
        lambda: _bits("circle", speed=0, depth=2, radius=3, direction="cw"),
        INVALID_PLAN,
        "speed",
    ),
    "hover for 0 s": (
        lambda: _bits("hover", duration=0, depth=2, heading=0),
        INVALID_PLAN,
        "duration",
    ),
    "speed 1.5 m/s": (
        lambda: _bits("straight", speed=1.5, depth=2, duration=30, heading=0),
        LIMIT_VIOLATION,
        "speed",
    ),
    "depth 20 m": (
        lambda: _bits("straight", speed=0.5, depth=20, duration=30, heading=0),
        LIMIT_VIOLATION,
        "depth",
    ),
    "circle too tight": (
        lambda: _bits("circle", speed=0.5, depth=2, radius=1, direction="cw"),
        LIMIT_VIOLATION,
        "radius",
    ),
}
CODEC_REASONS = {
    "malformed",
    "no_sync",
    "uncorrectable",
    "crc_mismatch",
    "unknown_pattern",
    "field_out_of_range",
    "unused_field_set",
}


@pytest.mark.parametrize("case", list(REJECTS))
def test_every_reject_reason_changes_nothing(case: str) -> None:
    make, reason, field = REJECTS[case]
    agent = _running_agent(Limits(max_depth_m=10.0))
    g = agent.guidance
    before = (agent.active, g.plan, g.mode, g.segment, g.hold, agent.accepted)
    active_json = {
        "pattern": "circle",
        "pattern_id": 3,
        "params": dict(encode_frame("circle", CIRCLE).command.params),
    }
    bits = make()
    if bits is None:
        ack, ref = agent.receive(None, 96, STATE)
    else:
        ack, ref = _receive(agent, bits)
    assert set(ack) == ACK_KEYS
    assert ack["outcome"] == "rejected"
    assert ack["reason"] == reason
    assert ack["field"] == field
    assert isinstance(ack["detail"], str)
    assert ack["detail"]
    assert ack["duplicate"] is False
    assert ack["replan_latency_ms"] is None
    assert ack["waypoints"] is None
    assert ack["seq"] == 2
    assert ack["active"] == active_json
    assert ref is None
    json.dumps(ack)
    if bits is None:
        assert ack["frame_hex"] is None
    else:
        assert ack["frame_hex"] == f"{bits:025x}"
    if reason in CODEC_REASONS:
        assert ack["command"] is None
        assert ack["corrected_bits"] is None
        assert ack["decode_latency_ms"] is None
    else:  # decoded, then refused: what was asked is reported
        assert ack["command"] is not None
        assert isinstance(ack["decode_latency_ms"], float)
        assert ack["decode_latency_ms"] > 0.0
        assert ack["corrected_bits"] == 0
    # nothing changed
    assert (agent.active, g.plan, g.mode, g.segment, g.hold, agent.accepted) == before
    assert agent.active is before[0]
    assert g.plan is before[1]
    assert agent.rejected == 1


def test_malformed_length_is_reported() -> None:
    agent = _agent()
    ack, _ = agent.receive(_bits("circle", **CIRCLE), 99, STATE)
    assert ack["reason"] == "malformed"
    assert "99" in ack["detail"]
    assert agent.active is None
    assert agent.guidance.mode is Mode.IDLE


def test_limit_violation_reports_every_broken_limit() -> None:
    agent = _agent(Limits(max_depth_m=10.0))
    ack, _ = _receive(agent, _bits("straight", speed=1.5, depth=20, duration=30, heading=0))
    assert ack["reason"] == LIMIT_VIOLATION
    assert ack["field"] == "depth"  # the first one
    assert "depth 20" in ack["detail"]
    assert "speed 1.5" in ack["detail"]


def test_a_rejected_first_frame_leaves_the_vehicle_idle() -> None:
    agent = _agent()
    ack, _ = _receive(agent, _bits("straight", speed=1.5, depth=2, duration=30, heading=0))
    assert ack["outcome"] == "rejected"
    assert ack["active"] is None
    assert agent.active is None
    assert agent.guidance.plan is None
    assert agent.guidance.mode is Mode.IDLE


# --- duplicates and surface ------------------------------------------------------------------


def test_duplicate_of_the_active_command_is_acknowledged_without_replanning() -> None:
    agent = _running_agent()
    g = agent.guidance
    before = (agent.active, g.plan, g.segment, g.mode)
    # the same command, even received with a corrected bit error
    ack, ref = _receive(agent, _flip_codeword(_bits("circle", **CIRCLE), 17))
    assert ack["outcome"] == "accepted"
    assert ack["duplicate"] is True
    assert ack["corrected_bits"] == 1
    assert ack["replan_latency_ms"] is None
    assert ack["waypoints"] is None
    assert isinstance(ack["decode_latency_ms"], float)
    assert "already active" in ack["detail"]
    assert ack["active"] == ack["command"]
    assert ref is None
    assert agent.active is before[0]
    assert g.plan is before[1]
    assert (g.segment, g.mode) == before[2:]
    assert agent.accepted == 2


def test_a_different_command_replans_and_an_earlier_one_is_no_duplicate() -> None:
    agent = _running_agent()
    first = agent.active
    ack, _ = _receive(agent, _bits("circle", speed=0.2, depth=2, radius=3, direction="ccw"))
    assert ack["duplicate"] is False
    second = agent.active
    assert second is not first
    assert agent.guidance.plan is second
    assert agent.guidance.segment == 0
    ack, _ = _receive(agent, _bits("circle", **CIRCLE))
    assert ack["duplicate"] is False
    assert agent.active is not second
    assert ack["active"]["params"]["direction"] == "cw"


def test_surface_is_accepted_whatever_the_limits() -> None:
    # the vehicle (2 m deep, at the origin) is deeper than allowed and outside the geofence
    limits = Limits(max_depth_m=1.0, geofence=CircleFence(1.0, (50.0, 50.0)))
    agent = _running_agent(Limits())
    agent.limits = limits
    before = agent.active
    for bits in (
        _bits("circle", **{**CIRCLE, "direction": "ccw"}),
        _bits("hover", duration=60, depth=0.5, heading=0),
    ):
        ack, _ = _receive(agent, bits)
        assert ack["reason"] == LIMIT_VIOLATION
    assert agent.active is before
    surface = encode_frame("surface", {})
    # the surfacing plan itself breaks the fence ...
    assert validate(plan(surface.command, STATE), limits)
    # ... and is flown all the same
    ack, ref = _receive(agent, surface.frame.value)
    assert ack["outcome"] == "accepted"
    assert ack["command"] == {"pattern": "surface", "pattern_id": 15, "params": {}}
    assert ack["active"] == ack["command"]
    assert agent.guidance.mode is Mode.SURFACING
    assert ref is not None
    assert ref.depth_m == 0.0
    assert ref.speed_mps == 0.0
    # repeated until acknowledged: a duplicate, still surfacing
    ack, _ = _receive(agent, surface.frame.value)
    assert ack["duplicate"] is True
    assert agent.guidance.mode is Mode.SURFACING


def test_seq_increments_per_frame_whatever_the_outcome() -> None:
    agent = _agent()
    circle = _bits("circle", **CIRCLE)
    outcomes = []
    for k, bits in enumerate([circle, None, circle, _no_sync(), _flip_codeword(circle, 1, 2, 3)]):
        if bits is None:
            ack, _ = agent.receive(None, 104, STATE)
        else:
            ack, _ = _receive(agent, bits)
        assert ack["seq"] == k + 1
        outcomes.append(ack["outcome"])
    assert outcomes == ["accepted", "rejected", "accepted", "rejected", "rejected"]
    assert agent.seq == 5
    assert (agent.accepted, agent.rejected) == (2, 3)


def test_the_console_reproduces_the_vehicles_plan_from_the_ack() -> None:
    agent = _agent()
    first = encode_frame("square", {"speed": 0.2, "depth": 2, "side_span": 8, "direction": "cw"})
    ack1, _ = agent.receive(first.frame.value, FRAME_BITS, STATE)
    mirror = plan(decode_frame(first.frame.bits).command, VehicleState(**ack1["from"]))
    assert agent.active is not None
    assert mirror.path == agent.active.path
    moved = VehicleState(3.0, 4.0, 2.0, 90.0, 0.2, 40.0, 2)
    second = encode_frame("circle", CIRCLE)
    ack2, _ = agent.receive(second.frame.value, FRAME_BITS, moved)
    again = plan(decode_frame(second.frame.bits).command, VehicleState(**ack2["from"]), mirror)
    assert agent.active is not None
    assert again.path == agent.active.path and again.anchor == agent.active.anchor


# --- without navigation --------------------------------------------------------------------

STALE = NoNavigation("navigation stale: the last odometry is 5.0 s old", last_known=True)
NONE_YET = NoNavigation("no navigation yet: no odometry has arrived", last_known=False)


@pytest.mark.parametrize("navigation", [STALE, NONE_YET], ids=["stale", "none yet"])
def test_without_navigation_a_command_is_rejected_and_changes_nothing(
    navigation: NoNavigation,
) -> None:
    agent = _running_agent()
    g = agent.guidance
    before = (agent.active, g.plan, g.mode, g.segment, g.hold)
    for bits in (_bits("hover", duration=60, depth=2, heading=0), _bits("circle", **CIRCLE)):
        ack, ref = agent.receive(bits, FRAME_BITS, STATE, navigation=navigation)
        assert set(ack) == ACK_KEYS
        assert (ack["outcome"], ack["reason"]) == ("rejected", NO_NAVIGATION)
        assert ack["detail"] == navigation.detail
        assert ack["duplicate"] is False  # the active command too: it cannot be confirmed
        assert ack["command"] is not None and isinstance(ack["decode_latency_ms"], float)
        assert ref is None
    assert (agent.active, g.plan, g.mode, g.segment, g.hold) == before
    # a frame that does not decode keeps its own reason
    ack, _ = agent.receive(_no_sync(), FRAME_BITS, STATE, navigation=navigation)
    assert ack["reason"] == "no_sync"


def test_surface_without_navigation_is_flown_from_the_last_known_state_only() -> None:
    surface = encode_frame("surface", {}).frame.value
    ack, _ = _agent().receive(surface, FRAME_BITS, STATE, navigation=NONE_YET)
    assert ack["reason"] == NO_NAVIGATION  # no state at all: nothing to plan from
    agent = _running_agent()
    ack, ref = agent.receive(surface, FRAME_BITS, STATE, navigation=STALE)
    assert ack["outcome"] == "accepted"
    assert ack["from"] == STATE.as_dict()
    assert ref is not None and ref.depth_m == 0.0
    assert agent.guidance.mode is Mode.SURFACING


def test_a_suspended_command_sent_again_is_replanned() -> None:
    agent = _running_agent()
    first = agent.active
    agent.suspend()
    later = VehicleState(5.0, 5.0, 2.0, 45.0, 0.1, 60.0)
    ack, ref = agent.receive(_bits("circle", **CIRCLE), FRAME_BITS, later)
    assert (ack["outcome"], ack["duplicate"]) == ("accepted", False)
    assert ack["from"] == later.as_dict()
    assert agent.active is not first and ref is not None
    assert agent.suspended is False
    ack, _ = agent.receive(_bits("circle", **CIRCLE), FRAME_BITS, later)
    assert ack["duplicate"] is True
    idle = _agent()
    idle.suspend()  # nothing to suspend
    assert idle.suspended is False


def test_the_recent_acks_are_the_newest_and_age_out() -> None:
    agent = _agent()
    acks = []
    for k in range(RECENT_ACKS_MAX + 3):
        state = VehicleState(0.0, 0.0, 2.0, 0.0, 0.0, 100.0 + k)
        acks.append(agent.receive(None, 8, state)[0])
    recent = agent.recent_acks(100.0 + RECENT_ACKS_MAX + 2)
    assert recent == acks[-RECENT_ACKS_MAX:]
    assert all(a is b for a, b in zip(recent, acks[-RECENT_ACKS_MAX:], strict=True))
    assert agent.recent_acks(100.0 + RECENT_ACKS_MAX + 2 + RECENT_ACKS_S) == [acks[-1]]
    assert agent.recent_acks(1e9) == []
