"""The header's line while the console's PostgreSQL mission log is out of reach (issue 24,
frontend/link.js): "mission log unreachable — sends refused (...)" in the message row as soon
as the server stops, gone when it is back; a change of who is in control is said there too.
In Chromium, on a console whose log is this test's own PostgreSQL server (stopped and started
again on its port)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from playwright.sync_api import expect

from tests.frontend.conftest import TOKEN, Console, Watched
from tests.frontend.pagekit import open_sized
from tests.pg_server import PgServer


@pytest.fixture
def own_server() -> Iterator[PgServer]:
    server = PgServer()
    yield server
    server.stop()


@pytest.fixture
def console_env(own_server: PgServer) -> dict[str, str]:
    return {"NEMESYS_DATABASE_URL": own_server.url(own_server.new_database())}


def test_the_header_says_when_the_mission_log_is_unreachable(
    own_server: PgServer, console: Console, watched: Watched
) -> None:
    page = open_sized(watched, console)
    line = page.get_by_test_id("messages").get_by_text("mission log unreachable — sends refused")
    expect(page.get_by_test_id("link-indicator")).not_to_have_class("level-unknown")
    expect(line).to_have_count(0)
    auth = {"Authorization": f"Bearer {TOKEN}"}
    released = console.http.post("/api/control", json={"action": "release"}, headers=auth)
    assert released.status_code == 200, released.text
    messages = page.get_by_test_id("messages")
    expect(messages).to_contain_text("control of nemesys: nobody")
    own_server.halt()
    expect(line).to_have_count(1)
    expect(page.get_by_test_id("link-indicator")).to_have_class("link-indicator level-red")
    own_server.resume()
    expect(line).to_have_count(0)
    assert console.get("/api/vehicle")["link"]["mission_log"]["reachable"] is True
