"""Opening the mission log with its checks, before the console takes any command.

:func:`open_checked` creates a missing directory, opens the log (bringing its tables to the
newest migration), runs SQLite's ``quick_check`` and takes (and releases) the write lock.
What stops it is a :class:`LogError` whose message is one line naming the file, what is
wrong and what to do (``nemesys console`` prints it and exits 2): a directory that cannot be
created, a file that is not a SQLite database, a corrupted one, a read-only one (the file, or
its directory: WAL creates files beside it), one locked by another process.

On PostgreSQL (a ``postgresql://`` URL: ``NEMESYS_DATABASE_URL``) the message names the URL
with its password masked: a server that cannot be reached, a login refused, a database that
does not exist, a user that may not write (:func:`classify_postgres`).
"""

from __future__ import annotations

import os
import sqlite3
from pathlib import Path
from typing import TYPE_CHECKING

from backend.mission_log.database import is_postgres_url, masked, one_line
from backend.mission_log.errors import LogSchemaNewer
from backend.mission_log.store import MissionLog

if TYPE_CHECKING:
    import psycopg

#: What to do instead, common to every fault.
ELSEWHERE = "or point --db / NEMESYS_DB_PATH elsewhere"
#: The same for a log on PostgreSQL.
ELSEWHERE_PG = "or fix NEMESYS_DATABASE_URL (unset, the log is the SQLite file --db)"
#: How long the check waits for another process's lock before calling the log locked (s).
CHECK_BUSY_TIMEOUT_S = 0.5


class LogError(Exception):
    """The mission log at ``path`` (a file, or a URL with its password masked) cannot be used:
    ``problem`` (what is wrong), ``hint`` (what to do). The message: ``mission log <path>
    <problem>: <hint>``."""

    def __init__(self, path: Path | str, problem: str, hint: str) -> None:
        super().__init__(f"mission log {path} {problem}: {hint}")
        self.path = path
        self.problem = problem
        self.hint = hint


class LogDirectoryError(LogError):
    """The log's directory does not exist and cannot be created."""


class LogNotADatabase(LogError):
    """The file is not a SQLite database."""


class LogCorrupted(LogError):
    """A SQLite database whose pages are damaged."""


class LogReadOnly(LogError):
    """The file, or the directory it is in, cannot be written."""


class LogLocked(LogError):
    """Another process holds the log's write lock."""


class LogTooNew(LogError):
    """A newer console migrated the log past what this one knows."""


def too_new(path: Path | str, err: LogSchemaNewer) -> LogTooNew:
    return LogTooNew(
        path,
        f"was brought to a newer schema by a newer console (migration {err.at}; this console "
        f"knows up to {err.head})",
        f"run the newer console {elsewhere(path)}",
    )


class LogUnreachable(LogError):
    """The PostgreSQL server cannot be reached."""


class LogLoginRefused(LogError):
    """The PostgreSQL server refused the URL's user or password."""


class LogNoDatabase(LogError):
    """The URL's database does not exist on the PostgreSQL server."""


def open_checked(path: Path | str) -> MissionLog:
    """The mission log at ``path`` (a file, or a ``postgresql://`` URL), checked (see the
    module's docstring).

    Raises:
        LogError: one of its subclasses; nothing was written to the log.
    """
    if is_postgres_url(path):
        return _open_postgres(str(path))
    where = Path(path)
    if str(path) == ":memory:":
        return MissionLog(path)
    try:
        where.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise LogDirectoryError(
            where,
            f"cannot be created: its directory {where.parent} cannot be made "
            f"({err.strerror or err})",
            f"create the directory {ELSEWHERE}",
        ) from None
    _check_writable(where)
    try:
        log = MissionLog(where, busy_timeout_s=CHECK_BUSY_TIMEOUT_S)
    except sqlite3.Error as err:
        raise classify(where, err) from None
    except LogSchemaNewer as err:
        raise too_new(where, err) from None
    try:
        problems = log.check()
    except sqlite3.Error as err:
        log.close()
        raise classify(where, err) from None
    if problems:
        log.close()
        more = f", and {len(problems) - 1} more" if len(problems) > 1 else ""
        raise _corrupted(where, f"quick_check: {problems[0]}{more}")
    log.set_busy_timeout()
    return log


def _check_writable(path: Path) -> None:
    """The file (if it exists) and its directory must be writable: SQLite in WAL mode creates
    ``<name>-wal`` and ``<name>-shm`` beside the file. (Root passes this check whatever the
    modes: SQLite's own error then says read-only, see :func:`classify`.)"""
    hint = f"make it writable {ELSEWHERE}"
    if path.exists() and not os.access(path, os.W_OK):
        raise LogReadOnly(path, "is read-only (the file is not writable)", hint)
    if not os.access(path.parent, os.W_OK):
        raise LogReadOnly(
            path,
            f"is read-only (its directory {path.parent} is not writable: SQLite creates "
            f"{path.name}-wal there)",
            f"make the directory writable {ELSEWHERE}",
        )


def _corrupted(path: Path, detail: str) -> LogCorrupted:
    return LogCorrupted(
        path,
        f"is corrupted ({detail})",
        f"move it aside (sqlite3's .recover may save its rows) {ELSEWHERE}",
    )


def classify(path: Path, err: sqlite3.Error) -> LogError:
    """SQLite's error on opening or checking the log, as a :class:`LogError`."""
    name = getattr(err, "sqlite_errorname", None) or ""
    text = str(err)
    if name == "SQLITE_NOTADB" or "file is not a database" in text:
        return LogNotADatabase(path, "is not a SQLite database", f"move it aside {ELSEWHERE}")
    if name.startswith("SQLITE_CORRUPT") or "malformed" in text:
        return _corrupted(path, text)
    if name.startswith(("SQLITE_BUSY", "SQLITE_LOCKED")) or "locked" in text:
        return LogLocked(
            path,
            "is locked by another process (another console?)",
            f"stop that process {ELSEWHERE}",
        )
    if name.startswith("SQLITE_READONLY") or "readonly" in text or "read-only" in text:
        return LogReadOnly(path, f"is read-only ({text})", f"make it writable {ELSEWHERE}")
    return LogError(
        path,
        f"cannot be opened ({text})",
        f"check that it is a file you may read and write {ELSEWHERE}",
    )


def elsewhere(path: Path | str) -> str:
    """What to do instead, for the log at ``path``."""
    return ELSEWHERE_PG if is_postgres_url(path) else ELSEWHERE


def _open_postgres(url: str) -> MissionLog:
    import psycopg

    where = masked(url)
    try:
        log = MissionLog(url, busy_timeout_s=CHECK_BUSY_TIMEOUT_S)
    except psycopg.Error as err:
        raise classify_postgres(where, err) from None
    except LogSchemaNewer as err:
        raise too_new(where, err) from None
    try:
        log.check()
    except psycopg.Error as err:
        log.close()
        raise classify_postgres(where, err) from None
    log.set_busy_timeout()
    return log


def classify_postgres(where: str, err: psycopg.Error) -> LogError:
    """psycopg's error on opening, migrating or checking the log at ``where`` (the URL,
    its password masked), as a :class:`LogError`."""
    import psycopg

    text = one_line(str(err))
    if isinstance(err, psycopg.OperationalError) and err.sqlstate is None:  # connecting
        if "password authentication failed" in text or "no password supplied" in text:
            return LogLoginRefused(
                where,
                f"cannot be opened: the server refused the login ({text})",
                f"check the user and password in the URL {ELSEWHERE_PG}",
            )
        if "does not exist" in text and "database" in text:
            return LogNoDatabase(
                where,
                f"does not exist on the server ({text})",
                f"create it (createdb, or CREATE DATABASE ... OWNER <the URL's user>) "
                f"{ELSEWHERE_PG}",
            )
        return LogUnreachable(
            where,
            f"cannot be reached ({text})",
            f"start PostgreSQL there, check the host and port {ELSEWHERE_PG}",
        )
    if isinstance(err, psycopg.errors.InvalidCatalogName):
        return LogNoDatabase(where, f"does not exist on the server ({text})", ELSEWHERE_PG)
    if isinstance(
        err, psycopg.errors.ReadOnlySqlTransaction | psycopg.errors.InsufficientPrivilege
    ):
        return LogReadOnly(
            where,
            f"cannot be written ({text})",
            f"use a database the URL's user owns, on a server that takes writes {ELSEWHERE_PG}",
        )
    if isinstance(err, psycopg.errors.LockNotAvailable):
        return LogLocked(
            where,
            f"is locked by another session ({text})",
            f"end that session {ELSEWHERE_PG}",
        )
    return LogError(where, f"cannot be opened ({text})", f"check the server's log {ELSEWHERE_PG}")
