"""A console whose PostgreSQL database goes away (issue 24): its pages are told at once (the
link's health: ``mission_log`` unreachable, the first problem "mission log unreachable — sends
refused"), every send answers 503 naming the cause and nothing is transmitted; when the
server is back the listener connects again, the header clears, what another console wrote
meanwhile reaches the pages, and sends go out again.

The server is this test's own (stopped and started again on its port), not the worker's
shared one."""

from __future__ import annotations

import functools
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import psycopg
import pytest
from fastapi.testclient import TestClient

from tests.agent_link import AgentLink
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    MakeClient,
    MakeLightClient,
    wait_state,
    wait_until,
)
from tests.backend.control.consoles import Page
from tests.pg_server import PgServer

pytestmark = pytest.mark.slow

UNREACHABLE = "mission log unreachable — sends refused"


@pytest.fixture
def own_server() -> Iterator[PgServer]:
    server = PgServer()
    yield server
    server.stop()


def health(client: TestClient) -> dict[str, Any]:
    r = client.get("/api/vehicle")
    assert r.status_code == 200, r.text
    link: dict[str, Any] = r.json()["link"]
    return link


def unreached(client: TestClient) -> dict[str, Any] | None:
    """The link's health once it says the mission log is unreachable."""
    link = health(client)
    return None if link["mission_log"]["reachable"] else link


def test_a_console_that_loses_its_database_refuses_sends_until_it_is_back(
    own_server: PgServer,
    tmp_path: Path,
    make_client: MakeClient,
    make_light_client: MakeLightClient,
) -> None:
    url = own_server.url(own_server.new_database())
    ship = make_client(
        db_path=tmp_path / "ship.sqlite3", console_name="ship", operator="alice", database_url=url
    )
    link = AgentLink()
    shore = make_light_client(
        link, db_path=tmp_path / "shore.sqlite3", console_name="shore", database_url=url
    )
    before = ship.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
    assert before.status_code == 202, before.text
    wait_state(ship, before.json()["id"], ("acknowledged",))
    assert health(ship)["mission_log"] == {"reachable": True, "problem": None, "since": None}
    frames = health(ship)["frames"]["dive"]["frames"]
    page = Page(ship)
    try:
        own_server.halt()
        _t, told = page.wait("link", lambda m: not m["link"]["mission_log"]["reachable"])
        assert told["link"]["problems"][0].startswith(UNREACHABLE)
        assert told["link"]["level"] == "red"
        for console in (ship, shore):
            reach = wait_until(functools.partial(unreached, console))
            assert reach["problems"][0].startswith(UNREACHABLE), reach["problems"]
            r = console.post(
                "/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH
            )
            assert r.status_code == 503, r.text
            assert (
                "unreachable" in r.json()["detail"]
                and "nothing was transmitted" in r.json()["detail"]
            )
            assert r.headers["Retry-After"]
        surface = ship.post("/api/surface", headers=AUTH)  # its record cannot be written
        assert surface.status_code == 503 and "nothing was transmitted" in surface.json()["detail"]
        assert health(ship)["frames"]["dive"]["frames"] == frames
        assert link.frames == []
        # what reads the log says it cannot, never a 500
        for path in ("/api/commands", "/api/dives", f"/api/commands/{before.json()['id']}"):
            r = ship.get(path)
            assert r.status_code == 503, (path, r.status_code, r.text)
            assert r.json()["detail"].startswith("the mission log cannot be read right now (")
            assert r.headers["Retry-After"]

        # meanwhile another console writes: this one reads it when the database is back
        own_server.resume()
        with psycopg.connect(url, autocommit=True) as other:
            other.execute("SELECT set_config('nemesys.console', 'elsewhere', false)")
            other.execute(
                "INSERT INTO events (dive, at, kind, detail) "
                "VALUES (1, '2026-01-01T00:00:00.000+00:00', 'datum', 'written while away')"
            )
        page.wait(
            "link", lambda m: m["link"]["mission_log"]["reachable"], timeout_s=20
        )  # the listener's backoff
        page.wait("event", lambda m: m["event"]["detail"] == "written while away")
    finally:
        page.close()
    assert UNREACHABLE not in " ".join(health(ship)["problems"])
    after = ship.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
    assert after.status_code == 202, after.text
    wait_state(ship, after.json()["id"], ("acknowledged",))
