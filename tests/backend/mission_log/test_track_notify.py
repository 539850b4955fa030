"""The track as a console without a transmitter reads it (issue 24, migration 0010 and
:meth:`backend.mission_log.store.MissionLog.newest_track_point`): on PostgreSQL each committed
batch of track points is told once, naming its dive and the writing console; the newest point
of a dive (or of the newest dive) is read with the database's clock, on both back-ends."""

from __future__ import annotations

import json
from typing import Any

import psycopg

from backend.mission_log.track import TRACK_BATCH
from tests.backend.log_backend import LogBackend


def test_each_committed_batch_of_track_points_is_told_once_with_its_dive(
    pg_log: LogBackend,
) -> None:
    log = pg_log.open()
    log.name_console("ship")
    try:
        with psycopg.connect(pg_log.url, autocommit=True) as listener:
            listener.execute("LISTEN nemesys_log")
            dive = log.new_dive("sim")
            for i in range(TRACK_BATCH):  # one batch: written at the TRACK_BATCH-th point
                log.add_track(dive, float(i), 1.0, 2.0, 3.0, 90.0)
            for i in range(3):  # another, written on the flush
                log.add_track(dive, TRACK_BATCH + float(i), 1.0, 2.0, 3.0, 90.0)
            log.flush_track()
            # notifications come in commit order: the event's is after every batch's
            event = log.add_event(dive, "datum", "the end of the batches")
            payloads: list[dict[str, Any]] = []
            for note in listener.notifies(timeout=10):
                payloads.append(json.loads(note.payload))
                if payloads[-1]["table"] == "events":
                    break
        assert payloads == [
            {"table": "track", "id": dive, "console": "ship"},
            {"table": "track", "id": dive, "console": "ship"},
            {"table": "events", "id": event["id"], "console": "ship"},
        ]
    finally:
        log.close()


def test_the_newest_point_of_a_dive_is_read_with_the_databases_clock(
    log_backend: LogBackend,
) -> None:
    log = log_backend.open()
    try:
        row, now_s = log.newest_track_point()
        assert row is None and now_s > 1.7e9  # seconds since 1970, this century
        first, second = log.new_dive("sim"), log.new_dive("sim")
        log.add_track(first, 5.0, 1.0, 2.0, 3.0, 90.0, {"depth_m": 3.0, "mode": "auto"})
        log.add_track(first, 4.0, 0.0, 0.0, 0.0, 80.0)
        log.add_status_point(second, 7.0, {"nav_valid": False, "heading_deg": 10.0})
        log.add_track(second, 6.0, 9.0, 9.0, 9.0, 45.0)
        row, _ = log.newest_track_point(first)  # by the vehicle's clock, not the order written
        assert row is not None
        assert (row["dive"], row["t_s"], row["x_m"], row["depth_m"]) == (first, 5.0, 1.0, 3.0)
        assert row["mode"] == "auto" and row["vehicle"] is None and row["at"]
        row, _ = log.newest_track_point()  # the newest dive's: a point without a position
        assert row is not None
        assert (row["dive"], row["t_s"], row["x_m"], row["nav_valid"]) == (second, 7.0, None, False)
        assert log.newest_track_point(second + 1)[0] is None
    finally:
        log.close()
