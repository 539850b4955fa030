"""The SQLite connection's change to WAL mode when another connection holds the file: SQLite
answers it with "database is locked" at once, without its busy handler, so
:class:`SqliteDatabase` tries it again for the connection's lock wait (consoles opening one
new log together: test_store.py)."""

from __future__ import annotations

import sqlite3
import time
from collections.abc import Iterator
from pathlib import Path
from types import SimpleNamespace

import pytest

from backend.mission_log import database
from backend.mission_log.database import SqliteDatabase


@pytest.fixture
def writer(tmp_path: Path) -> Iterator[sqlite3.Connection]:
    """A connection in a write transaction on a new file still in rollback-journal mode."""
    db = sqlite3.connect(tmp_path / "log.db", isolation_level=None, check_same_thread=False)
    db.execute("BEGIN IMMEDIATE")
    db.execute("CREATE TABLE t (x INTEGER)")
    yield db
    db.close()


def test_sqlite_refuses_the_mode_change_at_once_without_the_retry(
    writer: sqlite3.Connection, tmp_path: Path
) -> None:
    """The rule the retry is for: the busy handler (here 30 s) is not asked."""
    other = sqlite3.connect(tmp_path / "log.db", timeout=30, isolation_level=None)
    try:
        started = time.monotonic()
        with pytest.raises(sqlite3.OperationalError, match="locked"):
            other.execute("PRAGMA journal_mode=WAL")
        assert time.monotonic() - started < 10
    finally:
        other.close()


def test_the_mode_change_is_tried_again_until_the_other_connection_is_done(
    writer: sqlite3.Connection, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    waits: list[float] = []

    def sleep(seconds: float) -> None:
        waits.append(seconds)
        if len(waits) == 3:
            writer.execute("COMMIT")

    monkeypatch.setattr(database, "time", SimpleNamespace(monotonic=time.monotonic, sleep=sleep))
    db = SqliteDatabase(tmp_path / "log.db", busy_timeout_s=30.0)
    try:
        assert waits == [database.WAL_RETRY_S] * 3
        assert db.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        assert db.execute("SELECT COUNT(*) FROM t").fetchone()[0] == 0
    finally:
        db.close()


def test_a_lock_held_past_the_wait_is_still_locked(
    writer: sqlite3.Connection, tmp_path: Path
) -> None:
    with pytest.raises(sqlite3.OperationalError, match="locked"):
        SqliteDatabase(tmp_path / "log.db", busy_timeout_s=0.05)
