"""The exports' reader of a dive (backend/mission_log/dive_reader.py over read_only.py) on both
back-ends (``log_backend``): one snapshot (rows the console writes meanwhile are not seen, the
counts and the rows agree), a connection that cannot write, rows streamed from a cursor (a
server-side one on PostgreSQL), the track in arrival order, and the console's own export
connection (``MissionLog.exporting``) with the track buffer written first."""

from __future__ import annotations

import pytest

from backend.mission_log.dive_reader import NoSuchDive, open_read_only, snapshot
from backend.mission_log.store import MissionLog
from tests.backend.log_backend import LogBackend


def test_a_snapshot_sees_the_log_as_it_was_at_its_first_query(log_backend: LogBackend) -> None:
    log = log_backend.open()
    reader = open_read_only(log_backend.where)
    try:
        dive = log.new_dive("sim")
        for t_s in (3.0, 1.0, 2.0):  # arriving out of the vehicle's time order
            log.add_track(dive, t_s, t_s, 0.0, 1.0, 0.0, {"nav_valid": True})
        log.flush_track()
        with snapshot(reader) as rows:
            assert rows.counts(dive)["track"] == 3
            log.add_track(dive, 4.0, 4.0, 0.0, 1.0, 0.0)
            log.add_event(dive, "note", "written during the export")
            log.flush_track()
            assert [r["t_s"] for r in rows.track(dive)] == [3.0, 1.0, 2.0]  # arrival order
            assert rows.counts(dive)["track"] == 3 and list(rows.events(dive)) == []
            assert next(rows.track(dive))["nav_valid"] is True
        with snapshot(reader) as rows:  # the next snapshot sees them
            assert rows.counts(dive)["track"] == 4 and len(list(rows.events(dive))) == 1
            with pytest.raises(NoSuchDive, match=r"no dive 9 in the mission log \(its only"):
                rows.dive(9)
    finally:
        reader.close()
        log.close()


def test_the_readers_connection_cannot_write(log_backend: LogBackend) -> None:
    log_backend.open().close()
    reader = open_read_only(log_backend.where)
    try:
        with snapshot(reader), pytest.raises(Exception, match=r"(?i)read-?only"):
            reader.one("INSERT INTO dives (started_at, target) VALUES ('t0', 'sim')")
    finally:
        reader.close()
    assert log_backend.scalar("SELECT COUNT(*) FROM dives") == 0


def test_rows_come_from_a_cursor_a_batch_at_a_time(log_backend: LogBackend) -> None:
    """On PostgreSQL the rows stay on the server until fetched: a named cursor is open while
    the track is read, and closed after (and when a reader is left half-way)."""
    log = log_backend.open()
    dive = log.new_dive("sim")
    for k in range(30):
        log.add_track(dive, float(k), 0.0, 0.0, 1.0, 0.0)
    log.close()
    reader = open_read_only(log_backend.where)
    cursors = "SELECT COUNT(*) AS n FROM pg_cursors WHERE name LIKE 'nemesys_export_%'"
    try:
        with snapshot(reader) as rows:
            track = rows.track(dive)
            assert next(track)["t_s"] == 0.0
            if log_backend.postgres:
                assert reader.one(cursors) == {"n": 1}
            assert [r["t_s"] for r in track] == [float(k) for k in range(1, 30)]
            if log_backend.postgres:
                assert reader.one(cursors) == {"n": 0}
            left = rows.track(dive)
            next(left)  # left half-way: closed with the snapshot
        if log_backend.postgres:
            with snapshot(reader):
                assert reader.one(cursors) == {"n": 0}
        del left
    finally:
        reader.close()


def test_the_consoles_export_connection_has_the_buffered_track(log_backend: LogBackend) -> None:
    log = log_backend.open()
    try:
        dive = log.new_dive("sim")
        log.add_track(dive, 1.0, 1.0, 2.0, 3.0, 4.0)  # buffered, not written yet
        with log.exporting() as db, snapshot(db) as rows:
            assert db.kind == log_backend.kind and not db.shared
            assert [r["x_m"] for r in rows.track(dive)] == [1.0]
    finally:
        log.close()


def test_an_in_memory_log_is_exported_through_its_own_connection() -> None:
    """An in-memory log has no second connection: its own is shared (under its lock), and
    stays open and writable after."""
    log = MissionLog(":memory:")
    try:
        dive = log.new_dive("sim")
        log.add_track(dive, 1.0, 1.0, 2.0, 3.0, 4.0)
        with log.exporting() as db, snapshot(db) as rows:
            assert db.shared and rows.counts(dive)["track"] == 1
        log.add_event(dive, "note", "after the export")
        assert [e["detail"] for e in log.events(dive)] == ["after the export"]
    finally:
        log.close()
