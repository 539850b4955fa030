"""The mission log's two back-ends, for the tests that run on both (the ``log_backend``
fixture of ``tests/backend/conftest.py``): a SQLite file in the test's temporary directory,
or a fresh database on the tests' PostgreSQL server (``tests/pg_server.py``).

A :class:`LogBackend` opens the log, gives the settings or the ``nemesys console`` arguments
that put a console on it, and reads it over a connection of its own (what a killed process
leaves is what another connection sees).
"""

from __future__ import annotations

import sqlite3
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from backend.mission_log.database import pg_sql
from backend.mission_log.store import MissionLog

KINDS = ("sqlite", "postgresql")


@dataclass
class LogBackend:
    """``kind``: "sqlite" or "postgresql"; ``tmp``: the test's directory (the SQLite file,
    the token file); ``url``: the PostgreSQL database (with its password)."""

    kind: str
    tmp: Path
    url: str = ""

    @property
    def postgres(self) -> bool:
        return self.kind == "postgresql"

    @property
    def path(self) -> Path:
        """The SQLite file (on PostgreSQL the console's ``--db``, where its token is kept)."""
        return self.tmp / "log" / "missions.sqlite3"

    @property
    def where(self) -> Path | str:
        """What :class:`MissionLog` and ``open_checked`` take."""
        return self.url if self.postgres else self.path

    def open(self) -> MissionLog:
        return MissionLog(self.where)

    def settings(self) -> dict[str, Any]:
        """Settings overrides that put a console's log here."""
        return {"db_path": self.path, "database_url": self.url}

    def console_args(self) -> tuple[str, ...]:
        """``nemesys console`` arguments (with :meth:`console_env`)."""
        return ("--db", str(self.path))

    def console_env(self) -> dict[str, str]:
        return {"NEMESYS_DATABASE_URL": self.url} if self.postgres else {}

    def query(self, sql: str, params: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
        """Rows of ``sql`` (``?`` placeholders) over a connection of its own."""
        if self.postgres:
            import psycopg

            with psycopg.connect(self.url) as pg:
                return list(pg.execute(pg_sql(sql), params).fetchall())
        with sqlite3.connect(self.path) as raw:
            rows = raw.execute(sql, params).fetchall()
        raw.close()
        return rows

    def scalar(self, sql: str, params: tuple[Any, ...] = ()) -> Any:
        ((value,),) = self.query(sql, params)
        return value

    @property
    def integrity_error(self) -> type[Exception]:
        """What a broken constraint raises (the program's own misuse: not a write failure)."""
        if self.postgres:
            import psycopg

            return psycopg.IntegrityError
        return sqlite3.IntegrityError

    def write_error(self, message: str) -> Exception:
        """The driver's error of a write on a full disk, saying ``message``."""
        if self.postgres:
            import psycopg

            return psycopg.errors.DiskFull(message)
        return sqlite3.OperationalError(message)
