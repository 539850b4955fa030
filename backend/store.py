"""The mission log: every command, written before it is transmitted, and the dives' tracks.

SQLite in WAL mode with ``synchronous=FULL``: a committed row survives a killed process or a
power cut. One connection guarded by a lock (the console is one process; writes are small).
Rows are only ever inserted or updated field by field, so no record is half written.
"""

from __future__ import annotations

import contextlib
import json
import sqlite3
import threading
from collections.abc import Iterable, Iterator, Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from backend.lifecycle import ON_ITS_WAY, TERMINAL, Event, State, advance

SCHEMA = """
CREATE TABLE IF NOT EXISTS dives (
    id INTEGER PRIMARY KEY,
    started_at TEXT NOT NULL,
    target TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS commands (
    id INTEGER PRIMARY KEY,
    dive INTEGER NOT NULL REFERENCES dives(id),
    created_at TEXT NOT NULL,
    updated_at TEXT NOT NULL,
    operator TEXT NOT NULL,
    target TEXT NOT NULL,
    kind TEXT NOT NULL,
    pattern TEXT NOT NULL,
    pattern_id INTEGER NOT NULL,
    params TEXT NOT NULL,
    requested TEXT NOT NULL,
    bits TEXT NOT NULL,
    hex TEXT NOT NULL,
    state TEXT NOT NULL,
    attempts INTEGER NOT NULL DEFAULT 0,
    sent_at TEXT,
    acked_at TEXT,
    ack TEXT,
    reason TEXT,
    copies INTEGER,
    copies_sent INTEGER NOT NULL DEFAULT 0,
    p_delivered REAL NOT NULL DEFAULT 0,
    ber REAL,
    two_way INTEGER,
    superseded_by INTEGER
);
CREATE INDEX IF NOT EXISTS commands_dive ON commands(dive);
CREATE TABLE IF NOT EXISTS track (
    dive INTEGER NOT NULL REFERENCES dives(id),
    t_s REAL NOT NULL,
    x_m REAL NOT NULL,
    y_m REAL NOT NULL,
    z_m REAL NOT NULL,
    heading_deg REAL NOT NULL
);
CREATE INDEX IF NOT EXISTS track_dive ON track(dive, t_s);
"""

#: Columns added since the first release: (name, declaration), added to an older log at open.
_ADDED_COLUMNS = (
    ("copies", "INTEGER"),
    ("copies_sent", "INTEGER NOT NULL DEFAULT 0"),
    ("p_delivered", "REAL NOT NULL DEFAULT 0"),
    ("ber", "REAL"),
    ("two_way", "INTEGER"),
    ("superseded_by", "INTEGER"),
)
#: Columns holding JSON text.
_JSON = ("params", "requested", "ack")
#: Columns holding booleans (SQLite integers).
_BOOL = ("two_way",)
#: Columns a command update may set.
_UPDATABLE = frozenset(
    {
        "state",
        "attempts",
        "sent_at",
        "acked_at",
        "ack",
        "reason",
        "copies",
        "copies_sent",
        "p_delivered",
        "ber",
        "two_way",
        "superseded_by",
    }
)
STATES = tuple(State)
FINAL_STATES = frozenset(str(s) for s in TERMINAL)
#: CSV columns taken from the acknowledgement (the rest are the record's own).
CSV_ACK_COLUMNS = ("corrected_bits", "decode_latency_ms", "replan_latency_ms")
#: The CSV export's columns, in order.
CSV_COLUMNS = (
    "id",
    "dive",
    "created_at",
    "operator",
    "target",
    "kind",
    "pattern",
    "params",
    "hex",
    "bits",
    "state",
    "attempts",
    "sent_at",
    "acked_at",
    "reason",
    "copies",
    "copies_sent",
    "p_delivered",
    "superseded_by",
    *CSV_ACK_COLUMNS,
)


def now_iso() -> str:
    """Current UTC time, ISO 8601 with milliseconds."""
    return datetime.now(UTC).isoformat(timespec="milliseconds")


class MissionLog:
    """The SQLite mission log. Thread-safe."""

    def __init__(self, path: Path | str) -> None:
        self.path = Path(path)
        if str(path) != ":memory:":
            self.path.parent.mkdir(parents=True, exist_ok=True)
        self._lock = threading.RLock()  # re-entered by the writes of a transaction()
        self._db = sqlite3.connect(str(path), check_same_thread=False, isolation_level=None)
        self._db.row_factory = sqlite3.Row
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute("PRAGMA synchronous=FULL")
        self._db.execute("PRAGMA foreign_keys=ON")
        self._db.executescript(SCHEMA)
        self._migrate()
        self._track: list[tuple[int, float, float, float, float, float]] = []

    def _migrate(self) -> None:
        """Add the columns an older log lacks (values of old rows: the declared defaults)."""
        have = {row["name"] for row in self._db.execute("PRAGMA table_info(commands)")}
        for name, declaration in _ADDED_COLUMNS:
            if name not in have:
                self._db.execute(f"ALTER TABLE commands ADD COLUMN {name} {declaration}")

    def recover_interrupted(self) -> int:
        """Every command an earlier run left on its way (``queued`` or ``transmitted``) becomes
        ``interrupted``, naming the last time the log was written. One transaction; returns
        how many. Call before the console takes new commands."""
        on_its_way = sorted(ON_ITS_WAY)
        marks = ", ".join("?" * len(on_its_way))
        target = advance(State.QUEUED, Event.INTERRUPTED)
        with self._lock:
            last = self._db.execute(
                "SELECT MAX(t) FROM (SELECT MAX(updated_at) AS t FROM commands "
                "UNION ALL SELECT MAX(started_at) FROM dives)"
            ).fetchone()[0]
            with self.transaction():
                cur = self._db.execute(
                    "UPDATE commands SET state = ?, updated_at = ?, "
                    "reason = 'the console stopped while this command was ' || state || "
                    "' (the log was last written at ' || ? || "
                    "'); whether the vehicle received it is not known' "
                    f"WHERE state IN ({marks})",
                    (target, now_iso(), last or "an unknown time", *on_its_way),
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
            self._db.execute("BEGIN IMMEDIATE")
            try:
                yield
            except BaseException:
                self._db.execute("ROLLBACK")
                raise
            self._db.execute("COMMIT")

    def close(self) -> None:
        with self._lock:
            self._flush_track()
            self._db.close()

    # --- dives ---------------------------------------------------------------------------

    def new_dive(self, target: str) -> int:
        with self._lock:
            cur = self._db.execute(
                "INSERT INTO dives (started_at, target) VALUES (?, ?)", (now_iso(), target)
            )
            return int(cur.lastrowid or 0)

    def dives(self) -> list[dict[str, Any]]:
        with self._lock:
            self._flush_track()
            rows = self._db.execute(
                "SELECT d.id, d.started_at, d.target, "
                "(SELECT COUNT(*) FROM commands c WHERE c.dive = d.id) AS commands, "
                "(SELECT COUNT(*) FROM track t WHERE t.dive = d.id) AS track_points "
                "FROM dives d ORDER BY d.id DESC"
            ).fetchall()
        return [dict(r) for r in rows]

    def dive_exists(self, dive: int) -> bool:
        with self._lock:
            return (
                self._db.execute("SELECT 1 FROM dives WHERE id = ?", (dive,)).fetchone() is not None
            )

    # --- commands ------------------------------------------------------------------------

    def insert_command(self, dive: int, record: Mapping[str, Any]) -> dict[str, Any]:
        """Write a new command (state ``queued``) and return it with its id. Committed."""
        stamp = now_iso()
        row = {
            "dive": dive,
            "created_at": stamp,
            "updated_at": stamp,
            "state": "queued",
            "attempts": 0,
            **record,
        }
        cols = list(row)
        values = [json.dumps(row[c]) if c in _JSON else row[c] for c in cols]
        with self._lock:
            cur = self._db.execute(
                f"INSERT INTO commands ({', '.join(cols)}) VALUES ({', '.join('?' * len(cols))})",
                values,
            )
            got = self._command(int(cur.lastrowid or 0))
        assert got is not None
        return got

    def update_command(self, command_id: int, **fields: Any) -> dict[str, Any]:
        """Set some fields of a command (one atomic statement); returns the new record."""
        unknown = set(fields) - _UPDATABLE
        if unknown:
            raise ValueError(f"cannot update {sorted(unknown)}; allowed: {sorted(_UPDATABLE)}")
        if "state" in fields:
            if fields["state"] not in STATES:
                allowed = ", ".join(STATES)
                raise ValueError(f"unknown state {fields['state']!r}; allowed: {allowed}")
            fields["state"] = str(fields["state"])
        fields["updated_at"] = now_iso()
        sets = ", ".join(f"{k} = ?" for k in fields)
        values = [json.dumps(v) if k in _JSON else v for k, v in fields.items()]
        with self._lock:
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
        return _record(row) if row is not None else None

    def commands(
        self,
        *,
        state: str | None = None,
        pattern: str | None = None,
        target: str | None = None,
        dive: int | None = None,
        since: str | None = None,
        until: str | None = None,
        limit: int = 200,
        oldest_first: bool = False,
    ) -> list[dict[str, Any]]:
        filters = (
            ("state = ?", state),
            ("pattern = ?", pattern),
            ("target = ?", target),
            ("dive = ?", dive),
            ("created_at >= ?", since),
            ("created_at <= ?", until),
        )
        where = [clause for clause, value in filters if value is not None]
        args: list[Any] = [value for _, value in filters if value is not None]
        sql = "SELECT * FROM commands"
        if where:
            sql += " WHERE " + " AND ".join(where)
        sql += f" ORDER BY id {'ASC' if oldest_first else 'DESC'} LIMIT ?"
        args.append(limit)
        with self._lock:
            rows = self._db.execute(sql, args).fetchall()
        return [_record(r) for r in rows]

    # --- track ---------------------------------------------------------------------------

    def add_track(
        self, dive: int, t_s: float, x_m: float, y_m: float, z_m: float, heading_deg: float
    ) -> None:
        """Buffer one track point; written in batches of 10 (and on close)."""
        with self._lock:
            self._track.append((dive, t_s, x_m, y_m, z_m, heading_deg))
            if len(self._track) >= 10:
                self._flush_track()

    def _flush_track(self) -> None:
        if self._track:
            self._db.executemany("INSERT INTO track VALUES (?, ?, ?, ?, ?, ?)", self._track)
            self._track = []

    def track(self, dive: int) -> list[dict[str, float]]:
        with self._lock:
            self._flush_track()
            rows = self._db.execute(
                "SELECT t_s, x_m, y_m, z_m, heading_deg FROM track WHERE dive = ? ORDER BY t_s",
                (dive,),
            ).fetchall()
        return [dict(r) for r in rows]


def _record(row: sqlite3.Row) -> dict[str, Any]:
    out = dict(row)
    for col in _JSON:
        if out.get(col) is not None:
            out[col] = json.loads(out[col])
    for col in _BOOL:
        if out.get(col) is not None:
            out[col] = bool(out[col])
    return out


def csv_rows(records: Iterable[Mapping[str, Any]]) -> Iterable[list[str]]:
    """The log as CSV rows (header first, :data:`CSV_COLUMNS`); JSON columns as JSON text."""
    yield list(CSV_COLUMNS)
    for r in records:
        ack = r.get("ack") or {}
        values = (ack.get(c) if c in CSV_ACK_COLUMNS else r.get(c) for c in CSV_COLUMNS)
        yield [
            json.dumps(v) if isinstance(v, dict | list) else "" if v is None else str(v)
            for v in values
        ]
