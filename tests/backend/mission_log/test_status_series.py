"""The dive's status series in the track (issue 22, item 3): commanded depth, navigation
validity and its age logged beside each point, points without a position while the navigation
is not valid, an older log opened with its track made able to hold them, and the console's
monotonic-anchored UTC that stamps every row."""

from __future__ import annotations

import sqlite3
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pytest

from backend.clock import AnchoredUtc
from backend.dives import Dives
from backend.mission_log.series import dive_series
from backend.mission_log.store import MissionLog

CIRCLE: dict[str, Any] = {
    "pattern": "circle",
    "params": {"speed": 0.18, "depth": 3.0, "radius": 5.0},
}
HELIX: dict[str, Any] = {
    "pattern": "helix",
    "params": {"speed": 0.2, "end_depth": 8.5, "radius": 4.0},
}


@pytest.fixture
def log(tmp_path: Path) -> Iterator[MissionLog]:
    opened = MissionLog(tmp_path / "missions.sqlite3")
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


#: The track as issue 20 left it: the position NOT NULL, no navigation columns.
ISSUE_20_TRACK = """
CREATE TABLE dives (id INTEGER PRIMARY KEY, started_at TEXT NOT NULL, target TEXT NOT NULL);
CREATE TABLE track (
    dive INTEGER NOT NULL REFERENCES dives(id),
    t_s REAL NOT NULL,
    x_m REAL NOT NULL,
    y_m REAL NOT NULL,
    z_m REAL NOT NULL,
    heading_deg REAL NOT NULL,
    depth_m REAL,
    speed_mps REAL,
    battery_pct REAL,
    mode TEXT,
    active TEXT,
    at TEXT
);
CREATE INDEX track_dive ON track(dive, t_s);
"""


def test_an_older_track_is_opened_with_its_rows_and_takes_points_without_position(
    tmp_path: Path,
) -> None:
    db = tmp_path / "old.sqlite3"
    raw = sqlite3.connect(db)
    raw.executescript(ISSUE_20_TRACK)
    raw.execute("INSERT INTO dives VALUES (1, '2025-01-01T10:00:00.000+00:00', 'sim')")
    # inserted out of time order: the copy keeps the arrival order (rowid) as well
    for t_s in (3.0, 1.0, 2.0):
        raw.execute(
            "INSERT INTO track VALUES (1, ?, 1, 2, 3, 4, 3.5, 0.2, 88, 'running', ?, ?)",
            (t_s, '{"pattern": "circle", "params": {"depth": 3}}', f"2025-01-01T10:00:0{t_s:.0f}Z"),
        )
    raw.commit()
    raw.close()

    log = MissionLog(db)
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as ro:
            info = {r[1]: bool(r[3]) for r in ro.execute("PRAGMA table_info(track)")}
            order = [r[0] for r in ro.execute("SELECT t_s FROM track ORDER BY rowid")]
            indexes = {r[1] for r in ro.execute("PRAGMA index_list(track)")}
        ro.close()
        assert not any(info[c] for c in ("x_m", "y_m", "z_m", "heading_deg"))
        assert {"commanded_depth_m", "nav_valid", "nav_age_s"} <= set(info)
        assert order == [3.0, 1.0, 2.0] and "track_dive" in indexes
        rows = log.track_rows(1)
        assert [r["t_s"] for r in rows] == [1.0, 2.0, 3.0]
        assert rows[0]["battery_pct"] == 88 and rows[0]["nav_valid"] is None
        assert dive_series(rows, 10)["commanded_depth_m"] == [3.0, 3.0, 3.0]
        log.add_status_point(1, 4.0, {"nav_valid": False, "mode": "nav_fault"})
        assert [r["x_m"] for r in log.track_rows(1, positioned=False)][-1] is None
    finally:
        log.close()
    MissionLog(db).close()  # opening it again changes nothing and does not fail


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
