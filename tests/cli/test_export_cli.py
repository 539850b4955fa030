"""``nemesys export DIVE --mcap FILE --rosbag2 DIR``: a dive of a log written for the robotics
tools, the log a SQLite file or a PostgreSQL database (``log_backend``: ``--db`` takes either);
every bad input one line, exit status 2 and nothing written."""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from rosbags.highlevel import AnyReader

from backend.bag.msgdefs import typestore
from backend.mission_log.store import MissionLog
from bench._dive_log import ManualUtc, fill_dive
from cli.common import EXIT_OK, EXIT_USAGE
from cli.main import main
from tests.backend.log_backend import LogBackend
from tests.pg_server import PgServer


@pytest.fixture
def log_path(log_backend: LogBackend) -> str:
    """The log with a dive of 200 s: a file in its own directory (beside it, SQLite's -wal and
    -shm), or a PostgreSQL URL."""
    clock = ManualUtc()
    log = MissionLog(log_backend.where, now=clock)
    fill_dive(log, 200, clock, command_every_s=60)
    log.close()
    return str(log_backend.where)


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    out = io.StringIO()
    status = main(argv, out=out)
    return status, out.getvalue(), capsys.readouterr().err


def test_a_dive_is_written_in_both_forms_with_progress(
    log_path: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mcap, bag = tmp_path / "dive.mcap", tmp_path / "dive_bag"
    argv = ["export", "1", "--db", log_path, "--mcap", str(mcap), "--rosbag2", str(bag)]
    status, out, err = run(argv, capsys)
    assert status == EXIT_OK, err
    lines = out.splitlines()
    assert lines[0].startswith(f"{mcap}: dive 1, ") and lines[1].startswith(f"{bag}: dive 1, ")
    assert "/nemesys/typed/status 200" in lines[0] and "MB in" in lines[0]
    assert err.count("(100 %)") == 2  # the progress, on standard error
    for path in (mcap, bag):
        with AnyReader([path], default_typestore=typestore()) as reader:
            statuses = [c for c in reader.connections if c.topic == "/nemesys/typed/status"]
            assert [c.msgcount for c in statuses] == [200]


def test_the_log_defaults_to_the_consoles_variable(
    log_path: str,
    log_backend: LogBackend,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """As the console: NEMESYS_DATABASE_URL when set, else the file NEMESYS_DB_PATH."""
    monkeypatch.setenv("NEMESYS_DB_PATH", str(tmp_path / "none.sqlite3"))
    monkeypatch.setenv("NEMESYS_DATABASE_URL", log_path)
    if not log_backend.postgres:
        monkeypatch.setenv("NEMESYS_DB_PATH", log_path)
        monkeypatch.delenv("NEMESYS_DATABASE_URL")
    status, _, err = run(["export", "1", "--quiet", "--mcap", str(tmp_path / "d.mcap")], capsys)
    assert status == EXIT_OK and err == ""


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["7", "--mcap", "{tmp}/x.mcap"], "no dive 7 in the mission log (its only dive is 1)"),
        (["1"], "give --mcap FILE, --rosbag2 DIR, or both"),
        (["0", "--mcap", "{tmp}/x.mcap"], "DIVE is a dive's number, 1 and up, got 0"),
        (["1", "--mcap", "{tmp}/no/x.mcap"], "is not a directory: cannot write"),
        (["1", "--mcap", "{tmp}/x.mcap", "--db", "{tmp}/none.sqlite3"], "does not exist"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_nothing_written(
    log_path: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    args: list[str],
    message: str,
) -> None:
    argv = ["export", *(a.replace("{tmp}", str(tmp_path)) for a in args)]
    if "--db" not in argv:
        argv += ["--db", log_path]
    before = sorted(p.name for p in tmp_path.iterdir())
    status, out, err = run(argv, capsys)
    assert status == EXIT_USAGE and out == ""
    assert err.startswith("nemesys export: ") and message in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_an_existing_output_needs_force(
    log_path: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "dive.mcap"
    target.write_text("an earlier export")
    argv = ["export", "1", "--db", log_path, "--quiet", "--mcap", str(target)]
    status, _, err = run(argv, capsys)
    assert status == EXIT_USAGE and f"{target} exists: give --force to replace it" in err
    assert target.read_text() == "an earlier export"
    status, _, err = run([*argv, "--force"], capsys)
    assert status == EXIT_OK, err
    assert target.read_bytes()[:8] == b"\x89MCAP0\r\n"


def test_a_bad_datum_is_refused_naming_the_format(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [
        "export",
        "1",
        "--db",
        str(tmp_path / "log.sqlite3"),
        "--mcap",
        str(tmp_path / "x.mcap"),
    ]
    status, _, err = run([*argv, "--datum", "43.1"], capsys)
    assert status == EXIT_USAGE and "LAT,LON in degrees is needed" in err
    status, _, err = run([*argv, "--datum", "91,5"], capsys)
    assert status == EXIT_USAGE and "latitude must be in [-90, 90]" in err


@pytest.mark.parametrize(
    ("password", "database", "message"),
    [
        ("wrong", "postgres", "cannot be opened: the server refused the login"),
        (None, "no_such_log", "does not exist on the server"),
    ],
)
def test_a_postgres_log_that_cannot_be_read_is_one_line_with_the_password_masked(
    pg_server: PgServer,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    password: str | None,
    database: str,
    message: str,
) -> None:
    url = (
        pg_server.url(database) if password is None else pg_server.url(database, password=password)
    )
    argv = ["export", "1", "--db", url, "--mcap", str(tmp_path / "x.mcap")]
    status, out, err = run(argv, capsys)
    assert status == EXIT_USAGE and out == ""
    assert err.startswith("nemesys export: mission log postgresql://") and err.count("\n") == 1
    assert message in err and ":***@" in err and pg_server.url(database).split("@")[0] not in err
    assert list(tmp_path.iterdir()) == []
