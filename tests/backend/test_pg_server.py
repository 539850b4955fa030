"""The tests' PostgreSQL server (tests/pg_server.py): found where Debian puts it, or a failure
that says how to install it (never a skip); running, it listens on 127.0.0.1 only, as the
``postgres`` user when the tests run as root, and takes the password login of its URLs."""

from __future__ import annotations

import glob
import os
import shutil
import subprocess
from pathlib import Path

import psycopg
import pytest

from tests import pg_server
from tests.pg_server import PgServer, PostgresMissing


def test_without_postgres_the_tests_say_how_to_install_it(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setattr(shutil, "which", lambda _name: None)
    monkeypatch.setattr(glob, "glob", lambda _pattern: [str(tmp_path / "15" / "bin")])
    with pytest.raises(PostgresMissing) as missing:
        pg_server.bindir()
    assert "apt-get install postgresql" in str(missing.value)
    assert str(missing.value) == pg_server.INSTALL_HINT


def test_the_server_is_found_and_listens_on_loopback_only(pg_server: PgServer) -> None:
    assert (pg_server.bin / "initdb").is_file()
    with psycopg.connect(pg_server.url()) as db:
        ((addresses,),) = db.execute("SHOW listen_addresses").fetchall()
        ((socket_dir,),) = db.execute("SHOW unix_socket_directories").fetchall()
    assert addresses == "127.0.0.1"
    assert Path(socket_dir) == pg_server.root  # its own, not the system's
    pid = int((pg_server.data / "postmaster.pid").read_text().split()[0])
    owner = subprocess.run(
        ["ps", "-o", "user=", "-p", str(pid)], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert owner == ("postgres" if os.geteuid() == 0 else os.environ.get("USER", owner))
    with pytest.raises(psycopg.OperationalError, match="password authentication failed"):
        psycopg.connect(pg_server.url(password="wrong")).close()


def test_each_test_database_is_new_and_empty(pg_server: PgServer) -> None:
    first, second = pg_server.new_database(), pg_server.new_database()
    try:
        assert first != second
        with psycopg.connect(pg_server.url(first)) as db:
            tables = db.execute(
                "SELECT COUNT(*) FROM information_schema.tables WHERE table_schema = 'public'"
            ).fetchall()
        assert tables == [(0,)]
    finally:
        pg_server.drop_database(first)
        pg_server.drop_database(second)
