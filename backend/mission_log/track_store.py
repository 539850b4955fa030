"""The mission log's track: its points buffered and committed in batches, and read back in
time order (each point with what the vehicle's status said then).

Part of :class:`backend.mission_log.store.MissionLog` (its base class: the same lock,
connection, clock and buffer), kept here so that the store stays one reader's length.
"""

from __future__ import annotations

import contextlib
import json
import threading
from collections.abc import Callable, Mapping
from typing import Any

from backend.mission_log.database import LogDatabase
from backend.mission_log.track import (
    TRACK_COLUMNS,
    TRACK_WRITE_COLUMNS,
    TrackBuffer,
    TrackPoint,
    track_point,
)
from vehicle_contract.messages import number

__all__ = ["TrackStore"]


class TrackStore:
    """The track's writes and reads, on the log's own connection under its lock."""

    _db: LogDatabase
    _lock: threading.RLock
    _now: Callable[[], str]
    _track: TrackBuffer

    def transaction(self) -> contextlib.AbstractContextManager[None]:
        raise NotImplementedError  # the log's (:meth:`MissionLog.transaction`)

    def add_track(
        self,
        dive: int,
        t_s: float,
        x_m: float,
        y_m: float,
        z_m: float,
        heading_deg: float,
        status: Mapping[str, Any] | None = None,
        vehicle: str | None = None,
    ) -> None:
        """Buffer one track point (of a fleet's ``vehicle``) with what ``status`` says then
        (``track_point``); written
        (one commit) within :data:`TRACK_FLUSH_S` of the first point buffered, at
        :data:`TRACK_BATCH` points, on a read and on close. A write that fails is logged and
        tried again by the timer (never raised)."""
        position = (t_s, x_m, y_m, z_m, heading_deg)
        self._track.add(track_point(dive, position, status or {}, self._now(), vehicle))

    def add_status_point(
        self, dive: int, t_s: float, status: Mapping[str, Any], vehicle: str | None = None
    ) -> None:
        """Buffer one track point without a position: what ``status`` says at ``t_s`` when the
        vehicle sends no pose (its navigation not valid; the heading is the status's, null in
        the contract's nav fault). Written as :meth:`add_track`'s points are."""
        position = (t_s, None, None, None, number(status.get("heading_deg")))
        self._track.add(track_point(dive, position, status, self._now(), vehicle))

    def _write_track(self, points: list[TrackPoint]) -> None:
        """Commit ``points`` together (the track buffer's write)."""
        cols = ", ".join(TRACK_WRITE_COLUMNS)
        marks = ", ".join("?" * len(TRACK_WRITE_COLUMNS))
        with self.transaction(), self._db.writing():
            self._db.executemany(f"INSERT INTO track ({cols}) VALUES ({marks})", points)

    def track(self, dive: int, vehicle: str | None = None) -> list[dict[str, float]]:
        """The dive's positions in time order: ``t_s, x_m, y_m, z_m, heading_deg`` (its points
        without a position left out; of a fleet's ``vehicle`` only)."""
        keys = ("t_s", "x_m", "y_m", "z_m", "heading_deg")
        return [{k: row[k] for k in keys} for row in self.track_rows(dive, vehicle=vehicle)]

    def track_rows(
        self, dive: int, *, positioned: bool = True, vehicle: str | None = None
    ) -> list[dict[str, Any]]:
        """The dive's track points in time order with every column (``active`` parsed,
        ``nav_valid`` a boolean; an older log's points have null status columns). Only the
        points with a position unless ``positioned`` is false (the status series); only a
        fleet's ``vehicle``'s when given."""
        where = " AND x_m IS NOT NULL" if positioned else ""
        args: tuple[Any, ...] = (dive,)
        if vehicle is not None:
            where, args = where + " AND vehicle = ?", (dive, vehicle)
        with self._lock:
            self._track.flush()
            rows = self._db.execute(
                f"SELECT {', '.join(TRACK_COLUMNS[1:])} FROM track WHERE dive = ?{where} "
                "ORDER BY t_s",
                args,
            ).fetchall()
        return [_parsed(dict(r)) for r in rows]

    def newest_track_point(
        self, dive: int | None = None, vehicle: str | None = None
    ) -> tuple[dict[str, Any] | None, float]:
        """The newest point of ``dive`` by the vehicle's clock (None: of the newest dive with a
        track), with every column as :meth:`track_rows` gives them and its ``dive`` and
        ``vehicle`` (None: no point), and the database's clock (s since 1970): what a console
        without a transmitter shows of the vehicle another console hears
        (:mod:`backend.relay.telemetry`). ``vehicle``: only a fleet vehicle's points (None:
        any point). Read on the index ``(dive, t_s)``: one row (a fleet's vehicle: the
        newest points until one of it), not the dive's.

        Raises:
            LogWriteError: the log cannot be read (a database out of reach).
        """
        with self._lock, self._db.writing():
            self._track.flush()  # this console's own points too, as any read of the track
            db = self._db
            now_s = float(db.execute(f"SELECT {db.now_s_sql} AS now_s").fetchone()["now_s"])
            if dive is None:
                got = db.execute("SELECT MAX(dive) AS dive FROM track").fetchone()
                if got["dive"] is None:
                    return None, now_s
                dive = int(got["dive"])
            which = "" if vehicle is None else " AND vehicle = ?"
            args = (dive,) if vehicle is None else (dive, vehicle)
            row = db.execute(
                f"SELECT {', '.join(TRACK_WRITE_COLUMNS)} FROM track WHERE dive = ?{which} "
                "ORDER BY t_s DESC LIMIT 1",
                args,
            ).fetchone()
        return (None if row is None else _parsed(dict(row))), now_s


def _parsed(row: dict[str, Any]) -> dict[str, Any]:
    """A track row with ``active`` parsed and ``nav_valid`` a boolean (null: not said)."""
    row["active"] = None if row["active"] is None else json.loads(row["active"])
    row["nav_valid"] = None if row["nav_valid"] is None else bool(row["nav_valid"])
    return row
