"""Recovery of what a stopped console left on its way: ``MissionLog.recover_interrupted`` on
every state, and end to end a SIGKILLed ``nemesys console`` on a one-way TCP link whose
transmitted command is interrupted at the next start and retried to ``sent``, its frames
decoded on the loopback listener: both on SQLite and on PostgreSQL (``log_backend``). Older
logs: test_migrations.py."""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from backend.commands.lifecycle import ON_ITS_WAY, State
from bench._gateway import FrameGateway
from bench._server import ConsoleProcess, start_console
from tests.backend.conftest import CIRCLE, TOKEN, clear_nemesys_env, command_fields, wait_until
from tests.backend.log_backend import LogBackend

#: `nemesys console` subprocesses, killed and restarted: make test, not make test-fast.
pytestmark = pytest.mark.slow

AUTH = {"Authorization": f"Bearer {TOKEN}"}
#: The line ``nemesys console`` prints when it recovered records (before its URL).
RECOVERED_LINE = re.compile(
    r"^(\d+) commands? an earlier run left queued or transmitted (?:is|are) now interrupted",
    re.M,
)
URL_LINE = re.compile(r"^\s*http://\S+/\?token=", re.M)

# --- (a) the log's recovery --------------------------------------------------------------


def test_recovery_interrupts_exactly_what_was_on_its_way(log_backend: LogBackend) -> None:
    log = log_backend.open()
    try:
        dive = log.new_dive("tcp://127.0.0.1:9")
        ids: dict[State, int] = {}
        for i, state in enumerate(State):
            rec = log.insert_command(
                dive, {**command_fields("circle", **{**CIRCLE, "radius": 3.0 + i}), "copies": 3}
            )
            ids[state] = rec["id"]
            if state != State.QUEUED:
                log.update_command(rec["id"], state=state, reason=f"was {state}", attempts=1)
        before = {s: log.command(cid) for s, cid in ids.items()}
        last = max(r["updated_at"] for r in before.values() if r is not None)

        assert log.recover_interrupted() == len(ON_ITS_WAY) == 2

        for state, cid in ids.items():
            got, old = log.command(cid), before[state]
            assert got is not None and old is not None
            if state in ON_ITS_WAY:
                assert got["state"] == "interrupted", state
                assert got["reason"] == (
                    f"the console stopped while this command was {state} (the log was last "
                    f"written at {last}); whether the vehicle received it is not known"
                )
                assert got["updated_at"] >= last
                assert all(
                    got[k] == old[k] for k in old if k not in ("state", "reason", "updated_at")
                )
            else:
                assert got == old, state  # terminal: untouched, to the field
        assert log.recover_interrupted() == 0  # idempotent
        assert [r["state"] for r in log.commands(state="interrupted")] == ["interrupted"] * 3
    finally:
        log.close()


def test_recovery_of_an_empty_log_is_nothing(log_backend: LogBackend) -> None:
    log = log_backend.open()
    try:
        assert log.recover_interrupted() == 0
    finally:
        log.close()


def test_recovery_on_a_shared_log_is_the_consoles_own(log_backend: LogBackend) -> None:
    """A console starting on a log others share interrupts only what it left on its way (and
    records naming no console): another console's commands on their way are its own."""
    log = log_backend.open()
    try:
        dive = log.new_dive("sim")
        ids = {}
        for console in ("ship", "shore", None):
            if console is not None:
                log.name_console(console)
            else:
                log.console = None  # a record from before consoles were named
            rec = log.insert_command(dive, command_fields())
            log.update_command(rec["id"], state="transmitted", attempts=1)
            ids[console] = rec["id"]
        assert log.recover_interrupted("shore") == 2
        states = {c: (log.command(cid) or {})["state"] for c, cid in ids.items()}
        assert states == {"ship": "transmitted", "shore": "interrupted", None: "interrupted"}
        assert log.recover_interrupted() == 1  # every record: a log of one console
    finally:
        log.close()


# --- (b) end to end: SIGKILL, restart, retry ---------------------------------------------


@pytest.fixture
def listener() -> Iterator[FrameGateway]:
    server = FrameGateway()
    yield server
    server.close()


@pytest.fixture
def start_server(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    listener: FrameGateway,
    log_backend: LogBackend,
) -> Iterator[Callable[[], ConsoleProcess]]:
    """``nemesys console`` on a one-way TCP link to ``listener``, copies 0.5 s apart, its log
    on ``log_backend``."""
    clear_nemesys_env(monkeypatch)
    servers: list[ConsoleProcess] = []

    def start() -> ConsoleProcess:
        server = start_console(
            tmp_path / f"console-{len(servers)}.log",
            TOKEN,
            *log_backend.console_args(),
            *("--target", f"tcp://127.0.0.1:{listener.port}"),
            env={
                "NEMESYS_COPY_INTERVAL_S": "0.5",
                "NO_PROXY": "127.0.0.1,localhost",
                **log_backend.console_env(),
            },
        )
        servers.append(server)
        assert server.host == "127.0.0.1"
        return server

    yield start
    for server in servers:
        server.stop(timeout_s=10)


def get(c: httpx.Client, command_id: int) -> dict[str, Any]:
    r = c.get(f"/api/commands/{command_id}")
    assert r.status_code == 200, r.text
    rec: dict[str, Any] = r.json()
    return rec


def test_a_killed_console_interrupts_and_retries_on_restart(
    start_server: Callable[[], ConsoleProcess], listener: FrameGateway, log_backend: LogBackend
) -> None:
    first = start_server()
    with first.client() as c:
        r = c.post(
            "/api/commands",
            json={"pattern": "circle", "params": CIRCLE, "copies": 20},
            headers=AUTH,
        )
        assert r.status_code == 202, r.text
        cmd = r.json()
        assert cmd["state"] == "queued" and cmd["copies"] == 20
        on_way = wait_until(
            lambda: (
                (rec := get(c, cmd["id"]))["state"] == "transmitted"
                and rec["copies_sent"] >= 1
                and rec
            ),
            timeout_s=10.0,
            what="the command transmitted, one copy out",
        )
        assert on_way["copies_sent"] < 20  # 20 copies 0.5 s apart: still going out
    first.kill()
    wait_until(lambda: listener.closed == 1, what="the killed console's connection closed")
    before_kill = listener.frames(0)
    assert before_kill and set(before_kill) == {cmd["hex"]}
    # as the kill left it, read over a connection of its own
    assert log_backend.query("SELECT state FROM commands WHERE id = ?", (cmd["id"],)) == [
        ("transmitted",)
    ]

    second = start_server()
    printed = second.log_path.read_text()
    recovered, url = RECOVERED_LINE.search(printed), URL_LINE.search(printed)
    assert recovered is not None and url is not None, printed
    assert recovered.group(1) == "1"
    assert recovered.start() < url.start()  # the recovery is done before the URL is shown
    with second.client() as c:
        rows = c.get("/api/commands").json()
        assert [r["id"] for r in rows] == [cmd["id"]]
        assert not [r for r in rows if r["state"] in ("queued", "transmitted")]
        rec = get(c, cmd["id"])
        assert rec["state"] == "interrupted"
        assert rec["reason"].startswith("the console stopped while this command was transmitted")
        assert rec["copies_sent"] >= 1 and rec["attempts"] == rec["copies_sent"]

        r = c.post(f"/api/commands/{cmd['id']}/retry", json={"copies": 2}, headers=AUTH)
        assert r.status_code == 202, r.text
        retried = r.json()
        assert retried["state"] == "queued" and retried["retry_of"] == cmd["id"]
        done = wait_until(
            lambda: (
                (got := get(c, retried["id"]))["state"] not in ("queued", "transmitted") and got
            ),
            timeout_s=10.0,
            what="the retry ended",
        )
        assert get(c, cmd["id"]) == rec  # the interrupted record stays as it was
    assert done["state"] == "sent", done
    assert done["attempts"] == 2 and done["copies_sent"] == 2
    assert done["reason"] is None and done["hex"] == cmd["hex"]
    # the listener got the retry's two copies on the restarted console's connection (the
    # record counts a copy once the console wrote it; the listener's thread reads it after)
    assert listener.connections == 2 and not listener.rejected
    wait_until(lambda: len(listener.frames(1)) >= 2, what="the retry's two copies received")
    assert listener.frames(1) == [cmd["hex"]] * 2
