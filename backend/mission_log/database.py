"""The mission log's connection: SQLite (the embedded default, a file) or PostgreSQL (a
server several consoles share), behind one small interface, so the store's SQL is written
once.

Every difference between the two is here and nowhere else:

* placeholders: the store writes ``?``; PostgreSQL (psycopg) gets ``%s`` (:func:`pg_sql`);
* a new row's id: SQLite's ``lastrowid``, PostgreSQL's ``INSERT ... RETURNING id``;
* a write transaction: SQLite's ``BEGIN IMMEDIATE`` (takes the file's write lock at once),
  PostgreSQL's ``BEGIN``; migrations on PostgreSQL also take an advisory lock, so consoles
  starting together migrate one at a time;
* durability: SQLite in WAL mode with ``synchronous=FULL``; PostgreSQL with
  ``synchronous_commit=on`` (a committed row is on the server's disk);
* how long a write waits for another's lock: SQLite's ``busy_timeout``, PostgreSQL's
  ``lock_timeout``;
* the database's clock (:attr:`LogDatabase.now_s_sql`: seconds since 1970, what control's
  heartbeats are judged by, the same for every console) and a row locked for the rest of a
  transaction (``FOR UPDATE`` on PostgreSQL; SQLite's ``BEGIN IMMEDIATE`` already holds the
  whole file), and one another transaction holds skipped (``FOR UPDATE SKIP LOCKED``: a work
  queue several consoles take from, the relay's outbox; SQLite's one writer skips nothing);
* the writing console's name, which PostgreSQL's notifications carry (a session setting,
  ``nemesys.console``, set again on a new connection; SQLite has one console);
* which driver errors are a write that failed (:class:`LogWriteError`: disk full, read-only,
  locked, connection lost) and which are the program's own misuse (integrity and programming
  errors, raised as they are);
* the column types (REAL vs DOUBLE PRECISION, INTEGER PRIMARY KEY vs IDENTITY) are the
  migrations' (:mod:`backend.mission_log.migrating`, SQLAlchemy types).

A long read's own read-only connection (an export's: one snapshot, rows streamed) differs too:
:mod:`backend.mission_log.read_only`.

What is the same on both needs nothing here: ISO 8601 text times, JSON as text, ``||``,
``COALESCE``, ``LIMIT ?``, and upserts (``INSERT ... ON CONFLICT (key) DO UPDATE SET col =
excluded.col`` is the same statement on SQLite >= 3.24 and PostgreSQL).
"""

from __future__ import annotations

import contextlib
import sqlite3
import time
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol
from urllib.parse import urlsplit, urlunsplit

from backend.mission_log.errors import LogWriteError

if TYPE_CHECKING:
    import psycopg

#: URL schemes that select PostgreSQL.
POSTGRES_SCHEMES = ("postgresql", "postgres")
#: How long connecting to PostgreSQL may take before the console says it cannot (s).
CONNECT_TIMEOUT_S = 5
#: The advisory lock (a constant key of our choosing) migrations hold on PostgreSQL.
MIGRATION_LOCK_KEY = 0x4E454D45  # "NEME"
#: How the console names itself to the server (pg_stat_activity).
APPLICATION_NAME = "nemesys-console"
#: How often a new SQLite file's change to WAL mode is tried again while another connection
#: makes it (s).
WAL_RETRY_S = 0.005

Row = Mapping[str, Any]


class Cursor(Protocol):
    """What the store reads of a statement's cursor (rows as mappings)."""

    @property
    def rowcount(self) -> int: ...

    def fetchone(self) -> Any: ...

    def fetchall(self) -> list[Any]: ...


def is_postgres_url(where: str | Path) -> bool:
    """Whether ``where`` is a PostgreSQL URL (``postgresql://...``), not a file."""
    return isinstance(where, str) and urlsplit(where).scheme in POSTGRES_SCHEMES


def masked(url: str) -> str:
    """``url`` with its password replaced by ``***`` (in the user part and in a
    ``password=`` query parameter), for messages and logs."""
    parts = urlsplit(url)
    netloc = parts.netloc
    if "@" in netloc:
        login, host = netloc.rsplit("@", 1)
        if ":" in login:
            login = login.split(":", 1)[0] + ":***"
        netloc = f"{login}@{host}"
    query = "&".join(
        "password=***" if item.lower().startswith("password=") else item
        for item in parts.query.split("&")
    )
    return urlunsplit((parts.scheme, netloc, parts.path, query, parts.fragment))


def pg_sql(sql: str) -> str:
    """The store's SQL with psycopg's placeholders: ``?`` -> ``%s`` and a literal ``%`` ->
    ``%%``, outside quoted literals and identifiers."""
    out: list[str] = []
    quote: str | None = None
    for ch in sql:
        if quote is not None:
            if ch == quote:
                quote = None
            out.append("%%" if ch == "%" else ch)
        elif ch in "'\"":
            quote = ch
            out.append(ch)
        elif ch == "?":
            out.append("%s")
        elif ch == "%":
            out.append("%%")
        else:
            out.append(ch)
    return "".join(out)


class LogDatabase:
    """One connection to the log's database. Not locked: the store holds its own lock
    around every use."""

    #: "sqlite" or "postgresql".
    kind: str
    #: The log as messages name it: the file, or the URL with its password masked.
    where: str
    #: The driver's errors that mean the write failed (raised as :class:`LogWriteError`).
    write_errors: tuple[type[Exception], ...]
    #: The driver's errors of our own misuse (a broken constraint, bad SQL): raised as is.
    misuse_errors: tuple[type[Exception], ...]
    #: Errors among the misuse ones that are a write refused all the same (PostgreSQL: a user
    #: without the right to write is a programming error to psycopg).
    denied_errors: tuple[type[Exception], ...] = ()
    #: The dialect's URL for SQLAlchemy (migrations run on this same connection).
    sqlalchemy_url: str
    #: ``BEGIN`` of a write transaction.
    begin_sql: str
    #: An expression of the database's clock: seconds since 1970 (UTC), a float.
    now_s_sql: str
    #: What follows a ``SELECT`` to lock its rows until the transaction ends.
    for_update: str = ""
    #: The same, leaving out the rows another transaction has locked.
    skip_locked: str = ""

    @property
    def raw(self) -> Any:
        """The driver's connection (for the migrations' SQLAlchemy engine)."""
        raise NotImplementedError

    @property
    def in_transaction(self) -> bool:
        raise NotImplementedError

    def execute(self, sql: str, params: Sequence[Any] = ()) -> Cursor:
        raise NotImplementedError

    def executemany(self, sql: str, rows: Iterable[Sequence[Any]]) -> None:
        raise NotImplementedError

    def insert(self, sql: str, params: Sequence[Any]) -> int:
        """Run ``INSERT ...`` (one row into a table with an ``id``); the new row's id."""
        raise NotImplementedError

    def set_busy_timeout(self, seconds: float) -> None:
        raise NotImplementedError

    def check(self) -> list[str]:
        """The database's own integrity check (problems found; none: intact); then a write
        that changes nothing, rolled back: raises the driver's error if the log is locked by
        another process or read-only."""
        raise NotImplementedError

    def lock_for_migration(self) -> None:
        """Inside the migration's transaction: hold off other consoles migrating the same
        database until it ends."""

    def name_console(self, console: str) -> None:
        """The console's name, for what the database tells other consoles of its writes."""

    def close(self) -> None:
        raise NotImplementedError

    @contextlib.contextmanager
    def writing(self) -> Iterator[None]:
        """The driver's errors of a write as :class:`LogWriteError` (our own misuse stays as
        it is)."""
        try:
            yield
        except self.write_errors as err:
            if isinstance(err, self.misuse_errors) and not isinstance(err, self.denied_errors):
                raise
            raise LogWriteError(one_line(str(err))) from err


def one_line(text: str) -> str:
    """A driver's message on one line (psycopg's span several)."""
    return " ".join(text.split())


class SqliteDatabase(LogDatabase):
    """The log in a SQLite file (or ``:memory:``), WAL mode, ``synchronous=FULL``."""

    kind = "sqlite"
    write_errors = (sqlite3.DatabaseError,)
    misuse_errors = (sqlite3.IntegrityError, sqlite3.ProgrammingError)
    sqlalchemy_url = "sqlite://"
    begin_sql = "BEGIN IMMEDIATE"
    now_s_sql = "((julianday('now') - 2440587.5) * 86400.0)"

    def __init__(self, path: Path | str, busy_timeout_s: float) -> None:
        self.where = str(path)
        if str(path) != ":memory:":
            Path(path).parent.mkdir(parents=True, exist_ok=True)
        self._db = sqlite3.connect(
            str(path), timeout=busy_timeout_s, check_same_thread=False, isolation_level=None
        )
        try:
            _enter_wal(self._db, busy_timeout_s)
            self._db.execute("PRAGMA synchronous=FULL")
            self._db.execute("PRAGMA foreign_keys=ON")
        except BaseException:
            self._db.close()
            raise

    @property
    def raw(self) -> sqlite3.Connection:
        return self._db

    @property
    def in_transaction(self) -> bool:
        return self._db.in_transaction

    def _cursor(self) -> sqlite3.Cursor:
        cur = self._db.cursor()
        cur.row_factory = sqlite3.Row  # per cursor: SQLAlchemy's own stay tuples
        return cur

    def execute(self, sql: str, params: Sequence[Any] = ()) -> sqlite3.Cursor:
        return self._cursor().execute(sql, params)

    def executemany(self, sql: str, rows: Iterable[Sequence[Any]]) -> None:
        self._db.executemany(sql, rows)

    def insert(self, sql: str, params: Sequence[Any]) -> int:
        return int(self._db.execute(sql, params).lastrowid or 0)

    def set_busy_timeout(self, seconds: float) -> None:
        self._db.execute(f"PRAGMA busy_timeout = {round(seconds * 1000)}")

    def check(self) -> list[str]:
        rows = self._db.execute("PRAGMA quick_check").fetchall()
        self._db.execute("BEGIN IMMEDIATE")  # busy: locked
        try:
            self._db.execute("DELETE FROM dives WHERE 0")  # read-only, as opened
        finally:
            self._db.execute("ROLLBACK")
        return [
            line
            for row in rows
            for line in str(row[0]).splitlines()
            if line != "ok" and not line.startswith("***")
        ]

    def close(self) -> None:
        self._db.close()


def _enter_wal(db: sqlite3.Connection, wait_s: float) -> None:
    """Put the file in WAL mode (a no-op once it is). A new file's first connection changes
    its mode under an exclusive lock, and SQLite answers another connection changing it at
    that moment with "database is locked" at once, without its busy handler: consoles
    opening one new log together would fail. So the change is tried again for up to
    ``wait_s`` (s), the connection's own lock wait."""
    deadline = time.monotonic() + wait_s
    while True:
        try:
            db.execute("PRAGMA journal_mode=WAL")
            return
        except sqlite3.OperationalError as err:
            if "locked" not in str(err) or time.monotonic() >= deadline:
                raise
        time.sleep(WAL_RETRY_S)


class PostgresDatabase(LogDatabase):
    """The log on a PostgreSQL server, through psycopg 3 (autocommit: every statement
    outside :meth:`begin` is its own transaction, committed when it returns). A connection
    the server dropped is opened again before the next statement outside a transaction
    (the one that found it dropped failed: :class:`LogWriteError`)."""

    kind = "postgresql"
    sqlalchemy_url = "postgresql+psycopg://"
    begin_sql = "BEGIN"
    now_s_sql = "CAST(EXTRACT(EPOCH FROM clock_timestamp()) AS DOUBLE PRECISION)"
    for_update = " FOR UPDATE"
    skip_locked = " FOR UPDATE SKIP LOCKED"
    #: The console's name (``nemesys.console``, set on every new connection); "": not named.
    console = ""

    def __init__(self, url: str, busy_timeout_s: float) -> None:
        import psycopg

        self.url = url
        self.where = masked(url)
        self.write_errors = (psycopg.Error,)
        self.misuse_errors = (psycopg.IntegrityError, psycopg.ProgrammingError)
        self.denied_errors = (psycopg.errors.InsufficientPrivilege,)
        self._busy_timeout_s = busy_timeout_s
        self._db = self._connect()

    def _connect(self) -> psycopg.Connection[Any]:
        import psycopg

        db = psycopg.connect(
            self.url,
            autocommit=True,
            connect_timeout=CONNECT_TIMEOUT_S,
            application_name=APPLICATION_NAME,
        )
        try:
            db.execute("SET synchronous_commit = on")
            db.execute(f"SET lock_timeout = '{round(self._busy_timeout_s * 1000)}ms'")
            if self.console:
                db.execute("SELECT set_config('nemesys.console', %s, false)", (self.console,))
        except BaseException:
            db.close()
            raise
        return db

    def _live(self) -> psycopg.Connection[Any]:
        if self._db.closed and not self._closed:
            self._db = self._connect()
        return self._db

    _closed = False

    @property
    def raw(self) -> psycopg.Connection[Any]:
        return self._live()

    @property
    def in_transaction(self) -> bool:
        from psycopg.pq import TransactionStatus

        # a dropped connection's status is UNKNOWN: no transaction to finish (the next
        # statement outside one opens the connection again)
        return self._db.info.transaction_status in (
            TransactionStatus.ACTIVE,
            TransactionStatus.INTRANS,
            TransactionStatus.INERROR,
        )

    def execute(self, sql: str, params: Sequence[Any] = ()) -> Cursor:
        from psycopg.rows import dict_row

        db = self._db if self.in_transaction else self._live()
        cur = db.cursor(row_factory=dict_row)  # per cursor: SQLAlchemy's own stay tuples
        return cur.execute(pg_sql(sql), params)

    def executemany(self, sql: str, rows: Iterable[Sequence[Any]]) -> None:
        db = self._db if self.in_transaction else self._live()
        with db.cursor() as cur:
            cur.executemany(pg_sql(sql), rows)

    def insert(self, sql: str, params: Sequence[Any]) -> int:
        row = self.execute(f"{sql} RETURNING id", params).fetchone()
        return int(row["id"])

    def set_busy_timeout(self, seconds: float) -> None:
        self._busy_timeout_s = seconds
        self.execute(f"SET lock_timeout = '{round(seconds * 1000)}ms'")

    def check(self) -> list[str]:
        self.execute("BEGIN")
        try:  # a read-only server or database, or a user without the right, fails here
            self.execute("DELETE FROM dives WHERE false")
        finally:
            self.execute("ROLLBACK")
        return []

    def lock_for_migration(self) -> None:
        self.execute("SELECT pg_advisory_xact_lock(?)", (MIGRATION_LOCK_KEY,))

    def name_console(self, console: str) -> None:
        self.console = console
        self.execute("SELECT set_config('nemesys.console', ?, false)", (console,))

    def close(self) -> None:
        self._closed = True
        self._db.close()


def open_database(where: Path | str, busy_timeout_s: float) -> LogDatabase:
    """The log's database: a PostgreSQL URL (:func:`is_postgres_url`), else a SQLite file.

    Raises:
        sqlite3.Error, psycopg.Error: it cannot be opened.
    """
    if is_postgres_url(where):
        return PostgresDatabase(str(where), busy_timeout_s)
    return SqliteDatabase(where, busy_timeout_s)
