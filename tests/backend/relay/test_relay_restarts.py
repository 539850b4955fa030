"""A relayed command is never sent twice when either console restarts (issue 24, item 4): real
``nemesys console`` processes on one real PostgreSQL, the ship on a one-way TCP link to a
loopback stand-in for the ME modem's gateway, where every frame is decoded and counted.

* The ship killed (SIGKILL) between its claim of the outbox row and its commit: it has
  claimed the row and waits to insert the command record (the test holds the ``commands``
  table locked against writes, and sees the ship's statement waiting on it in
  ``pg_stat_activity``). Its transaction dies with it: the row is ``waiting``, no record, no
  frame. Restarted, the ship takes the row and sends it: one command, its copies, once.
* The ship killed after its commit, its copies going out: the row stays ``taken``, the record
  becomes ``interrupted`` at the restart, and the restarted ship sends nothing more of it
  (a later relayed command is taken, so it did look).
* The shore killed while its row waits (no ship yet) and started again: the ship, started
  later, sends the row once; the restarted shore wrote nothing again.
"""

from __future__ import annotations

import concurrent.futures
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import psycopg
import pytest
from psycopg.rows import dict_row

from bench._gateway import FrameGateway
from bench._server import ConsoleProcess, start_console
from tests.backend.conftest import CIRCLE, TOKEN, clear_nemesys_env, wait_until

pytestmark = pytest.mark.slow  # console processes, killed and started again

AUTH = {"Authorization": f"Bearer {TOKEN}"}
#: Long enough that neither the shore's wait nor the row's age ends while a console restarts
#: on a loaded machine; what is measured here is what is sent, not how soon.
SLOW_ENV = {
    "NEMESYS_RELAY_WAIT_S": "60",
    "NEMESYS_RELAY_MAX_AGE_S": "600",
    "NEMESYS_CONTROL_TIMEOUT_S": "120",
    "NO_PROXY": "127.0.0.1,localhost",
}

Start = Callable[[str], ConsoleProcess]


@pytest.fixture
def gateway() -> Iterator[FrameGateway]:
    server = FrameGateway()
    yield server
    server.close()


@pytest.fixture
def start(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, gateway: FrameGateway, shared_url: str
) -> Iterator[Start]:
    """``start("ship")``: the console holding the transmitter (copies 0.5 s apart);
    ``start("shore")``: the relay. Each on the shared database, its own ``--db`` kept across
    restarts (its name and token beside it)."""
    clear_nemesys_env(monkeypatch)
    started: list[ConsoleProcess] = []

    def run(name: str) -> ConsoleProcess:
        target = gateway.target if name == "ship" else "relay"
        env = {
            **SLOW_ENV,
            "NEMESYS_DATABASE_URL": shared_url,
            "NEMESYS_CONSOLE_NAME": name,
            "NEMESYS_OPERATOR": "alice" if name == "ship" else "bob",
            "NEMESYS_TARGET": target,
            "NEMESYS_COPY_INTERVAL_S": "0.5",
        }
        console = start_console(
            tmp_path / f"{name}-{len(started)}.log",
            TOKEN,
            *("--db", str(tmp_path / f"{name}.sqlite3")),
            env=env,
        )
        started.append(console)
        return console

    yield run
    for console in started:
        console.stop(timeout_s=10)


def rows(url: str, sql: str, params: tuple[Any, ...] = ()) -> list[dict[str, Any]]:
    with psycopg.connect(url, autocommit=True) as pg:
        return list(pg.cursor(row_factory=dict_row).execute(sql, params).fetchall())


def post(console: ConsoleProcess, path: str, body: dict[str, Any] | None = None) -> httpx.Response:
    with console.client(timeout_s=120) as http:
        return http.post(path, json=body, headers=AUTH)


def control_to_the_shore(ship: ConsoleProcess, shore: ConsoleProcess) -> None:
    assert post(shore, "/api/control", {"action": "request"}).json()["outcome"] == "pending"
    assert post(ship, "/api/control", {"action": "grant"}).json()["outcome"] == "granted"


def relay_in_the_background(
    pool: concurrent.futures.ThreadPoolExecutor, shore: ConsoleProcess, copies: int
) -> concurrent.futures.Future[httpx.Response]:
    body = {"pattern": "circle", "params": CIRCLE, "copies": copies}
    return pool.submit(post, shore, "/api/commands", body)


def test_a_ship_killed_between_claim_and_commit_sends_the_row_once_after_its_restart(
    start: Start, gateway: FrameGateway, shared_url: str
) -> None:
    ship, shore = start("ship"), start("shore")
    control_to_the_shore(ship, shore)
    with (
        psycopg.connect(shared_url) as blocker,
        concurrent.futures.ThreadPoolExecutor(1) as pool,
    ):
        # no command can be written (SHARE: the outbox's rows, which name commands, can) until
        # the commit below
        blocker.execute("LOCK TABLE commands IN SHARE MODE")
        answer = relay_in_the_background(pool, shore, copies=2)
        waiting = wait_until(
            lambda: rows(
                shared_url,
                "SELECT pid FROM pg_stat_activity WHERE wait_event_type = 'Lock' "
                "AND query LIKE 'INSERT INTO commands%%'",
            ),
            what="the ship's record insert waiting, its outbox row claimed",
        )
        (row,) = rows(shared_url, "SELECT * FROM outbox")
        assert row["state"] == "waiting"
        ship.kill()
        gone = waiting[0]["pid"]
        wait_until(
            lambda: not rows(shared_url, "SELECT 1 FROM pg_stat_activity WHERE pid = %s", (gone,)),
            what="the killed ship's session ended by the server",
        )
        blocker.commit()
        # its transaction died with it: the row waits, nothing recorded, nothing sent
        (row,) = rows(shared_url, "SELECT * FROM outbox")
        assert row["state"] == "waiting" and row["command_id"] is None
        assert rows(shared_url, "SELECT id FROM commands") == []
        assert gateway.count() == 0

        start("ship")  # the restarted ship takes it at its first sweep
        r = answer.result(timeout=120)
    assert r.status_code == 202, r.text
    sent = r.json()
    assert sent["origin"] == "relay:shore" and sent["console"] == "ship"
    wait_until(lambda: gateway.count() >= 2, what="the two copies at the gateway")
    (row,) = rows(shared_url, "SELECT * FROM outbox")
    assert row["state"] == "taken" and row["command_id"] == sent["id"]
    assert [r["id"] for r in rows(shared_url, "SELECT id FROM commands")] == [sent["id"]]
    with shore.client() as http:
        done = wait_until(
            lambda: (
                (rec := http.get(f"/api/commands/{sent['id']}").json())["state"] == "sent" and rec
            )
        )
    assert done["copies_sent"] == 2
    assert [f.hex for f in gateway.trace()] == [sent["hex"]] * 2 and not gateway.rejected


def test_a_ship_killed_after_its_commit_leaves_the_row_taken_and_sends_nothing_more(
    start: Start, gateway: FrameGateway, shared_url: str
) -> None:
    ship, shore = start("ship"), start("shore")
    control_to_the_shore(ship, shore)
    r = post(shore, "/api/commands", {"pattern": "circle", "params": CIRCLE, "copies": 20})
    assert r.status_code == 202, r.text
    first = r.json()
    wait_until(lambda: gateway.count(first["hex"]) >= 1, what="a first copy at the gateway")
    closed = gateway.closed
    ship.kill()
    wait_until(lambda: gateway.closed > closed, what="the killed ship's connection closed")
    out_before_restart = gateway.count(first["hex"])
    assert out_before_restart < 20  # 20 copies 0.5 s apart: killed on the way

    start("ship")
    (row,) = rows(shared_url, "SELECT * FROM outbox")
    assert row["state"] == "taken" and row["command_id"] == first["id"]
    (record,) = rows(shared_url, "SELECT state FROM commands WHERE id = %s", (first["id"],))
    assert record["state"] == "interrupted"
    # a later relayed command is taken and sent: the restarted ship swept the outbox
    probe = post(shore, "/api/commands", {"pattern": "circle", "params": {**CIRCLE, "radius": 8}})
    assert probe.status_code == 202, probe.text
    wait_until(lambda: gateway.count(probe.json()["hex"]) >= 1, what="the later command's copy")
    assert gateway.count(first["hex"]) == out_before_restart  # nothing more of the first
    assert [r["state"] for r in rows(shared_url, "SELECT state FROM outbox ORDER BY id")] == [
        "taken",
        "taken",
    ]


def test_a_row_left_waiting_by_a_killed_shore_is_sent_once_after_its_restart(
    start: Start, gateway: FrameGateway, shared_url: str
) -> None:
    shore = start("shore")  # alone: in control at its start, nobody to send
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        answer = relay_in_the_background(pool, shore, copies=2)
        wait_until(lambda: rows(shared_url, "SELECT id FROM outbox"), what="the row written")
        shore.kill()
        with pytest.raises(httpx.TransportError):
            answer.result(timeout=30)
    shore = start("shore")  # the same console: still in control (its name, the timeout)
    (row,) = rows(shared_url, "SELECT * FROM outbox")
    assert row["state"] == "waiting"

    start("ship")
    wait_until(lambda: gateway.count() >= 2, what="the two copies at the gateway")
    (row,) = rows(shared_url, "SELECT * FROM outbox")
    assert row["state"] == "taken" and row["console"] == "shore"
    ((command,),) = [tuple(r.values()) for r in rows(shared_url, "SELECT id FROM commands")]
    assert command == row["command_id"]
    with shore.client() as http:
        record = wait_until(
            lambda: (rec := http.get(f"/api/commands/{command}").json())["state"] == "sent" and rec
        )
    assert record["origin"] == "relay:shore" and record["copies_sent"] == 2
    assert [f.hex for f in gateway.trace()] == [record["hex"]] * 2
