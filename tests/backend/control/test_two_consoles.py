"""Two consoles on one PostgreSQL mission log (issue 24): a ship's, in training mode, holding
the transmitter to the simulated vehicle, and a shore's (the light app: its own in-memory
vehicle stands for the ship's until the relay, build item 4, carries its frames).

The ship starts first and takes control; the shore asks, the ship grants; the shore's
commands and their states reach the ship's pages within 1 s; the ship, no longer in control,
gets 409 naming the shore; its Surface is accepted all the same and supersedes the shore's
command still going out; the shore's heartbeat stops and its control is released after the
timeout, on the database's clock. Waits are on conditions, never fixed sleeps."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from tests.agent_link import AgentLink
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    MakeClient,
    MakeLightClient,
    advance,
    console_of,
    wait_state,
    wait_until,
)
from tests.backend.control.consoles import Page, act, order, owner
from tests.manual_clock import ManualClock

#: Control is released this long after the owner's last heartbeat (s): short for the test,
#: long enough for a loaded machine's event loop to beat (every third of it) in time.
TIMEOUT_S = 3.0
#: The issue's bound on what another console's pages are told.
SYNC_S = 1.0

pytestmark = pytest.mark.slow


def consoles(
    shared_url: str,
    tmp_path: Path,
    make_client: MakeClient,
    make_light_client: MakeLightClient,
    link: AgentLink,
    clock: ManualClock | None = None,
) -> tuple[TestClient, TestClient]:
    common: dict[str, Any] = {"database_url": shared_url, "control_timeout_s": TIMEOUT_S}
    ship = make_client(
        db_path=tmp_path / "ship.sqlite3", console_name="ship", operator="alice", **common
    )
    extra: dict[str, Any] = {} if clock is None else {"clock": clock}
    shore = make_light_client(
        link,
        db_path=tmp_path / "shore.sqlite3",
        console_name="shore",
        operator="bob",
        **extra,
        **common,
    )
    return ship, shore


def test_the_shore_asks_the_ship_grants_and_each_sees_the_other_live(
    shared_url: str,
    tmp_path: Path,
    make_client: MakeClient,
    make_light_client: MakeLightClient,
) -> None:
    link = AgentLink()
    ship, shore = consoles(shared_url, tmp_path, make_client, make_light_client, link)
    assert owner(ship) == ("ship", "alice")  # the first console took control at start
    assert owner(shore) == ("ship", "alice")
    session = shore.get("/api/session").json()["console"]
    assert session == {"name": "shore", "shared_log": True, "control_timeout_s": TIMEOUT_S}
    ship_page, shore_page = Page(ship), Page(shore)
    try:
        # not in control: 409 naming who is, nothing written or sent
        r = shore.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
        assert r.status_code == 409, r.text
        assert "console 'ship' (operator 'alice') is in control" in r.json()["detail"]
        assert link.frames == []

        # the request waits for the owner, whose pages show it
        asked = act(shore, "request")
        assert asked.status_code == 200, asked.text
        assert asked.json()["outcome"] == "pending"
        ship_page.wait(
            "control", lambda m: (m["control"]["request"] or {}).get("console") == "shore"
        )
        granted = act(ship, "grant")
        assert granted.json()["outcome"] == "granted", granted.text
        assert granted.json()["control"]["console"] == "shore"
        _t, told = shore_page.wait("control", lambda m: m["control"]["console"] == "shore")
        assert told["control"]["operator"] == "bob" and told["control"]["epoch"] == 2
        shore_page.wait("event", lambda m: "granted" in m["event"]["detail"])

        # the shore's command: its record and states on the ship's pages within 1 s
        r = shore.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
        assert r.status_code == 202, r.text
        sent = r.json()
        assert sent["console"] == "shore"
        done = wait_state(shore, sent["id"], ("acknowledged",))
        shore_page.wait(
            "command",
            lambda m: m["command"]["id"] == sent["id"] and m["command"]["state"] == "acknowledged",
        )
        ship_page.wait(
            "command",
            lambda m: m["command"]["id"] == sent["id"] and m["command"]["state"] == "acknowledged",
        )
        assert ship.get(f"/api/commands/{sent['id']}").json() == done  # one log
        ship_states = ship_page.command_states(sent["id"])
        for t_shore, state in shore_page.command_states(sent["id"]):
            caught_up = [
                t for t, s in ship_states if order(s) >= order(state) and t >= t_shore - SYNC_S
            ]
            assert caught_up and min(caught_up) - t_shore < SYNC_S, (state, ship_states)

        # the ship is no longer in control
        r = ship.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
        assert r.status_code == 409, r.text
        assert "console 'shore' (operator 'bob')" in r.json()["detail"]
    finally:
        ship_page.close()
        shore_page.close()


def test_surface_from_the_ship_is_accepted_and_supersedes_the_shore(
    shared_url: str,
    tmp_path: Path,
    make_client: MakeClient,
    make_light_client: MakeLightClient,
) -> None:
    link, clock = AgentLink(), ManualClock()
    ship, shore = consoles(shared_url, tmp_path, make_client, make_light_client, link, clock)
    assert act(shore, "request").json()["outcome"] == "pending"
    assert act(ship, "grant").json()["outcome"] == "granted"
    link.answer = False  # the vehicle out of range: the copies keep going out
    r = shore.post(
        "/api/commands",
        json={"pattern": "circle", "params": CIRCLE, "copies": 5},
        headers=AUTH,
    )
    assert r.status_code == 202, r.text
    circle = wait_state(shore, r.json()["id"], ("transmitted",))
    assert len(link.frames) == 1  # the next copy waits for the shore's clock

    surface = ship.post("/api/surface", headers=AUTH)  # not in control: accepted all the same
    assert surface.status_code == 202, surface.text
    assert surface.json()["console"] == "ship" and surface.json()["origin"] == "surface"
    ended = wait_state(shore, circle["id"], ("superseded",))
    assert ended["superseded_by"] == surface.json()["id"]
    assert "console 'ship'" in ended["reason"]
    advance(shore, clock, 10.0)  # when its copies were due
    assert len(link.frames) == 1  # none left after the Surface
    assert owner(ship) == ("shore", "bob")  # a Surface takes no control


def test_the_shores_control_is_released_when_its_heartbeat_stops(
    shared_url: str,
    tmp_path: Path,
    make_client: MakeClient,
    make_light_client: MakeLightClient,
) -> None:
    ship, shore = consoles(shared_url, tmp_path, make_client, make_light_client, AgentLink())
    assert act(shore, "request").json()["outcome"] == "pending"
    assert act(ship, "grant").json()["outcome"] == "granted"
    ship_page = Page(ship)
    try:
        beat = console_of(shore).control
        assert beat is not None and beat.heartbeat is not None
        shore.portal.call(_cancel, beat.heartbeat)  # type: ignore[union-attr]
        _t, told = ship_page.wait(
            "control", lambda m: m["control"]["console"] is None, timeout_s=TIMEOUT_S + 10
        )
        assert told["control"]["epoch"] == 3
        ship_page.wait("event", lambda m: m["event"]["data"]["outcome"] == "timed_out")
    finally:
        ship_page.close()
    assert owner(shore) == (None, None)
    r = shore.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
    assert r.status_code == 409 and "nobody is in control" in r.json()["detail"], r.text
    assert act(ship, "request").json()["outcome"] == "granted"
    wait_until(lambda: owner(shore) == ("ship", "alice"))


async def _cancel(task: object) -> None:
    import asyncio

    assert isinstance(task, asyncio.Task)
    task.cancel()
