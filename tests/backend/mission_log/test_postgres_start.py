"""The mission log on PostgreSQL at start (``nemesys console`` as a subprocess with
``NEMESYS_DATABASE_URL``): a server that cannot be reached, a refused login, a missing
database and a URL of another kind each give one line on stderr naming the URL with its
password masked (never the password), and exit 2 with no URL and no traceback."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.backend.mission_log.test_db_faults import assert_refused, run_console
from tests.pg_server import PASSWORD, PgServer
from tests.pg_server import free_port as free_pg_port


def assert_names_the_url(line: str, url: str) -> None:
    """The line names ``url`` with its password masked, and never the password."""
    assert url.replace(f":{PASSWORD}@", ":***@") in line, line
    assert PASSWORD not in line
    assert "NEMESYS_DATABASE_URL" in line


@pytest.mark.slow  # a `nemesys console` subprocess
def test_a_postgres_server_that_cannot_be_reached(tmp_path: Path) -> None:
    url = f"postgresql://nemesys:{PASSWORD}@127.0.0.1:{free_pg_port()}/nemesys"
    line = assert_refused(
        run_console(tmp_path / "missions.sqlite3", database_url=url),
        "cannot be reached",
        "Connection refused",
        "start PostgreSQL there",
    )
    assert_names_the_url(line, url)
    assert not (tmp_path / "missions.sqlite3").exists()  # no SQLite log instead


@pytest.mark.slow  # `nemesys console` subprocesses
def test_a_postgres_login_refused_or_database_missing(tmp_path: Path, pg_server: PgServer) -> None:
    wrong = pg_server.url("postgres").replace(PASSWORD, "not-the-password")
    line = assert_refused(
        run_console(tmp_path / "missions.sqlite3", database_url=wrong),
        "the server refused the login",
        "password authentication failed",
        "check the user and password",
    )
    assert "not-the-password" not in line and ":***@" in line
    missing = pg_server.url("no_such_database")
    line = assert_refused(
        run_console(tmp_path / "missions.sqlite3", database_url=missing),
        "does not exist on the server",
        "create it",
    )
    assert_names_the_url(line, missing)


@pytest.mark.slow  # a `nemesys console` subprocess
def test_a_database_url_of_another_kind_is_refused_without_its_password(tmp_path: Path) -> None:
    line = assert_refused(
        run_console(tmp_path / "missions.sqlite3", database_url="mysql://op:hunter2@db/log"),
        "setting database_url",
        "postgresql://user:password@host:port/database",
        "scheme 'mysql'",
    )
    assert "hunter2" not in line
