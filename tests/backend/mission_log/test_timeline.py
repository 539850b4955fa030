"""A dive on one clock for the replay's slider (backend/mission_log/timeline.py)."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta
from typing import Any

import pytest

from backend.mission_log.timeline import (
    dive_clock,
    dive_timeline,
    link_events,
    position_at,
    running_command,
    vehicle_at,
)

T0 = datetime(2025, 5, 1, 12, 0, 0, tzinfo=UTC)
CIRCLE: dict[str, Any] = {
    "pattern": "circle",
    "params": {"speed": 0.18, "depth": 3.0, "radius": 5.0},
}


def iso(seconds: float) -> str:
    """The station's clock ``seconds`` after T0, as the log writes it."""
    return (T0 + timedelta(seconds=seconds)).isoformat(timespec="milliseconds")


def row(t_s: float, at_s: float | None, **fields: Any) -> dict[str, Any]:
    """A track row: the vehicle's clock ``t_s``, arrived at station second ``at_s``."""
    base = {"x_m": t_s, "y_m": 0.0, "z_m": 2.0, "heading_deg": 0.0, "mode": "running"}
    return {"t_s": t_s, **base, "active": None, "at": None if at_s is None else iso(at_s), **fields}


def command(cid: int, sent_s: float | None, **fields: Any) -> dict[str, Any]:
    return {
        "id": cid,
        **CIRCLE,
        "kind": "command",
        "state": "sent",
        "copies": 2,
        "first_sent_at": None if sent_s is None else iso(sent_s),
        "sent_at": None if sent_s is None else iso(sent_s),
        "ack": None,
        **fields,
    }


def test_the_station_clock_maps_onto_the_dives_through_the_track() -> None:
    # the vehicle's clock runs 10x the station's (a simulator at time scale 10), from 100 s
    rows = [row(100.0 + 10 * k, 5.0 + k) for k in range(5)]
    clock = dive_clock(rows, iso(0))
    assert clock(iso(5.0)) == pytest.approx(0.0)
    assert clock(iso(6.5)) == pytest.approx(15.0)  # between two points
    assert clock(iso(10.0)) == pytest.approx(50.0)  # after the last: at the track's rate
    assert clock(iso(4.0)) == pytest.approx(-10.0)  # before the first (a command sent first)
    assert clock(None) is None and clock("not a time") is None
    # no track (a one-way modem without telemetry): station seconds from the dive's start
    station = dive_clock([], iso(0))
    assert station(iso(7.25)) == pytest.approx(7.25)


def test_the_running_command_is_the_newest_sent_with_the_same_values() -> None:
    older, newer = command(1, 1.0), command(2, 2.0)
    snapped = {"pattern": "circle", "params": {**CIRCLE["params"], "speed": 0.18 + 1e-9}}
    assert running_command(snapped, [older, newer]) == 2
    other = {"pattern": "circle", "params": {**CIRCLE["params"], "radius": 6.0}}
    assert running_command(other, [older, newer]) is None  # not sent by this console
    assert running_command(None, [older]) is None


def test_link_events_in_time_order_on_the_dives_clock() -> None:
    rows = [row(100.0 + k, 10.0 + k) for k in range(20)]
    acked = command(
        1,
        11.0,
        sent_at=iso(13.0),
        state="acknowledged",
        ack={"outcome": "accepted", "t_s": 103.5, "corrected_bits": 2},
    )
    rejected = command(
        2, 15.0, state="rejected", ack={"outcome": "rejected", "detail": "speed too high"}
    )
    rejected["acked_at"] = iso(16.0)
    lost = command(3, 17.0, state="timed_out", updated_at=iso(19.0))
    never = command(4, None, state="failed", updated_at=None)
    events = [{"at": iso(18.0), "kind": "echo_mismatch", "detail": "the vehicle runs square"}]
    placed, unplaced = link_events(
        [acked, rejected, lost, never], events, dive_clock(rows, iso(0)), 100.0
    )
    assert [(e["t_s"], e["kind"], e["command_id"]) for e in placed] == [
        (pytest.approx(1.0), "sent", 1),
        (pytest.approx(3.0), "sent", 1),  # its last copy
        (pytest.approx(3.5), "acknowledged", 1),  # the vehicle's own t_s
        (pytest.approx(5.0), "sent", 2),
        (pytest.approx(6.0), "rejected", 2),
        (pytest.approx(7.0), "sent", 3),
        (pytest.approx(8.0), "echo_mismatch", None),
        (pytest.approx(9.0), "timed_out", 3),
    ]
    assert "corrected 2 bits" in placed[2]["text"] and "speed too high" in placed[4]["text"]
    assert unplaced == 1  # the failed command's end has no time


def test_position_between_samples_and_the_heading_the_short_way() -> None:
    samples: list[dict[str, Any]] = [
        {"t_s": 0.0, "x_m": 0.0, "y_m": 0.0, "z_m": 1.0, "heading_deg": 350.0, "pattern": None},
        {"t_s": 2.0, "x_m": 4.0, "y_m": 2.0, "z_m": 3.0, "heading_deg": 10.0, "pattern": "circle"},
    ]
    at = position_at(samples, 0.5)
    assert (at["x_m"], at["y_m"], at["z_m"]) == pytest.approx((1.0, 0.5, 1.5))
    assert at["heading_deg"] == pytest.approx(355.0)  # through north, not through south
    assert at["pattern"] is None  # what it ran at the sample before
    assert position_at(samples, 9.0)["x_m"] == 4.0 and position_at(samples, 9.0)["pattern"]


def test_the_timeline_and_the_vehicle_at_a_time() -> None:
    c = command(7, 12.5, state="acknowledged")
    rows = [row(100.0 + k, 10.0 + k, active=CIRCLE if k >= 3 else None) for k in range(10)]
    doc = dive_timeline(rows, [c], [], iso(0))
    assert doc["start_t_s"] == 100.0 and doc["from_t_s"] == 0.0
    assert doc["duration_s"] == pytest.approx(9.0)
    assert [s["command_id"] for s in doc["samples"]] == [None] * 3 + [7] * 7
    assert [s["pattern"] for s in doc["samples"]][2:4] == [None, "circle"]
    assert doc["commands"][0]["sent_t_s"] == pytest.approx(2.5)
    span, at = vehicle_at(rows, [c], [], iso(0), 4.5)
    assert span[0] == 0.0 and span[1] == pytest.approx(9.0)
    assert at is not None and at["x_m"] == pytest.approx(104.5) and at["command_id"] == 7
    assert vehicle_at([], [c], [], iso(0), 1.0)[1] is None  # no track: no position
