"""The mission log: every command, written before it is transmitted, and the dives' tracks.

A SQLite file (the embedded default: WAL mode, ``synchronous=FULL``) or a PostgreSQL database
(``postgresql://...``, several consoles sharing it; ``synchronous_commit=on``): either way a
committed row survives a killed process or a power cut. The two differ only in
:mod:`backend.mission_log.database`; the tables are the migrations'
(:mod:`backend.mission_log.migrating`), brought up to date when the log is opened. One
connection guarded by a lock (the console is one process; writes are small). Rows are only
ever inserted or updated field by field, each statement or :meth:`MissionLog.transaction`
committed whole, so no record is half written. A write that fails (disk full, the file made
read-only, the server gone) raises :class:`LogWriteError`. Track points are written within
:data:`TRACK_FLUSH_S` of their arrival (a killed console loses less than that; the buffer is
:mod:`backend.mission_log.track`).
Opening a log with its checks: :func:`backend.mission_log.opening.open_checked`.
"""

from __future__ import annotations

import contextlib
import json
import threading
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

from backend.clock import CONSOLE_UTC
from backend.commands.lifecycle import ON_ITS_WAY, Event, State, advance
from backend.mission_log.command_rows import (
    FINAL_STATES,
    STATES,
    WIRE_ORDER,
    checked_update,
    column_value,
    command_row,
    commands_query,
)
from backend.mission_log.database import LogDatabase, open_database
from backend.mission_log.errors import LogWriteError
from backend.mission_log.migrating import migrate
from backend.mission_log.read_only import ReadOnlyDatabase, read_only_of
from backend.mission_log.track import TRACK_BATCH, TRACK_BUFFER_MAX, TRACK_FLUSH_S, TrackBuffer
from backend.mission_log.track_store import TrackStore

__all__ = [
    "BUSY_TIMEOUT_S",
    "FINAL_STATES",
    "STATES",
    "TRACK_BATCH",
    "TRACK_BUFFER_MAX",
    "TRACK_FLUSH_S",
    "WIRE_ORDER",
    "LogWriteError",
    "MissionLog",
    "now_iso",
]

#: How long a write waits for a lock another connection holds before it fails (s).
BUSY_TIMEOUT_S = 1.0
#: How long opening a log waits for another console's migration of it to finish (s).
MIGRATION_WAIT_S = 30.0
#: The page cache of an export's own connection (KiB; SQLite's default is 2000): it reads
#: once, in order (``backend.mission_log.dive_reader``).
EXPORT_CACHE_KIB = 256


def now_iso() -> str:
    """Current UTC time on the console's monotonic-anchored clock (:data:`CONSOLE_UTC`: the
    log's stamps never go back within a run), ISO 8601 with milliseconds."""
    return CONSOLE_UTC.now().isoformat(timespec="milliseconds")


class MissionLog(TrackStore):
    """The mission log, in a SQLite file or on PostgreSQL. Thread-safe (its track: the
    :class:`backend.mission_log.track_store.TrackStore` it is).

    ``where``: the SQLite file (or ``":memory:"``), or a ``postgresql://`` URL. Opening
    brings the tables to the newest migration. ``now``: the stamps the log writes (ISO UTC);
    a benchmark that fills a long dive in seconds passes its own clock, the console keeps
    :func:`now_iso`.

    Raises:
        sqlite3.Error, psycopg.Error: the database cannot be opened or migrated (what is
            wrong, in words: :func:`backend.mission_log.opening.open_checked`).
    """

    def __init__(
        self,
        where: Path | str,
        *,
        busy_timeout_s: float = BUSY_TIMEOUT_S,
        now: Callable[[], str] = now_iso,
    ) -> None:
        self._db: LogDatabase = open_database(where, busy_timeout_s)
        #: The SQLite file (None on PostgreSQL).
        self.path = Path(where) if self._db.kind == "sqlite" else None
        #: The log as messages name it: the file, or the URL with its password masked.
        self.where = self._db.where
        self._now = now
        self._busy_timeout_s = busy_timeout_s
        self._lock = threading.RLock()  # re-entered by the writes of a transaction()
        self._track = TrackBuffer(self._lock, self._write_track)
        self._closed = False
        #: The console writing (:meth:`name_console`; None: not named).
        self.console: str | None = None
        try:
            # another console may be migrating the same log: wait for its whole migration
            # (every step in one transaction), not a write's usual lock wait
            self._db.set_busy_timeout(max(busy_timeout_s, MIGRATION_WAIT_S))
            migrate(self._db)
            self._db.set_busy_timeout(busy_timeout_s)
        except BaseException:
            self._db.close()
            raise

    @property
    def kind(self) -> str:
        """``"sqlite"`` or ``"postgresql"``."""
        return self._db.kind

    @property
    def read_errors(self) -> tuple[type[Exception], ...]:
        """The driver's errors a read raises when the database is out of reach (a PostgreSQL
        server gone): a reader that can go on with what it read last catches them."""
        return self._db.write_errors

    def set_busy_timeout(self, busy_timeout_s: float = BUSY_TIMEOUT_S) -> None:
        """How long a write waits for another connection's lock before it fails."""
        with self._lock:
            self._db.set_busy_timeout(busy_timeout_s)
            self._busy_timeout_s = busy_timeout_s

    def name_console(self, console: str) -> None:
        """This console's name among those sharing the log: written into every command it
        records, and carried by PostgreSQL's notifications of its writes (so it can tell
        its own: :mod:`backend.mission_log.listen`)."""
        with self._lock:
            self._db.name_console(console)
            self.console = console

    @contextlib.contextmanager
    def connection(self) -> Iterator[LogDatabase]:
        """The log's connection under its lock, for the SQL kept beside the store (the
        control table: :mod:`backend.mission_log.control`)."""
        with self._lock:
            yield self._db

    def check(self) -> list[str]:
        """The database's integrity check (SQLite's ``quick_check``): the problems it finds
        (none: intact). Then a write that changes nothing, rolled back: raises the driver's
        error if the log is locked by another process or read-only."""
        with self._lock:
            return self._db.check()

    def recover_interrupted(self, console: str | None = None) -> int:
        """Every command an earlier run left on its way (``queued`` or ``transmitted``) becomes
        ``interrupted``, naming the last time the log was written. One transaction; returns
        how many. Call before the console takes new commands. ``console``: only the records
        that console wrote (and those that name none): on a log several consoles share, the
        others' commands on their way are theirs (None: every record, a log of one console)."""
        on_its_way = sorted(ON_ITS_WAY)
        marks = ", ".join("?" * len(on_its_way))
        mine = "" if console is None else " AND (console = ? OR console IS NULL)"
        target = advance(State.QUEUED, Event.INTERRUPTED)
        with self._lock:
            last = self._db.execute(
                "SELECT MAX(t) AS last FROM (SELECT MAX(updated_at) AS t FROM commands "
                "UNION ALL SELECT MAX(started_at) FROM dives) AS times"
            ).fetchone()["last"]
            with self.transaction(), self._db.writing():
                cur = self._db.execute(
                    "UPDATE commands SET state = ?, updated_at = ?, "
                    "reason = 'the console stopped while this command was ' || state || "
                    "' (the log was last written at ' || ? || "
                    "'); whether the vehicle received it is not known' "
                    f"WHERE state IN ({marks}){mine}",
                    (
                        target,
                        self._now(),
                        last or "an unknown time",
                        *on_its_way,
                        *(() if console is None else (console,)),
                    ),
                )
        return cur.rowcount

    @contextlib.contextmanager
    def transaction(self) -> Iterator[None]:
        """Every write inside is committed together, or none is (a crash or an exception in
        between leaves the log as it was). Holds the log's lock throughout."""
        with self._lock:
            if self._db.in_transaction:  # nested: part of the outer one
                yield
                return
            with self._db.writing():
                self._db.execute(self._db.begin_sql)
            try:
                yield
                with self._db.writing():
                    self._db.execute("COMMIT")
            except BaseException:
                if self._db.in_transaction:  # SQLite may have rolled back already
                    with contextlib.suppress(*self._db.write_errors):
                        self._db.execute("ROLLBACK")
                raise

    def close(self) -> None:
        with self._lock:
            if self._closed:
                return
            self._closed = True
            self._track.close()
            self._db.close()

    @contextlib.contextmanager
    def exporting(self) -> Iterator[ReadOnlyDatabase]:
        """A connection for a long read (an export) that does not hold the log's lock: a
        read-only one of its own (SQLite's file, or the same PostgreSQL database), the track
        buffer written first. An in-memory log (tests) has no second connection: its own,
        under the lock throughout.

        Raises:
            sqlite3.Error, psycopg.Error: the second connection cannot be opened.
        """
        self.flush_track()
        db = read_only_of(self._db, cache_kib=EXPORT_CACHE_KIB, busy_timeout_s=self._busy_timeout_s)
        try:
            with self._lock if db.shared else contextlib.nullcontext():
                yield db
        finally:
            db.close()

    def flush_track(self) -> None:
        """Write the buffered track points now (a failure is logged, as the buffer's)."""
        self._track.flush()

    # --- dives ---------------------------------------------------------------------------

    def new_dive(self, target: str) -> int:
        """Open a new dive (``backend.dives`` decides when); returns its number."""
        with self._lock, self._db.writing():
            return self._db.insert(
                "INSERT INTO dives (started_at, target) VALUES (?, ?)", (self._now(), target)
            )

    def dives(self) -> list[dict[str, Any]]:
        with self._lock:
            self._track.flush()
            rows = self._db.execute(
                "SELECT d.id, d.started_at, d.target, "
                "(SELECT COUNT(*) FROM commands c WHERE c.dive = d.id) AS commands, "
                "(SELECT COUNT(*) FROM track t WHERE t.dive = d.id) AS track_points "
                "FROM dives d ORDER BY d.id DESC"
            ).fetchall()
        return [dict(r) for r in rows]

    def dive(self, dive: int) -> dict[str, Any] | None:
        """The dive's row (``id, started_at, target``); None: no such dive."""
        with self._lock:
            row = self._db.execute("SELECT * FROM dives WHERE id = ?", (dive,)).fetchone()
        return None if row is None else dict(row)

    def dive_exists(self, dive: int) -> bool:
        return self.dive(dive) is not None

    # --- commands ------------------------------------------------------------------------

    def insert_command(self, dive: int, record: Mapping[str, Any]) -> dict[str, Any]:
        """Write a new command (state ``queued``) and return it with its id. Committed."""
        stamp = self._now()
        row = {
            "dive": dive,
            "created_at": stamp,
            "updated_at": stamp,
            "state": "queued",
            "attempts": 0,
            "console": self.console,
            **record,
        }
        cols = list(row)
        values = [column_value(c, row[c]) for c in cols]
        with self._lock, self._db.writing():
            new_id = self._db.insert(
                f"INSERT INTO commands ({', '.join(cols)}) VALUES ({', '.join('?' * len(cols))})",
                values,
            )
            got = self._command(new_id)
        assert got is not None
        return got

    def update_command(self, command_id: int, **fields: Any) -> dict[str, Any]:
        """Set some fields of a command (one atomic statement); returns the new record."""
        fields = checked_update(fields)
        fields["updated_at"] = self._now()
        sets = ", ".join(f"{k} = ?" for k in fields)
        values = [column_value(k, v) for k, v in fields.items()]
        with self._lock, self._db.writing():
            self._db.execute(f"UPDATE commands SET {sets} WHERE id = ?", [*values, command_id])
            got = self._command(command_id)
        if got is None:
            raise KeyError(command_id)
        return got

    def command(self, command_id: int) -> dict[str, Any] | None:
        with self._lock:
            return self._command(command_id)

    def _command(self, command_id: int) -> dict[str, Any] | None:
        """The record as written (under the lock: the row this call's statement left)."""
        row = self._db.execute("SELECT * FROM commands WHERE id = ?", (command_id,)).fetchone()
        return command_row(row) if row is not None else None

    def commands(
        self,
        *,
        state: str | None = None,
        pattern: str | None = None,
        target: str | None = None,
        dive: int | None = None,
        vehicle: str | None = None,
        since: str | None = None,
        until: str | None = None,
        limit: int = 200,
        oldest_first: bool = False,
    ) -> list[dict[str, Any]]:
        sql, args = commands_query(
            state=state,
            pattern=pattern,
            target=target,
            dive=dive,
            vehicle=vehicle,
            since=since,
            until=until,
            limit=limit,
            oldest_first=oldest_first,
        )
        with self._lock:
            rows = self._db.execute(sql, args).fetchall()
        return [command_row(r) for r in rows]

    def last_sent(self, vehicle: str | None = None) -> dict[str, Any] | None:
        """The command whose first copy left most recently (of any dive; to a fleet's
        ``vehicle``), as ``{id, pattern, pattern_id, params}``; None: nothing has left yet."""
        which = "" if vehicle is None else "AND vehicle = ? "
        with self._lock:
            row = self._db.execute(
                "SELECT id, pattern, pattern_id, params FROM commands "
                f"WHERE first_sent_at IS NOT NULL {which}"
                "ORDER BY first_sent_at DESC, id DESC LIMIT 1",
                () if vehicle is None else (vehicle,),
            ).fetchone()
        if row is None:
            return None
        params = json.loads(row["params"])
        return {
            "id": row["id"],
            "pattern": row["pattern"],
            "pattern_id": row["pattern_id"],
            "params": params,
        }

    # --- events: what the vehicle did that the console did not cause ------------------------

    def add_event(
        self,
        dive: int,
        kind: str,
        detail: str,
        data: Mapping[str, Any] | None = None,
        vehicle: str | None = None,
    ) -> dict[str, Any]:
        """Write one event (committed; ``vehicle``: the fleet's vehicle it concerns); returns
        it with its id (``vehicle`` in it only when it names one)."""
        text = None if data is None else json.dumps(data)
        row = (dive, self._now(), kind, detail, text, vehicle)
        with self._lock, self._db.writing():
            new_id = self._db.insert(
                "INSERT INTO events (dive, at, kind, detail, data, vehicle) "
                "VALUES (?, ?, ?, ?, ?, ?)",
                row,
            )
        keys = ("dive", "at", "kind", "detail")
        named = {} if vehicle is None else {"vehicle": vehicle}
        event = {"id": new_id, **dict(zip(keys, row, strict=False))}
        return {**event, "data": data, **named}

    def events(self, dive: int | None = None, *, after: int = 0) -> list[dict[str, Any]]:
        """Events, oldest first (of one dive; with an id above ``after``)."""
        sql = "SELECT * FROM events WHERE id > ?" + (" AND dive = ?" if dive is not None else "")
        with self._lock:
            rows = self._db.execute(
                sql + " ORDER BY id", (after,) + (() if dive is None else (dive,))
            )
            out = [dict(r) for r in rows.fetchall()]
        for event in out:
            event["data"] = None if event["data"] is None else json.loads(event["data"])
            if event.get("vehicle", "") is None:
                del event["vehicle"]
        return out
