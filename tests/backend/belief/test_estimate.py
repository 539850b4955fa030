"""A belief from hand-made evidence (records as the mission log writes them, echoes, a fix):
which command, with what probability and why; where, from what; the Surface from its record."""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

import pytest

from backend.belief.commands import Echo
from backend.belief.estimate import Evidence, estimate
from backend.belief.position import FRESH_TELEMETRY_S, HOLD_DRIFT_M, Fix, Start
from backend.belief.reckoning import FIX_SIGMA_M, Current
from backend.chart.geo import TRAINING_DATUM
from codec import encode_frame
from planner import VehicleState

NOW = 1_700_000_000.0
CIRCLE: dict[str, float | str] = {"speed": 0.18, "depth": 3.0, "radius": 5.0, "direction": "cw"}
START = Start(VehicleState(0.0, 0.0, 2.0), "the simulator's start")
STILL = Current(0.0, 0.0, 0.0, "none")


def iso(t: float) -> str:
    return datetime.fromtimestamp(t, UTC).isoformat(timespec="milliseconds")


def rec(
    cid: int, pattern: str, sent_s: float | None, state: str, p: float, copies_sent: int = 1
) -> dict[str, Any]:
    params: dict[str, float | str] = CIRCLE if pattern == "circle" else {}
    enc = encode_frame(pattern, params)
    return {
        "id": cid,
        "kind": "surface" if pattern == "surface" else "command",
        "pattern": pattern,
        "params": dict(enc.command.params),
        "bits": enc.frame.bits,
        "state": state,
        "copies": copies_sent,
        "copies_sent": copies_sent,
        "p_delivered": p,
        "ber": 1e-3,
        "two_way": False,
        "reason": None,
        "superseded_by": None,
        "created_at": iso((sent_s or NOW) - 0.1),
        "updated_at": iso(sent_s or NOW),
        "first_sent_at": None if sent_s is None else iso(sent_s),
    }


def evidence(**changes: Any) -> Evidence:
    values: dict[str, Any] = {
        "vehicle": "nemesys",
        "now_s": NOW,
        "time_scale": 1.0,
        "two_way": False,
        "records": [],
        "last_sent": None,
        "accepted": None,
        "echo": None,
        "mirror": None,
        "fix": None,
        "start": START,
        "current": STILL,
        "datum": TRAINING_DATUM,
        "top_speed_mps": 0.19,
    } | changes
    return Evidence(**values)


def test_one_way_the_newest_delivered_wins() -> None:
    circle = rec(1, "circle", NOW - 30, "superseded", 0.9)
    surface = rec(2, "surface", NOW - 20, "sent", 0.99, copies_sent=3)
    retry = rec(3, "circle", NOW - 10, "sent", 0.8)
    b = estimate(evidence(records=[circle, surface, retry], last_sent=retry))
    assert b.last_sent is not None and b.last_sent.id == 3
    assert (b.command.id, b.command.kind) == (3, "command")
    assert b.command.p == pytest.approx(0.8)
    assert b.runner_up is not None and b.runner_up.id == 2
    assert b.runner_up.p == pytest.approx(0.99 * 0.2)
    assert b.command.reason == "one-way link: 1 copy left, p(delivered) 80 %"
    assert b.runner_up.reason.endswith("the newer command did not arrive")


def test_one_way_the_rest_is_the_unknown_last_state() -> None:
    b = estimate(evidence(records=[rec(1, "circle", NOW - 5, "sent", 0.6)]))
    assert b.command.id == 1 and b.command.p == pytest.approx(0.6)
    assert b.runner_up is not None and b.runner_up.kind == "unknown"
    assert b.runner_up.p == pytest.approx(0.4)
    assert "no telemetry" in b.runner_up.reason


def test_one_way_with_telemetry_the_status_is_the_last_known_state() -> None:
    old = rec(1, "circle", NOW - 60, "sent", 0.9)
    echo = Echo(None, NOW - 30, "status")  # the vehicle said it holds, after the circle
    b = estimate(evidence(records=[old], echo=echo))
    assert b.command.kind == "last_known" and b.command.pattern is None
    assert b.command.p == 1.0 and b.runner_up is None
    assert "no command sent since" in b.command.reason


def test_no_fix_ever_the_position_is_assumed_and_says_what() -> None:
    b = estimate(evidence())
    p = b.position
    assert p.source == "assumed" and p.sigma_m is None and p.age_s is None
    assert (p.x_m, p.y_m, p.z_m) == (0.0, 0.0, 2.0)
    assert p.basis == "the simulator's start, no fix ever"
    assert p.lat_deg == pytest.approx(TRAINING_DATUM.lat_deg)
    assert b.command.kind == "unknown" and b.command.p == 1.0


def test_a_fresh_fix_is_the_position() -> None:
    fix = Fix(VehicleState(3.0, 4.0, 2.5, 90.0, 0.2, 100.0), NOW - 1.0, "pose")
    p = estimate(evidence(fix=fix)).position
    assert p.source == "telemetry" and (p.x_m, p.y_m, p.z_m) == (3.0, 4.0, 2.5)
    assert p.sigma_m == pytest.approx(FIX_SIGMA_M + 0.2 * 1.0)  # it may have moved since
    assert p.age_s == pytest.approx(1.0)


def test_freshness_is_on_the_vehicle_clock() -> None:
    fix = Fix(VehicleState(3.0, 4.0, 2.5, 90.0, 0.2, 100.0), NOW - 1.0, "pose")
    fast = estimate(evidence(fix=fix, time_scale=FRESH_TELEMETRY_S + 1)).position
    assert fast.source == "dead_reckoning"  # a 1 s old fix at 4x is 4 vehicle seconds old
    known = estimate(evidence(fix=fix, time_scale=50.0, vehicle_now_s=102.0)).position
    assert known.source == "telemetry"  # the simulator's own clock says 2 s


def test_a_stale_fix_holding_stays_and_its_uncertainty_grows() -> None:
    fix = Fix(VehicleState(3.0, 4.0, 2.5, 90.0, 0.0, 100.0), NOW - 20.0, "pose")
    echo = Echo(None, NOW - 20.0, "status")
    p = estimate(evidence(fix=fix, echo=echo)).position
    assert p.source == "dead_reckoning" and (p.x_m, p.y_m) == (3.0, 4.0)
    # it keeps station: no current carries it off, it drifts to its capture radius at most
    assert p.sigma_m == pytest.approx(FIX_SIGMA_M + HOLD_DRIFT_M)
    assert p.basis == "the last fix (pose) 20.0 s ago, then holding (as last reported)"


def test_a_command_sent_after_the_fix_moves_the_belief_and_the_spread_counts() -> None:
    fix = Fix(VehicleState(0.0, 0.0, 3.0, 0.0, 0.0, 100.0), NOW - 100.0, "pose")
    echo = Echo(None, NOW - 100.0, "status")
    sure = estimate(evidence(fix=fix, echo=echo, records=[rec(1, "circle", NOW - 90, "sent", 1)]))
    half = estimate(evidence(fix=fix, echo=echo, records=[rec(1, "circle", NOW - 90, "sent", 0.5)]))
    moved = (sure.position.x_m**2 + sure.position.y_m**2) ** 0.5
    assert moved > 4.0  # on the 5 m circle about the fix (its anchor), 90 s in
    assert (half.position.x_m, half.position.y_m) == (sure.position.x_m, sure.position.y_m)
    assert half.position.sigma_m is not None and sure.position.sigma_m is not None
    # the other half: holding at the fix, that far away
    assert half.position.sigma_m**2 == pytest.approx(
        sure.position.sigma_m**2 + 0.5 * moved**2, rel=1e-6
    )


def test_two_way_the_echo_decides() -> None:
    circle = rec(1, "circle", NOW - 30, "acknowledged", 1.0)
    echo = Echo({"pattern": "circle", "params": circle["params"]}, NOW - 1, "status")
    b = estimate(evidence(two_way=True, records=[circle], accepted=circle, echo=echo))
    assert (b.command.id, b.command.p) == (1, 1.0) and b.runner_up is None
    assert b.command.reason.endswith("command 1 (acknowledged)")
    other = Echo({"pattern": "hover", "params": {}}, NOW - 1, "status")
    b = estimate(evidence(two_way=True, records=[circle], accepted=circle, echo=other))
    assert b.command.kind == "last_known" and b.command.pattern == "hover"
    assert "not a command of this console" in b.command.reason
    assert b.runner_up is not None and b.runner_up.id == 1 and b.runner_up.p == 0.0


def test_the_surface_from_its_record_only() -> None:
    going = rec(4, "surface", NOW - 2, "transmitted", 0.9)
    s = estimate(evidence(records=[rec(3, "circle", NOW - 9, "sent", 1), going])).surface
    assert s.in_progress and s.id == 4 and s.state == "transmitted"
    assert s.changed_s == pytest.approx(2.0, abs=0.01)
    done = estimate(evidence(records=[{**going, "state": "acknowledged"}])).surface
    assert not done.in_progress and done.id == 4
    none = estimate(evidence()).surface
    assert not none.in_progress and none.id is None
