"""Opening the mission log with its checks, before the console takes any command.

:func:`open_checked` creates a missing directory, opens the log, runs SQLite's ``quick_check``
and takes (and releases) the write lock. What stops it is a :class:`LogError` whose message
is one line naming the file, what is wrong and what to do (``nemesys console`` prints it and
exits 2): a directory that cannot be created, a file that is not a SQLite database, a
corrupted one, a read-only one (the file, or its directory: WAL creates files beside it), one
locked by another process.
"""

from __future__ import annotations

import os
import sqlite3
from pathlib import Path

from backend.mission_log.store import MissionLog

#: What to do instead, common to every fault.
ELSEWHERE = "or point --db / NEMESYS_DB_PATH elsewhere"
#: How long the check waits for another process's lock before calling the log locked (s).
CHECK_BUSY_TIMEOUT_S = 0.5


class LogError(Exception):
    """The mission log at ``path`` cannot be used: ``problem`` (what is wrong), ``hint`` (what
    to do). The message: ``mission log <path> <problem>: <hint>``."""

    def __init__(self, path: Path, problem: str, hint: str) -> None:
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


def open_checked(path: Path | str) -> MissionLog:
    """The mission log at ``path``, checked (see the module's docstring).

    Raises:
        LogError: one of its subclasses; nothing was written to the log.
    """
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
