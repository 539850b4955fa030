"""The mission log's faults. At start (``nemesys console`` as a subprocess): a file that is not
a database, a corrupted one, a read-only one, one locked by another process, a directory that
cannot be made, and a busy port each give one line on stderr naming the file (or port) and
exit 2, with no URL and no traceback; a missing directory is created; the URL is printed only
once the server answers (on PostgreSQL: test_postgres_start.py). While running, on both
back-ends (``log_backend``): a write that fails fails the send with 503 and its reason, and no
frame leaves that the log does not hold; a write failing after a frame left stops that
delivery, logged. Track points are on disk within a second of their arrival.

Running as root, chmod does not make a file read-only; the read-only case is then run with
SQLite's own read-only open (``mode=ro``, what SQLite falls back to on a file it may not
write) patched into ``sqlite3.connect`` of the subprocess.
"""

from __future__ import annotations

import asyncio
import logging
import os
import queue
import re
import socket
import sqlite3
import subprocess
import sys
import threading
import time
from collections.abc import Awaitable, Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import httpx
import pytest
from fastapi.testclient import TestClient

from backend.commands.manager import CommandManager
from backend.mission_log.database import LogDatabase
from backend.mission_log.store import TRACK_FLUSH_S, LogWriteError, MissionLog
from bench._server import REPO, free_port
from station.link import Capability
from tests.agent_link import AgentLink
from tests.backend.commands.test_manager import CIRCLE as CIRCLE_FRAME
from tests.backend.commands.test_manager import COPY_INTERVAL_S, Rig
from tests.backend.commands.test_manager import HOVER as HOVER_FRAME
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    TOKEN,
    MakeClient,
    MakeLightClient,
    command_fields,
    console_of,
    wait_until,
)
from tests.backend.log_backend import LogBackend
from tests.manual_clock import ManualClock

#: The line with the operator URL (viser prints a URL of its own, without a token).
URL_LINE = re.compile(r"(http://[^/\s]+)/\?token=\S+")
RUN_TIMEOUT_S = 60.0
DISK_FULL = "database or disk is full"
NOTHING_SENT = "; nothing was transmitted"
ROOT = os.geteuid() == 0

#: ``python -c`` of a console whose every SQLite connection is opened read-only by SQLite.
READ_ONLY_CONSOLE = """
import runpy, sqlite3, sys
from pathlib import Path
_connect = sqlite3.connect
def connect(database, *args, **kwargs):
    kwargs["uri"] = True
    return _connect(Path(database).resolve().as_uri() + "?mode=ro", *args, **kwargs)
sqlite3.connect = connect
sys.argv = ["nemesys", *sys.argv[1:]]
runpy.run_module("cli.main", run_name="__main__")
"""


# --- helpers ------------------------------------------------------------------------------


def console_env(**more: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("NEMESYS_")}
    env["NEMESYS_TOKEN"] = TOKEN
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    env.update(more)
    return env


def console_args(db: Path, port: int) -> list[str]:
    return ["console", "--db", str(db), "--port", str(port), "--viewer-port", "0"]


def run_console(
    db: Path, port: int | None = None, *, prelude: str | None = None, database_url: str = ""
) -> subprocess.CompletedProcess[str]:
    """``nemesys console`` to its end (a fault ends it at once; a console that starts instead
    is stopped at the timeout and fails the test); its log on ``database_url`` when given."""
    start = ["-c", prelude] if prelude else ["-m", "cli.main"]
    more = {"NEMESYS_DATABASE_URL": database_url} if database_url else {}
    return subprocess.run(
        [sys.executable, *start, *console_args(db, port or free_port())],
        cwd=REPO,
        env=console_env(**more),
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
        check=False,
    )


def assert_refused(result: subprocess.CompletedProcess[str], *words: str) -> str:
    """Exit 2, exactly one line on stderr holding ``words``, no URL, no traceback."""
    output = result.stdout + result.stderr
    assert result.returncode == 2, output
    lines = result.stderr.splitlines()
    assert len(lines) == 1, output
    assert "http://" not in result.stdout and "Traceback" not in output
    line = lines[0]
    assert line.startswith("nemesys console: "), line
    for word in words:
        assert word in line, line
    return line


def make_log(path: Path, track_points: int = 0, commands: int = 0) -> None:
    log = MissionLog(path)
    try:
        dive = log.new_dive("sim")
        for _ in range(commands):
            log.insert_command(dive, command_fields())
        for i in range(track_points):
            log.add_track(dive, float(i), float(i), -float(i), 2.0, 90.0)
    finally:
        log.close()


def corrupt(path: Path) -> None:
    """A valid log of many pages, then 200 zero bytes into every page from the third on
    (the first two, with the header and the schema, are kept): b-tree cells point nowhere."""
    make_log(path, track_points=3000, commands=20)
    page_bytes = 4096
    pages = path.stat().st_size // page_bytes
    assert pages > 8
    with path.open("r+b") as f:
        for page in range(2, pages):
            f.seek(page * page_bytes + 100)
            f.write(bytes(200))


def full_disk(db: LogDatabase, message: str) -> Exception:
    """The driver's error of a write on a full disk: SQLite's ``OperationalError``,
    PostgreSQL's ``DiskFull`` (53100)."""
    if db.kind == "postgresql":
        import psycopg

        return psycopg.errors.DiskFull(message)
    return sqlite3.OperationalError(message)


class FailingWrites:
    """The log's connection, whose statements beginning with one of ``verbs`` fail as the
    database fails them on a full disk (:func:`full_disk`); the rest go to the real one."""

    def __init__(self, db: LogDatabase, verbs: Sequence[str], message: str) -> None:
        self.db = db
        self.verbs = tuple(v.upper() for v in verbs)
        self.message = message

    def _check(self, sql: str) -> None:
        if sql.lstrip().upper().startswith(self.verbs):
            raise full_disk(self.db, self.message)

    def execute(self, sql: str, parameters: Any = ()) -> Any:
        self._check(sql)
        return self.db.execute(sql, parameters)

    def executemany(self, sql: str, parameters: Any) -> None:
        self._check(sql)
        self.db.executemany(sql, parameters)

    def insert(self, sql: str, parameters: Any) -> int:
        self._check(sql)
        return self.db.insert(sql, parameters)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.db, name)


@contextmanager
def failing_writes(
    log: MissionLog, *verbs: str, message: str = DISK_FULL
) -> Iterator[FailingWrites]:
    """``log``'s statements beginning with ``verbs`` fail while inside."""
    with log._lock:
        real: LogDatabase = log._db
        proxy = FailingWrites(real, verbs, message)
        log._db = proxy  # type: ignore[assignment]
    try:
        yield proxy
    finally:
        with log._lock:
            log._db = real


def command_rows(log_backend: LogBackend) -> int:
    count: int = log_backend.scalar("SELECT COUNT(*) FROM commands")
    return count


# --- at start: the mission log ------------------------------------------------------------


@pytest.mark.slow  # a `nemesys console` subprocess
def test_a_file_that_is_not_a_database(tmp_path: Path) -> None:
    db = tmp_path / "missions.sqlite3"
    db.write_bytes(os.urandom(8192))
    line = assert_refused(run_console(db), str(db), "is not a SQLite database", "move it aside")
    assert line == (
        f"nemesys console: mission log {db} is not a SQLite database: move it aside or point "
        "--db / NEMESYS_DB_PATH elsewhere"
    )


@pytest.mark.slow  # a `nemesys console` subprocess
def test_a_corrupted_database(tmp_path: Path) -> None:
    db = tmp_path / "missions.sqlite3"
    corrupt(db)
    with sqlite3.connect(db) as raw:  # the damage is one SQLite itself finds
        assert raw.execute("PRAGMA quick_check").fetchone()[0] != "ok"
    assert_refused(run_console(db), str(db), "is corrupted (quick_check: ", "move it aside")


@pytest.mark.slow  # a `nemesys console` subprocess
def test_a_database_with_a_damaged_schema(tmp_path: Path) -> None:
    db = tmp_path / "missions.sqlite3"
    make_log(db)
    with db.open("r+b") as f:  # the schema's cells on the first page, after the header
        f.seek(3000)
        f.write(b"\xff" * 1000)
    assert_refused(run_console(db), str(db), "is corrupted", "move it aside")


#: As root the modes do not stop writes, and os.access says so: the console is run with
#: os.access answering as it does for a user without write permission on the log's folder.
NO_WRITE_ACCESS_CONSOLE = """
import os, runpy, sys
_access = os.access
def access(path, mode, *args, **kwargs):
    if mode & os.W_OK and "logs" in str(path):
        return False
    return _access(path, mode, *args, **kwargs)
os.access = access
sys.argv = ["nemesys", *sys.argv[1:]]
runpy.run_module("cli.main", run_name="__main__")
"""


@pytest.mark.slow  # a `nemesys console` subprocess
def test_a_read_only_file(tmp_path: Path) -> None:
    db = tmp_path / "logs" / "missions.sqlite3"
    db.parent.mkdir()
    make_log(db)
    db.chmod(0o444)
    db.parent.chmod(0o555)
    try:
        # a user gets the modes; root (CI) gets the same answers from os.access
        prelude = NO_WRITE_ACCESS_CONSOLE if ROOT else None
        assert_refused(run_console(db, prelude=prelude), str(db), "is read-only", "writable")
    finally:
        db.parent.chmod(0o755)
        db.chmod(0o644)


@pytest.mark.slow  # a `nemesys console` subprocess
def test_a_file_sqlite_opens_read_only(tmp_path: Path) -> None:
    db = tmp_path / "missions.sqlite3"
    make_log(db)
    result = run_console(db, prelude=READ_ONLY_CONSOLE)
    line = assert_refused(result, str(db), "is read-only", "make it writable")
    assert "attempt to write a readonly database" in line


@pytest.mark.slow  # `nemesys console` and sqlite3 subprocesses
@pytest.mark.parametrize("journal", ["wal", "delete"])
def test_a_database_locked_by_another_process(tmp_path: Path, journal: str) -> None:
    db = tmp_path / "missions.sqlite3"
    make_log(db)
    holder = sqlite3.connect(db, isolation_level=None)
    try:
        holder.execute(f"PRAGMA journal_mode={journal}")
        holder.execute("BEGIN EXCLUSIVE")
        holder.execute("INSERT INTO dives (started_at, target) VALUES ('now', 'other')")
        line = assert_refused(run_console(db), str(db), "is locked by another process")
    finally:
        holder.execute("ROLLBACK")
        holder.close()
    assert "another console?" in line


@pytest.mark.slow  # a `nemesys console` subprocess
def test_a_directory_that_cannot_be_made(tmp_path: Path) -> None:
    blocker = tmp_path / "not-a-directory"
    blocker.write_text("a file where the directory should be")
    db = blocker / "logs" / "missions.sqlite3"
    line = assert_refused(run_console(db), str(db), "cannot be created", "create the directory")
    assert str(db.parent) in line


# --- at start: the port, the URL ----------------------------------------------------------


@pytest.mark.slow  # a `nemesys console` subprocess
def test_a_busy_port(tmp_path: Path) -> None:
    with socket.socket() as other:
        other.bind(("127.0.0.1", 0))
        other.listen()
        port = other.getsockname()[1]
        line = assert_refused(run_console(tmp_path / "missions.sqlite3", port))
    assert line == (
        f"nemesys console: port {port} on 127.0.0.1 is in use: another console? choose --port"
    )


@pytest.mark.slow  # a `nemesys console` subprocess
def test_the_url_is_printed_once_the_console_answers_and_a_missing_directory_is_made(
    tmp_path: Path,
) -> None:
    db = tmp_path / "new" / "logs" / "missions.sqlite3"
    proc = subprocess.Popen(
        [sys.executable, "-m", "cli.main", *console_args(db, free_port())],
        cwd=REPO,
        env=console_env(),
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    lines: queue.Queue[str] = queue.Queue()

    def read() -> None:
        assert proc.stdout is not None
        for text in proc.stdout:
            lines.put(text)

    threading.Thread(target=read, daemon=True).start()
    try:
        deadline = time.monotonic() + RUN_TIMEOUT_S
        while (match := URL_LINE.search(lines.get(timeout=deadline - time.monotonic()))) is None:
            pass
        # the moment the URL is out: one request, no retry
        answer = httpx.get(f"{match.group(1)}/api/session", timeout=5.0, trust_env=False)
        assert answer.status_code == 200, answer.text
        assert db.is_file()
    finally:
        proc.terminate()
        try:
            proc.wait(15)
        except subprocess.TimeoutExpired:  # pragma: no cover - a hung shutdown
            proc.kill()
            proc.wait()


# --- while running: a write that fails ----------------------------------------------------


class TransmitSpy:
    def __init__(self) -> None:
        self.frames: list[str] = []


def spy_transmit(client: TestClient, monkeypatch: pytest.MonkeyPatch) -> TransmitSpy:
    """Every frame handed to the console's link."""
    link = console_of(client).link
    assert link is not None
    spy = TransmitSpy()
    real = link.transmit

    async def transmit(frame: Any) -> str | None:
        spy.frames.append(frame.hex)
        return await real(frame)

    monkeypatch.setattr(link, "transmit", transmit)
    return spy


def post_circle(client: TestClient) -> httpx.Response:
    body = {"pattern": "circle", "params": CIRCLE}
    response: httpx.Response = client.post("/api/commands", json=body, headers=AUTH)
    return response


@pytest.mark.parametrize(
    ("verb", "message"),
    [
        ("INSERT", DISK_FULL),  # the write itself
        ("COMMIT", DISK_FULL),  # the commit, after the delivery was begun in memory
        ("INSERT", "attempt to write a readonly database"),
    ],
)
def test_a_send_the_log_cannot_record_is_503_and_nothing_leaves(
    make_light_client: MakeLightClient, log_backend: LogBackend, verb: str, message: str
) -> None:
    clock, link = ManualClock(), AgentLink()
    client = make_light_client(link, clock=clock, **log_backend.settings())
    console = console_of(client)
    assert console.log is not None
    with failing_writes(console.log, verb, message=message):
        r = post_circle(client)
        # a delivery begun by mistake sends its first copy at once (no timer before it):
        # the app's event loop runs whatever is ready, then nothing can be on its way
        client.portal.call(clock.settle)  # type: ignore[union-attr]
    assert r.status_code == 503, r.text
    assert r.json()["detail"] == f"the mission log cannot be written: {message}{NOTHING_SENT}"
    assert link.frames == [] and clock.pending() == []
    assert client.get("/api/commands").json() == []
    assert console.commands is not None and console.commands._live == {}
    # the disk fixed, the same send goes through
    sent = post_circle(client)
    assert sent.status_code == 202, sent.text
    client.portal.call(clock.settle)  # type: ignore[union-attr]
    assert link.frames == [sent.json()["hex"]]


#: The database's own refusal of a write on a read-only connection.
READ_ONLY = {
    "sqlite": ("PRAGMA query_only = {on}", "attempt to write a readonly database"),
    "postgresql": (
        "SET default_transaction_read_only = {on}",
        "cannot execute INSERT in a read-only transaction",
    ),
}


def test_a_real_read_only_connection_fails_the_send(
    make_client: MakeClient, monkeypatch: pytest.MonkeyPatch, log_backend: LogBackend
) -> None:
    client = make_client(**log_backend.settings())
    console = console_of(client)
    assert console.log is not None
    spy = spy_transmit(client, monkeypatch)
    log = console.log
    statement, refusal = READ_ONLY[log_backend.kind]

    def read_only(on: bool) -> None:  # the database refuses every write of the connection
        with log._lock:
            log._db.execute(statement.format(on=int(on) if log.kind == "sqlite" else on))

    read_only(True)
    try:
        r = post_circle(client)
    finally:
        read_only(False)
    assert r.status_code == 503, r.text
    detail = r.json()["detail"]
    assert detail == f"the mission log cannot be written: {refusal}{NOTHING_SENT}"
    assert spy.frames == [] and command_rows(log_backend) == 0


def test_surface_and_retry_the_log_cannot_record_are_503(
    make_client: MakeClient, monkeypatch: pytest.MonkeyPatch, log_backend: LogBackend
) -> None:
    client = make_client(**log_backend.settings())
    console = console_of(client)
    log, dives = console.log, console.dives
    assert log is not None and dives is not None
    old = log.insert_command(dives.ensure(), command_fields())
    log.update_command(old["id"], state="interrupted", reason="an earlier run stopped")
    spy = spy_transmit(client, monkeypatch)
    with failing_writes(log, "INSERT", "UPDATE"):
        surface = client.post("/api/surface", headers=AUTH)
        retry = client.post(f"/api/commands/{old['id']}/retry", headers=AUTH)
    for r in (surface, retry):
        assert r.status_code == 503, r.text
        assert r.json()["detail"] == f"the mission log cannot be written: {DISK_FULL}{NOTHING_SENT}"
        assert r.headers["Retry-After"]
    assert spy.frames == []
    assert [c["id"] for c in log.commands()] == [old["id"]]
    assert log.command(old["id"])["state"] == "interrupted"  # type: ignore[index]


def test_a_write_failing_after_a_frame_left_stops_the_delivery_logged(
    make_client: MakeClient,
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
    log_backend: LogBackend,
) -> None:
    client = make_client(**log_backend.settings())
    console = console_of(client)
    cm = console.commands
    assert console.log is not None and cm is not None
    spy = spy_transmit(client, monkeypatch)
    ended: list[BaseException | None] = []
    deliver = cm._deliver

    async def watched(d: Any) -> None:
        try:
            await deliver(d)
        except BaseException as err:
            ended.append(err)
            raise
        ended.append(None)

    monkeypatch.setattr(cm, "_deliver", watched)
    caplog.set_level(logging.ERROR, logger="backend.commands.manager")
    with failing_writes(console.log, "UPDATE"):
        r = post_circle(client)
        assert r.status_code == 202, r.text  # logged (the insert), then transmitted
        wait_until(lambda: ended, what="the end of the delivery")
    assert ended == [None]  # it ended, it did not die
    assert len(spy.frames) == 1 and spy.frames[0] == r.json()["hex"]
    assert cm._live == {}
    errors = [
        rec.getMessage()
        for rec in caplog.records
        if rec.name == "backend.commands.manager" and rec.levelno >= logging.ERROR
    ]
    assert len(errors) == 1, errors
    assert f"command {r.json()['id']}: copy 1 (frame {r.json()['hex']}) left at " in errors[0]
    assert f"the mission log cannot be written: {DISK_FULL}: delivery stopped" in errors[0]


# --- the command manager: what a failed commit leaves ----------------------------------------


def run_rig(log_backend: LogBackend, scenario: Callable[[Rig], Awaitable[None]]) -> None:
    rig = Rig(log_backend.tmp, Capability.NONE, where=log_backend.where)

    async def main() -> None:
        try:
            await scenario(rig)
        finally:
            await rig.cm.close()
            rig.log.close()

    asyncio.run(main())


def test_a_failed_commit_sends_nothing_and_stops_what_it_superseded(
    log_backend: LogBackend,
) -> None:
    async def scenario(rig: Rig) -> None:
        cm: CommandManager = rig.cm
        old = await cm.submit(CIRCLE_FRAME, copies=20)
        await rig.until(lambda: rig.link.count(CIRCLE_FRAME) >= 2)
        with failing_writes(rig.log, "COMMIT"), pytest.raises(LogWriteError) as caught:
            await cm.submit(HOVER_FRAME, copies=2)
        assert str(caught.value) == f"the mission log cannot be written: {DISK_FULL}{NOTHING_SENT}"
        circles = rig.link.count(CIRCLE_FRAME)
        await rig.clock.advance(10 * COPY_INTERVAL_S)
        assert rig.clock.pending() == []  # no copy of either is due any more
        assert rig.link.count(HOVER_FRAME) == 0  # the new command: nothing left
        assert rig.link.count(CIRCLE_FRAME) == circles  # the old one: stopped
        assert cm._live == {}
        done = rig.record(old["id"])
        assert done["state"] == "interrupted" and "could not record" in done["reason"]
        assert [c["id"] for c in rig.log.commands()] == [old["id"]]

    run_rig(log_backend, scenario)


# --- track points -----------------------------------------------------------------------------


def on_disk(log_backend: LogBackend) -> int:
    """Track points another connection sees: what a crash would leave."""
    count: int = log_backend.scalar("SELECT COUNT(*) FROM track")
    return count


@pytest.mark.slow  # the log's real flush period, ~1 s
def test_a_track_point_is_on_disk_within_a_second(log_backend: LogBackend) -> None:
    log = log_backend.open()
    try:
        dive = log.new_dive("sim")
        for count in (1, 3):  # one point, then a few
            before = on_disk(log_backend)
            added_s = time.monotonic()
            for i in range(count):
                log.add_track(dive, float(i), 0.0, 0.0, 2.0, 0.0)
            while on_disk(log_backend) < before + count:
                assert time.monotonic() - added_s <= 1.0, "a track point is not on disk after 1 s"
                time.sleep(0.01)
        assert TRACK_FLUSH_S <= 0.5
    finally:
        log.close()


@pytest.mark.slow  # the log's real flush period, ~1 s
def test_track_points_the_log_cannot_take_are_kept_and_written_later(
    log_backend: LogBackend, caplog: pytest.LogCaptureFixture
) -> None:
    log = log_backend.open()
    caplog.set_level(logging.ERROR, logger="backend.mission_log.store")
    try:
        dive = log.new_dive("sim")
        with failing_writes(log, "INSERT"):
            for i in range(12):  # past a batch: no exception reaches the telemetry
                log.add_track(dive, float(i), 0.0, 0.0, 2.0, 0.0)
            # the flush that failed says so: until then nothing was on its way to the disk
            wait_until(
                lambda: any("track points are kept in memory only" in m for m in caplog.messages),
                timeout_s=5.0,
                what="the failed flush",
            )
            assert on_disk(log_backend) == 0
        log.add_track(dive, 12.0, 0.0, 0.0, 2.0, 0.0)
        wait_until(lambda: on_disk(log_backend) == 13, timeout_s=1.0, interval_s=0.01)
    finally:
        log.close()
