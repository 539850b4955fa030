"""A dive read back row by row, for the exports: a read-only connection of its own and a cursor
per table, so a long dive streams in constant memory and never holds the console's lock. The
log is a SQLite file or a PostgreSQL database alike: what differs for such a read (the snapshot,
server-side cursors on PostgreSQL) is :mod:`backend.mission_log.read_only`'s.

The reader is one read transaction (:func:`snapshot`): every query sees the log as it was at
the first, so a dive still being written is exported as it stood then, its counts and its rows
alike (no half-written row: SQLite's WAL and PostgreSQL's repeatable read show committed
transactions only). An older log is read as it is, never migrated: a column it lacks reads as
null.

Each table's rows come in the order of their own console time (the stamps of
:data:`backend.clock.CONSOLE_UTC`): the track in arrival order, the commands by when they were
written, the frames by when their first copy left, the acknowledgements by when they arrived,
the events by when they were logged.
"""

from __future__ import annotations

import contextlib
import json
import sqlite3
from collections.abc import Iterator
from pathlib import Path
from typing import Any, Final

from backend.mission_log.command_rows import command_row
from backend.mission_log.database import Row, is_postgres_url, masked
from backend.mission_log.opening import LogError, classify, classify_postgres
from backend.mission_log.read_only import ReadOnlyDatabase
from backend.mission_log.read_only import open_read_only as _open
from backend.mission_log.store import EXPORT_CACHE_KIB
from backend.mission_log.track import TRACK_COLUMNS

#: Rows fetched from the database at a time.
BATCH_ROWS: Final = 512


class NoSuchLog(LogError):
    """The mission log file does not exist."""


class NoSuchDive(LookupError):
    """The log has no dive ``dive``; the message names it and the dives there are."""

    def __init__(self, dive: int, known: list[int]) -> None:
        there = (
            f"its dives are {known[0]} to {known[-1]}"
            if len(known) > 1
            else f"its only dive is {known[0]}"
            if known
            else "it has no dive yet"
        )
        super().__init__(f"no dive {dive} in the mission log ({there})")
        self.dive = dive


def open_read_only(where: Path | str) -> ReadOnlyDatabase:
    """The log at ``where`` (a SQLite file, or a ``postgresql://`` URL) opened read-only
    (nothing of it is changed, an older one not migrated).

    Raises:
        LogError: the file does not exist, is not a SQLite database, or cannot be read; the
            server cannot be reached, refuses the login, or has no such database (the URL's
            password masked).
    """
    if is_postgres_url(where):
        import psycopg

        try:
            return _open(where, cache_kib=EXPORT_CACHE_KIB)
        except psycopg.Error as err:
            raise classify_postgres(masked(str(where)), err) from None
    path = Path(where)
    if not path.is_file():
        raise NoSuchLog(path, "does not exist", "give the console's --db file")
    try:
        return _open(path, cache_kib=EXPORT_CACHE_KIB)
    except sqlite3.Error as err:
        raise classify(path, err) from None


@contextlib.contextmanager
def snapshot(db: ReadOnlyDatabase) -> Iterator[DiveReader]:
    """A :class:`DiveReader` of ``db`` in one read transaction (ended on leaving)."""
    with db.snapshot():
        yield DiveReader(db)


class DiveReader:
    """A dive's rows out of a log connection (:func:`snapshot` makes one)."""

    def __init__(self, db: ReadOnlyDatabase) -> None:
        self._db = db
        self._columns: dict[str, set[str]] = {}

    def columns(self, table: str) -> set[str]:
        """The columns ``table`` has in this log."""
        if table not in self._columns:
            self._columns[table] = self._db.columns(table)
        return self._columns[table]

    def dive(self, dive: int) -> dict[str, Any]:
        """The dive's row (``id, started_at, target``).

        Raises:
            NoSuchDive: naming it and the dives the log has.
        """
        row = self._db.one("SELECT * FROM dives WHERE id = ?", (dive,))
        if row is None:
            known = [int(r["id"]) for r in self._db.all("SELECT id FROM dives ORDER BY id")]
            raise NoSuchDive(dive, known)
        return dict(row)

    def _time(self, *candidates: str) -> str:
        """The first of ``candidates`` (command columns) this log has, as one SQL term."""
        have = [c for c in candidates if c in self.columns("commands")]
        return f"COALESCE({', '.join(have)})" if len(have) > 1 else have[0]

    def counts(self, dive: int) -> dict[str, int]:
        """How many rows of each kind the dive has: ``track`` (every point), ``positioned``
        (with a position), ``commands``, ``frames`` (sent), ``acks`` and ``events``."""
        sent = self._time("first_sent_at", "sent_at")
        where = {
            "track": "track WHERE dive = ?",
            "positioned": "track WHERE dive = ? AND x_m IS NOT NULL",
            "commands": "commands WHERE dive = ?",
            "frames": f"commands WHERE dive = ? AND {sent} IS NOT NULL",
            "acks": "commands WHERE dive = ? AND ack IS NOT NULL",
            "events": "events WHERE dive = ?",
        }
        out = {}
        for kind, rows in where.items():
            row = self._db.one(f"SELECT COUNT(*) AS n FROM {rows}", (dive,))
            out[kind] = 0 if row is None else int(row["n"])
        return out

    def _rows(self, sql: str, args: tuple[Any, ...]) -> Iterator[Row]:
        return self._db.stream(sql, args, BATCH_ROWS)

    def vehicles(self, dive: int) -> list[str]:
        """The fleet's vehicles the dive's track points and commands name, in name order
        (none: a single vehicle's dive, or a log from before fleets)."""
        names: set[str] = set()
        for table in ("track", "commands"):
            if "vehicle" in self.columns(table):
                sql = f"SELECT DISTINCT vehicle FROM {table} WHERE dive = ? AND vehicle IS NOT NULL"
                names.update(str(r["vehicle"]) for r in self._db.all(sql, (dive,)))
        return sorted(names)

    def track(self, dive: int) -> Iterator[dict[str, Any]]:
        """The dive's track points in arrival order, every column and the fleet's ``vehicle``
        each is of (one this log lacks: null; ``active`` parsed, ``nav_valid`` a boolean)."""
        have = self.columns("track")
        wanted = (*TRACK_COLUMNS[1:], "vehicle")
        cols = ", ".join(c if c in have else f"NULL AS {c}" for c in wanted)
        sql = f"SELECT {cols} FROM track WHERE dive = ? ORDER BY {self._db.track_order}"
        for r in self._rows(sql, (dive,)):
            row = dict(r)
            row["active"] = None if row["active"] is None else json.loads(row["active"])
            row["nav_valid"] = None if row["nav_valid"] is None else bool(row["nav_valid"])
            yield row

    def commands(self, dive: int) -> Iterator[dict[str, Any]]:
        """The dive's commands by when the console wrote them."""
        sql = "SELECT * FROM commands WHERE dive = ? ORDER BY created_at, id"
        return (command_row(r) for r in self._rows(sql, (dive,)))

    def sent(self, dive: int) -> Iterator[tuple[str, dict[str, Any]]]:
        """``(when its first copy left, command)`` of each command sent, in that order (an
        older log without ``first_sent_at``: its last copy)."""
        at = self._time("first_sent_at", "sent_at")
        sql = (
            f"SELECT {at} AS left_at, * FROM commands WHERE dive = ? AND {at} IS NOT NULL "
            f"ORDER BY {at}, id"
        )
        return ((r["left_at"], command_row(r)) for r in self._rows(sql, (dive,)))

    def acks(self, dive: int) -> Iterator[tuple[str, dict[str, Any]]]:
        """``(when it arrived, command)`` of each command with an acknowledgement, in that
        order (an acknowledgement without ``acked_at``, a rejection: the record's last
        update)."""
        at = self._time("acked_at", "updated_at")
        sql = (
            f"SELECT {at} AS acked, * FROM commands WHERE dive = ? AND ack IS NOT NULL "
            f"ORDER BY {at}, id"
        )
        return ((r["acked"], command_row(r)) for r in self._rows(sql, (dive,)))

    def events(self, dive: int) -> Iterator[dict[str, Any]]:
        """The dive's events by when they were logged (``data`` parsed)."""
        for r in self._rows("SELECT * FROM events WHERE dive = ? ORDER BY at, id", (dive,)):
            event = dict(r)
            event["data"] = None if event["data"] is None else json.loads(event["data"])
            yield event

    def datums(self, dive: int) -> list[tuple[str, float, float]]:
        """``(at, lat_deg, lon_deg)`` of every datum set up to the end of ``dive`` (the ``datum``
        events of it and of the dives before), oldest first: few rows, read at once."""
        rows = self._db.all(
            "SELECT at, data FROM events WHERE kind = 'datum' AND dive <= ? AND data IS NOT NULL "
            "ORDER BY dive, id",
            (dive,),
        )
        out = []
        for row in rows:
            doc = json.loads(row["data"])
            lat, lon = doc.get("lat_deg"), doc.get("lon_deg")
            if isinstance(lat, int | float) and isinstance(lon, int | float):
                out.append((str(row["at"]), float(lat), float(lon)))
        return out
