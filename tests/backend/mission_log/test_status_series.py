"""The dive's status series in the track (issue 22, item 3): commanded depth, navigation
validity and its age logged beside each point, points without a position while the navigation
is not valid, an older log opened with its track made able to hold them (migration 0006), and
the console's monotonic-anchored UTC that stamps every row; on both back-ends (``log_backend``)."""

from __future__ import annotations

from collections.abc import Iterator
from datetime import UTC, datetime
from typing import Any

import pytest

from backend.clock import AnchoredUtc
from backend.dives import Dives
from backend.mission_log.database import open_database
from backend.mission_log.dive_reader import open_read_only, snapshot
from backend.mission_log.migrating import migrate
from backend.mission_log.series import dive_series
from backend.mission_log.store import MissionLog
from tests.backend.log_backend import LogBackend

CIRCLE: dict[str, Any] = {
    "pattern": "circle",
    "params": {"speed": 0.18, "depth": 3.0, "radius": 5.0},
}
HELIX: dict[str, Any] = {
    "pattern": "helix",
    "params": {"speed": 0.2, "end_depth": 8.5, "radius": 4.0},
}


@pytest.fixture
def log(log_backend: LogBackend) -> Iterator[MissionLog]:
    opened = log_backend.open()
    yield opened
    opened.close()


def test_a_point_keeps_the_commanded_depth_and_the_navigation(log: MissionLog) -> None:
    dive = log.new_dive("sim")
    log.add_track(
        dive,
        10.0,
        1.0,
        2.0,
        3.0,
        90.0,
        {"depth_m": 3.1, "active": HELIX, "nav_valid": True, "nav_age_s": 0.2},
    )
    log.add_track(dive, 11.0, 1.0, 2.0, 3.0, 90.0, {"active": CIRCLE, "nav_valid": "yes"})
    first, second = log.track_rows(dive)
    assert first["commanded_depth_m"] == 8.5 and first["nav_valid"] is True
    assert first["nav_age_s"] == 0.2 and first["at"] is not None
    # a nav_valid that is not a boolean is not said (a 1.x vehicle: taken as true)
    assert second["commanded_depth_m"] == 3.0 and second["nav_valid"] is None


def test_a_status_without_navigation_makes_a_point_without_a_position(log: MissionLog) -> None:
    dives = Dives(log, "sim")
    dives.track((100.0, 1.0, 2.0, 3.0, 45.0), {"nav_valid": True, "battery_pct": 90.0})
    fault = {"t_s": 101.0, "nav_valid": False, "nav_age_s": 6.5, "mode": "nav_fault"}
    dives.status({**fault, "heading_deg": None, "depth_m": None})
    dives.status({**fault, "t_s": 101.5})  # within the second: not kept
    dives.status({"t_s": 103.0, "nav_valid": True})  # valid: its pose makes the point
    dives.status({"t_s": None, "nav_valid": False})  # no time: not placed
    dives.track((104.0, 1.5, 2.0, 3.0, 50.0), {"nav_valid": True})
    assert dives.current is not None
    rows = log.track_rows(dives.current, positioned=False)
    assert [r["t_s"] for r in rows] == [100.0, 101.0, 104.0]
    nav = rows[1]
    assert nav["x_m"] is None and nav["heading_deg"] is None and nav["nav_valid"] is False
    assert nav["mode"] == "nav_fault" and nav["nav_age_s"] == 6.5
    # the track of positions (the chart, the replay) leaves it out
    assert [r["t_s"] for r in log.track_rows(dives.current)] == [100.0, 104.0]
    assert [p["t_s"] for p in log.track(dives.current)] == [100.0, 104.0]
    series = dive_series(rows, 3600)
    assert series["nav_valid"] == [True, False, True]
    assert series["depth_m"] == [3.0, None, 3.0]  # no depth said, no pose: unknown
    assert series["mode"] == [None, "nav_fault", None]


def test_an_older_rows_commanded_depth_comes_from_its_active_command() -> None:
    old: dict[str, Any] = {"t_s": 5.0, "x_m": 0.0, "y_m": 0.0, "z_m": 1.0, "heading_deg": 0.0}
    old |= {"depth_m": None, "speed_mps": None, "battery_pct": None, "active": CIRCLE}
    logged = {**old, "t_s": 6.0, "commanded_depth_m": 4.0}  # the logged value wins
    assert dive_series([old, logged], 10)["commanded_depth_m"] == [3.0, 4.0]


def test_an_older_track_is_migrated_with_its_rows_and_takes_points_without_position(
    log_backend: LogBackend,
) -> None:
    """A log migrated up to 0005 (issue 20's track: the position NOT NULL, no navigation
    columns) is brought to 0006 at open: the columns added, the position nullable (SQLite:
    the table made again), its rows kept in their arrival order, its index kept."""
    old = open_database(log_backend.where, 1.0)
    try:
        migrate(old, to="0005")
        old.execute("INSERT INTO dives (id, started_at, target) VALUES (1, 't0', 'sim')")
        # inserted out of time order: the copy keeps the arrival order as well
        for n, t_s in enumerate((3.0, 1.0, 2.0)):
            old.execute(
                "INSERT INTO track VALUES (1, ?, 1, 2, 3, 4, 3.5, 0.2, 88, 'running', ?, ?)",
                (t_s, '{"pattern": "circle", "params": {"depth": 3}}', f"2025-01-01T10:00:0{n}Z"),
            )
    finally:
        old.close()
    with pytest.raises(log_backend.integrity_error):  # the position was NOT NULL
        log_backend.query("INSERT INTO track (dive, t_s) VALUES (1, 9.0)")

    log = log_backend.open()
    try:
        if log_backend.postgres:
            info = {
                str(name): nullable == "YES"
                for name, nullable in log_backend.query(
                    "SELECT column_name, is_nullable FROM information_schema.columns "
                    "WHERE table_name = 'track'"
                )
            }
            indexes = {r[0] for r in log_backend.query("SELECT indexname FROM pg_indexes")}
        else:
            info = {str(r[1]): not r[3] for r in log_backend.query("PRAGMA table_info(track)")}
            indexes = {r[1] for r in log_backend.query("PRAGMA index_list(track)")}
        assert all(info[c] for c in ("x_m", "y_m", "z_m", "heading_deg"))
        assert {"commanded_depth_m", "nav_valid", "nav_age_s"} <= set(info)
        assert "track_dive" in indexes
        reader = open_read_only(log_backend.where)
        try:
            with snapshot(reader) as dive:
                assert [r["t_s"] for r in dive.track(1)] == [3.0, 1.0, 2.0]  # arrival order
        finally:
            reader.close()
        rows = log.track_rows(1)
        assert [r["t_s"] for r in rows] == [1.0, 2.0, 3.0]
        assert rows[0]["battery_pct"] == 88 and rows[0]["nav_valid"] is None
        assert dive_series(rows, 10)["commanded_depth_m"] == [3.0, 3.0, 3.0]
        log.add_status_point(1, 4.0, {"nav_valid": False, "mode": "nav_fault"})
        last = log.track_rows(1, positioned=False)[-1]
        assert last["x_m"] is None and last["nav_valid"] is False
    finally:
        log.close()
    log_backend.open().close()  # opening it again changes nothing and does not fail
    assert log_backend.scalar("SELECT COUNT(*) FROM track") == 4


def test_the_consoles_utc_moves_with_the_monotonic_clock_only() -> None:
    wall = [1_700_000_000.0]
    mono = [50.0]
    clock = AnchoredUtc(lambda: wall[0], lambda: mono[0])
    mono[0] += 2.5
    wall[0] -= 3600.0  # the system clock stepped back an hour: not seen
    assert clock.now_s() == 1_700_000_002.5
    assert clock.now() == datetime.fromtimestamp(1_700_000_002.5, UTC)


def test_every_stamp_of_a_dive_is_on_the_consoles_clock(
    log: MissionLog, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The commands', the events' and the track's stamps come from one clock, so they order
    against each other: a stepped system clock cannot put an event before the command that
    caused it."""
    from backend.mission_log import store

    mono = [0.0]
    monkeypatch.setattr(store, "CONSOLE_UTC", AnchoredUtc(lambda: 1_700_000_000.0, lambda: mono[0]))
    dive = log.new_dive("sim")
    stamps: list[Any] = []
    for step in range(3):
        mono[0] += 1.0
        log.add_track(dive, float(step), 0.0, 0.0, 1.0, 0.0)
        mono[0] += 0.25
        stamps.append(log.add_event(dive, "note", f"event {step}")["at"])
    at = [r["at"] for r in log.track_rows(dive)]
    assert at[0] == "2023-11-14T22:13:21.000+00:00"
    merged = sorted(at + stamps)
    assert merged == [x for pair in zip(at, stamps, strict=True) for x in pair]
