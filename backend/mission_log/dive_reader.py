"""A dive read back row by row, for the exports: a read-only connection of its own and a cursor
per table, so a long dive streams in constant memory and never holds the console's lock.

The reader is one read transaction (:func:`snapshot`): every query sees the log as it was at
the first, so a dive still being written is exported as it stood then, its counts and its rows
alike (no half-written row: SQLite's WAL shows committed transactions only). An older log is
read as it is, never migrated: a column it lacks reads as null.

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
from backend.mission_log.opening import LogError, classify
from backend.mission_log.store import EXPORT_CACHE_KIB
from backend.mission_log.track import TRACK_COLUMNS

#: Rows fetched from SQLite at a time.
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


def open_read_only(path: Path | str) -> sqlite3.Connection:
    """The log at ``path`` opened read-only (nothing of it is changed, an older one not migrated).

    Raises:
        LogError: the file does not exist, is not a SQLite database, or cannot be read.
    """
    where = Path(path)
    if not where.is_file():
        raise NoSuchLog(where, "does not exist", "give the console's --db file")
    try:
        db = sqlite3.connect(
            f"{where.resolve().as_uri()}?mode=ro", uri=True, check_same_thread=False
        )
        db.execute(f"PRAGMA cache_size = -{EXPORT_CACHE_KIB}")
        db.execute("SELECT COUNT(*) FROM sqlite_master").fetchone()
    except sqlite3.Error as err:
        raise classify(where, err) from None
    return db


@contextlib.contextmanager
def snapshot(db: sqlite3.Connection) -> Iterator[DiveReader]:
    """A :class:`DiveReader` of ``db`` in one read transaction (ended on leaving)."""
    db.row_factory = sqlite3.Row
    if db.in_transaction:  # a caller's own transaction: its view is the snapshot
        yield DiveReader(db)
        return
    db.execute("BEGIN")
    try:
        yield DiveReader(db)
    finally:
        db.execute("ROLLBACK")


class DiveReader:
    """A dive's rows out of a log connection (:func:`snapshot` makes one)."""

    def __init__(self, db: sqlite3.Connection) -> None:
        self._db = db
        self._columns: dict[str, set[str]] = {}

    def columns(self, table: str) -> set[str]:
        """The columns ``table`` has in this log."""
        if table not in self._columns:
            rows = self._db.execute(f"PRAGMA table_info({table})").fetchall()
            self._columns[table] = {str(r[1]) for r in rows}
        return self._columns[table]

    def dive(self, dive: int) -> dict[str, Any]:
        """The dive's row (``id, started_at, target``).

        Raises:
            NoSuchDive: naming it and the dives the log has.
        """
        row = self._db.execute("SELECT * FROM dives WHERE id = ?", (dive,)).fetchone()
        if row is None:
            known = [int(r[0]) for r in self._db.execute("SELECT id FROM dives ORDER BY id")]
            raise NoSuchDive(dive, known)
        return dict(row)

    def _time(self, *candidates: str) -> str:
        """The first of ``candidates`` (command columns) this log has, as one SQL term."""
        have = [c for c in candidates if c in self.columns("commands")]
        return f"COALESCE({', '.join(have)})" if len(have) > 1 else have[0]

    def counts(self, dive: int) -> dict[str, int]:
        """How many rows of each kind the dive has: ``track`` (every point), ``positioned``
        (with a position), ``commands``, ``frames`` (sent), ``acks`` and ``events``."""
        one = self._db.execute
        sent = self._time("first_sent_at", "sent_at")
        return {
            "track": one("SELECT COUNT(*) FROM track WHERE dive = ?", (dive,)).fetchone()[0],
            "positioned": one(
                "SELECT COUNT(*) FROM track WHERE dive = ? AND x_m IS NOT NULL", (dive,)
            ).fetchone()[0],
            "commands": one("SELECT COUNT(*) FROM commands WHERE dive = ?", (dive,)).fetchone()[0],
            "frames": one(
                f"SELECT COUNT(*) FROM commands WHERE dive = ? AND {sent} IS NOT NULL", (dive,)
            ).fetchone()[0],
            "acks": one(
                "SELECT COUNT(*) FROM commands WHERE dive = ? AND ack IS NOT NULL", (dive,)
            ).fetchone()[0],
            "events": one("SELECT COUNT(*) FROM events WHERE dive = ?", (dive,)).fetchone()[0],
        }

    def _rows(self, sql: str, args: tuple[Any, ...]) -> Iterator[sqlite3.Row]:
        cursor = self._db.execute(sql, args)
        try:
            while batch := cursor.fetchmany(BATCH_ROWS):
                yield from batch
        finally:
            cursor.close()

    def track(self, dive: int) -> Iterator[dict[str, Any]]:
        """The dive's track points in arrival order, every column (one this log lacks: null;
        ``active`` parsed, ``nav_valid`` a boolean)."""
        have = self.columns("track")
        cols = ", ".join(c if c in have else f"NULL AS {c}" for c in TRACK_COLUMNS[1:])
        for r in self._rows(f"SELECT {cols} FROM track WHERE dive = ? ORDER BY rowid", (dive,)):
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
        rows = self._db.execute(
            "SELECT at, data FROM events WHERE kind = 'datum' AND dive <= ? AND data IS NOT NULL "
            "ORDER BY dive, id",
            (dive,),
        ).fetchall()
        out = []
        for at, data in rows:
            doc = json.loads(data)
            lat, lon = doc.get("lat_deg"), doc.get("lon_deg")
            if isinstance(lat, int | float) and isinstance(lon, int | float):
                out.append((str(at), float(lat), float(lon)))
        return out
