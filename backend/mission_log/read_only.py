"""A read-only connection of its own to the mission log, for a long read (a dive's export:
:mod:`backend.mission_log.dive_reader`) that neither holds the console's lock nor sees a write
half-done: each :meth:`ReadOnlyDatabase.snapshot` is one read transaction, every query in it
sees the log as it was at the first, and rows are streamed a batch at a time (constant memory),
as mappings.

What differs between the back-ends for such a read is here and nowhere else (the log's own
connection's differences are :mod:`backend.mission_log.database`'s):

* opening: SQLite's file in ``mode=ro`` (nothing written, an older log not migrated) with a
  small page cache (one pass in order); on PostgreSQL a new psycopg connection whose
  transactions are ``REPEATABLE READ READ ONLY``;
* the snapshot: SQLite's read transaction (WAL: committed transactions only); PostgreSQL's
  repeatable-read transaction (its snapshot taken at the first query);
* streaming: a SQLite cursor; a server-side (named) cursor on PostgreSQL, so the server does
  not send the whole result at once;
* a table's columns: ``PRAGMA table_info`` or ``information_schema``;
* the track's arrival order: SQLite's ``rowid`` (an older log's points have no ``at``);
  PostgreSQL's rows have no order of their own: ``at`` (the console's clock when each point
  arrived, never going back within a run), then between points of one millisecond their place
  in the table (``ctid``: one console's points are appended in the order it wrote them).

The queries are the store's SQL (``?`` placeholders), as on the log's own connection.
"""

from __future__ import annotations

import contextlib
import itertools
import sqlite3
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from backend.mission_log.database import (
    APPLICATION_NAME,
    CONNECT_TIMEOUT_S,
    LogDatabase,
    PostgresDatabase,
    Row,
    is_postgres_url,
    masked,
    pg_sql,
)

if TYPE_CHECKING:
    import psycopg

#: How long opening a SQLite log read-only waits for a writer's lock (s).
READ_BUSY_TIMEOUT_S = 5.0


class ReadOnlyDatabase:
    """A read-only connection to the log (:func:`open_read_only`, :func:`read_only_of`)."""

    #: "sqlite" or "postgresql".
    kind: str
    #: The log as messages name it: the file, or the URL with its password masked.
    where: str
    #: The track's rows in the order they arrived (an ``ORDER BY`` term).
    track_order: str
    #: The log's own connection, shared (an in-memory log has no other): use it under the
    #: log's lock; closing this leaves it open.
    shared = False

    @contextlib.contextmanager
    def snapshot(self) -> Iterator[None]:
        """One read transaction: every query inside sees the log as it was at the first."""
        raise NotImplementedError
        yield  # pragma: no cover

    def one(self, sql: str, params: Sequence[Any] = ()) -> Row | None:
        """The first row of ``sql``."""
        raise NotImplementedError

    def all(self, sql: str, params: Sequence[Any] = ()) -> list[Row]:
        """Every row of ``sql`` (for few rows)."""
        raise NotImplementedError

    def stream(self, sql: str, params: Sequence[Any], batch: int) -> Iterator[Row]:
        """The rows of ``sql``, ``batch`` at a time from the database (inside a snapshot)."""
        raise NotImplementedError

    def columns(self, table: str) -> set[str]:
        """The columns ``table`` has in this log."""
        raise NotImplementedError

    def close(self) -> None:
        raise NotImplementedError


class SqliteReadOnly(ReadOnlyDatabase):
    """A SQLite log read through ``db`` (rows as :class:`sqlite3.Row`)."""

    kind = "sqlite"
    track_order = "rowid"

    def __init__(self, db: sqlite3.Connection, where: str, *, shared: bool = False) -> None:
        self._db = db
        self.where = where
        self.shared = shared

    @classmethod
    def open(cls, path: Path | str, cache_kib: int, busy_timeout_s: float) -> SqliteReadOnly:
        """The file ``path`` read-only.

        Raises:
            sqlite3.Error: it cannot be opened or is not a SQLite database.
        """
        uri = f"{Path(path).resolve().as_uri()}?mode=ro"
        db = sqlite3.connect(uri, uri=True, timeout=busy_timeout_s, check_same_thread=False)
        try:
            db.execute(f"PRAGMA cache_size = -{cache_kib}")
            db.execute("SELECT COUNT(*) FROM sqlite_master").fetchone()  # a database at all
        except BaseException:
            db.close()
            raise
        return cls(db, str(path))

    def _execute(self, sql: str, params: Sequence[Any]) -> sqlite3.Cursor:
        cur = self._db.cursor()
        cur.row_factory = sqlite3.Row  # per cursor: a shared connection's own stay as they are
        return cur.execute(sql, params)

    @contextlib.contextmanager
    def snapshot(self) -> Iterator[None]:
        if self._db.in_transaction:  # a caller's own transaction: its view is the snapshot
            yield
            return
        self._db.execute("BEGIN")
        try:
            yield
        finally:
            self._db.execute("ROLLBACK")

    def one(self, sql: str, params: Sequence[Any] = ()) -> Row | None:
        row: Row | None = self._execute(sql, params).fetchone()  # sqlite3.Row: [name], keys()
        return row

    def all(self, sql: str, params: Sequence[Any] = ()) -> list[Row]:
        return list(self._execute(sql, params).fetchall())

    def stream(self, sql: str, params: Sequence[Any], batch: int) -> Iterator[Row]:
        cursor = self._execute(sql, params)
        try:
            while rows := cursor.fetchmany(batch):
                yield from rows
        finally:
            cursor.close()

    def columns(self, table: str) -> set[str]:
        return {str(r["name"]) for r in self._execute(f"PRAGMA table_info({table})", ())}

    def close(self) -> None:
        if not self.shared:
            self._db.close()


class PostgresReadOnly(ReadOnlyDatabase):
    """A log on PostgreSQL read through a connection of its own (rows as dicts)."""

    kind = "postgresql"
    track_order = "at, ctid"

    def __init__(self, url: str) -> None:
        """Raises: psycopg.Error: the server cannot be reached, or refuses the login."""
        import psycopg

        self.where = masked(url)
        self._db: psycopg.Connection[Any] = psycopg.connect(
            url,
            autocommit=False,  # the first query of a snapshot begins its transaction
            connect_timeout=CONNECT_TIMEOUT_S,
            application_name=f"{APPLICATION_NAME} export",
        )
        self._db.read_only = True
        self._db.isolation_level = psycopg.IsolationLevel.REPEATABLE_READ
        self._names = itertools.count(1)
        self._open: set[psycopg.ServerCursor[Any]] = set()

    @contextlib.contextmanager
    def snapshot(self) -> Iterator[None]:
        import psycopg

        self._db.rollback()  # whatever ran before: the snapshot starts at its own first query
        try:
            yield
        finally:
            for cursor in list(self._open):  # one the consumer left: gone with the transaction
                with contextlib.suppress(psycopg.Error):
                    cursor.close()
            self._open.clear()
            if not self._db.closed:
                self._db.rollback()

    def one(self, sql: str, params: Sequence[Any] = ()) -> Row | None:
        from psycopg.rows import dict_row

        row: Row | None = (
            self._db.cursor(row_factory=dict_row).execute(pg_sql(sql), params).fetchone()
        )
        return row

    def all(self, sql: str, params: Sequence[Any] = ()) -> list[Row]:
        from psycopg.rows import dict_row

        return list(self._db.cursor(row_factory=dict_row).execute(pg_sql(sql), params).fetchall())

    def stream(self, sql: str, params: Sequence[Any], batch: int) -> Iterator[Row]:
        from psycopg.rows import dict_row

        cursor = self._db.cursor(f"nemesys_export_{next(self._names)}", row_factory=dict_row)
        cursor.itersize = batch
        self._open.add(cursor)
        try:
            cursor.execute(pg_sql(sql), params)
            while rows := cursor.fetchmany(batch):
                yield from rows
        finally:
            self._open.discard(cursor)
            cursor.close()

    def columns(self, table: str) -> set[str]:
        rows = self.all(
            "SELECT column_name FROM information_schema.columns "
            "WHERE table_schema = current_schema() AND table_name = ?",
            (table,),
        )
        return {str(r["column_name"]) for r in rows}

    def close(self) -> None:
        self._db.close()


def open_read_only(
    where: Path | str, *, cache_kib: int, busy_timeout_s: float = READ_BUSY_TIMEOUT_S
) -> ReadOnlyDatabase:
    """The log at ``where`` (a SQLite file, or a ``postgresql://`` URL) read-only.

    Raises:
        sqlite3.Error, psycopg.Error: it cannot be opened.
    """
    if is_postgres_url(where):
        return PostgresReadOnly(str(where))
    return SqliteReadOnly.open(where, cache_kib, busy_timeout_s)


def read_only_of(db: LogDatabase, *, cache_kib: int, busy_timeout_s: float) -> ReadOnlyDatabase:
    """A read-only connection to the log ``db`` is on: one of its own, or ``db``'s own
    connection shared for an in-memory SQLite log (:attr:`ReadOnlyDatabase.shared`).

    Raises:
        sqlite3.Error, psycopg.Error: it cannot be opened.
    """
    if isinstance(db, PostgresDatabase):
        return PostgresReadOnly(db.url)
    if db.where == ":memory:":
        return SqliteReadOnly(db.raw, db.where, shared=True)
    return SqliteReadOnly.open(db.where, cache_kib, busy_timeout_s)
