"""A dive in a mission log, filled through the store API (bench/_dive_log.py): ten minutes at
1 Hz with five commands (the fourth rejected), two minutes of navigation fault, a datum and an
echo-mismatch event; on each back-end in turn (a SQLite file, then a fresh database on the
tests' PostgreSQL server), once per module."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from backend.mission_log.store import MissionLog
from bench._dive_log import Filled, ManualUtc, fill_dive
from tests.backend.log_backend import KINDS
from tests.pg_server import PgServer

#: The dive's length (s), and a command every so many seconds.
DIVE_S = 600
COMMAND_EVERY_S = 120


@dataclass(frozen=True)
class DiveLog:
    """The log (a SQLite file, or a PostgreSQL URL with its password) and what was written
    into it."""

    where: Path | str
    filled: Filled


@pytest.fixture(scope="module", params=KINDS)
def dive_log(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[DiveLog]:
    server: PgServer | None = None
    where: Path | str = tmp_path_factory.mktemp("dive") / "missions.sqlite3"
    if request.param == "postgresql":
        server = request.getfixturevalue("pg_server")
        name = server.new_database()
        where = server.url(name)
    clock = ManualUtc()
    log = MissionLog(where, now=clock)
    try:
        filled = fill_dive(log, DIVE_S, clock, COMMAND_EVERY_S)
    finally:
        log.close()
    yield DiveLog(where, filled)
    if server is not None:
        server.drop_database(name)
