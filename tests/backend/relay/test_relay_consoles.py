"""Commands from a console without the transmitter (issue 24, item 4), two real consoles in
this process on one real PostgreSQL: the ship in training, holding the simulated vehicle's
transmitter, and the shore (``target relay``), whose commands go to the shared log's outbox
and are checked again, sent and recorded by the ship.

The shore asks for control, the ship grants; a circle from the shore is transmitted by the
ship (one frame at the simulator) and acknowledged by the training vehicle; both consoles read
the same record (``origin`` ``relay:shore``, operator ``bob``, console ``ship``) and the shore's
page sees each of its states within 1 s of the ship's; a command the ship's own checks refuse
is answered to the shore with the ship's status and reason, nothing sent; the shore's page
shows its link as "relay via ship". Waits are on conditions, never fixed sleeps."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import psycopg
import pytest
from fastapi.testclient import TestClient

from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    MakeClient,
    console_of,
    wait_state,
    wait_until,
)
from tests.backend.control.consoles import Page, act, order, owner
from tests.backend.relay.rows import shore_row_decided

pytestmark = pytest.mark.slow

#: The issue's bound on what another console's pages are told.
SYNC_S = 1.0


def ship_and_shore(
    shared_url: str, tmp_path: Path, make_client: MakeClient, **ship: Any
) -> tuple[TestClient, TestClient]:
    """The ship (training, in control at start) and the shore (relay), on ``shared_url``."""
    common: dict[str, Any] = {"database_url": shared_url, "control_timeout_s": 5.0}
    ship_client = make_client(
        db_path=tmp_path / "ship.sqlite3",
        console_name="ship",
        operator="alice",
        **common,
        **ship,
    )
    shore_client = make_client(
        db_path=tmp_path / "shore.sqlite3",
        console_name="shore",
        operator="bob",
        target="relay",
        **common,
    )
    return ship_client, shore_client


def outbox_rows(url: str) -> list[dict[str, Any]]:
    with psycopg.connect(url) as pg:
        cur = pg.cursor(row_factory=psycopg.rows.dict_row)
        return list(cur.execute("SELECT * FROM outbox ORDER BY id").fetchall())


def frames_at_the_vehicle(ship: TestClient) -> int:
    sim = console_of(ship).sim
    assert sim is not None
    return sim.frames_in


def grant_the_shore(ship: TestClient, shore: TestClient) -> None:
    assert act(shore, "request").json()["outcome"] == "pending"
    assert act(ship, "grant").json()["outcome"] == "granted"
    wait_until(lambda: owner(shore) == ("shore", "bob"))


def test_a_circle_from_the_shore_is_sent_by_the_ship_and_both_see_it_live(
    shared_url: str, tmp_path: Path, make_client: MakeClient
) -> None:
    ship, shore = ship_and_shore(shared_url, tmp_path, make_client)
    assert owner(shore) == ("ship", "alice")
    ship_page, shore_page = Page(ship), Page(shore)
    try:
        # its link: relay via the ship, with the ship's link (its beat, every second)
        relay = wait_until(lambda: (r := shore.get("/api/vehicle").json()["link"]["relay"]) and r)
        assert relay["via"] == "ship" and relay["fresh"] and relay["target"] == "sim"
        assert shore.get("/api/vehicle").json()["link"]["target"] == "relay"
        assert ship.get("/api/vehicle").json()["link"]["relay"] is None

        # not in control: the shore's own gate refuses, nothing written to the outbox
        r = shore.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
        assert r.status_code == 409, r.text
        assert "console 'ship' (operator 'alice') is in control" in r.json()["detail"]
        assert outbox_rows(shared_url) == []

        grant_the_shore(ship, shore)
        before = frames_at_the_vehicle(ship)
        r = shore.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
        assert r.status_code == 202, r.text
        sent = r.json()
        assert sent["console"] == "ship" and sent["origin"] == "relay:shore"
        assert sent["operator"] == "bob" and sent["target"] == "sim"
        done = wait_state(shore, sent["id"], ("acknowledged",))
        assert ship.get(f"/api/commands/{sent['id']}").json() == done  # one log
        assert frames_at_the_vehicle(ship) == before + 1
        (row,) = outbox_rows(shared_url)
        assert row["state"] == "taken" and row["command_id"] == sent["id"]
        assert row["console"] == "shore" and row["decided_by"] == "ship"

        def acked(m: dict[str, Any]) -> bool:
            c = m["command"]
            return bool(c["id"] == sent["id"] and c["state"] == "acknowledged")

        ship_page.wait("command", acked)
        shore_page.wait("command", acked)
        shore_states = shore_page.command_states(sent["id"])
        for t_ship, state in ship_page.command_states(sent["id"]):
            caught_up = [
                t for t, s in shore_states if order(s) >= order(state) and t >= t_ship - SYNC_S
            ]
            assert caught_up and min(caught_up) - t_ship < SYNC_S, (state, shore_states)
    finally:
        ship_page.close()
        shore_page.close()


def test_a_command_the_ships_checks_refuse_is_answered_to_the_shore_with_its_reason(
    shared_url: str, tmp_path: Path, make_client: MakeClient
) -> None:
    # the ship's vehicle may not go below 2 m; the shore's settings allow 100 m
    ship, shore = ship_and_shore(shared_url, tmp_path, make_client, max_depth_m=2.0)
    grant_the_shore(ship, shore)
    shore_page = Page(shore)
    try:
        before = frames_at_the_vehicle(ship)
        deep = {**CIRCLE, "depth": 3}
        checked = shore.post("/api/preview", json={"pattern": "circle", "params": deep})
        assert checked.status_code == 200 and not checked.json()["violations"]  # fine here
        r = shore.post("/api/commands", json={"pattern": "circle", "params": deep}, headers=AUTH)
        assert r.status_code in (409, 422), r.text
        detail = r.json()["detail"]
        assert detail["message"].startswith("console 'ship' (holding the transmitter) refused it")
        assert any(v["param"] == "depth" for v in detail["violations"]), detail
        (row,) = outbox_rows(shared_url)
        assert row["state"] == "refused" and row["status"] == r.status_code
        assert row["command_id"] is None and "depth" in row["reason"]
        # told on every console's pages as an event
        _t, told = shore_page.wait("event", lambda m: m["event"]["kind"] == "relay")
        assert "refused by console 'ship'" in told["event"]["detail"]
        assert frames_at_the_vehicle(ship) == before  # nothing sent
        assert shore.get("/api/commands").json() == []
    finally:
        shore_page.close()


def test_a_shore_override_covers_only_the_violations_its_operator_was_shown(
    shared_url: str, tmp_path: Path, make_client: MakeClient
) -> None:
    """The shore's operator overrides what the shore's checks found (here nothing); the ship's
    stricter limit is not covered by it: refused back with the violation, shown to the
    operator. Sent again with override, having seen it, the ship sends it (the training
    vehicle, on the ship's limits, may still reject it: that is the vehicle's answer)."""
    ship, shore = ship_and_shore(shared_url, tmp_path, make_client, max_depth_m=2.0)
    grant_the_shore(ship, shore)
    before = frames_at_the_vehicle(ship)
    body = {"pattern": "circle", "params": {**CIRCLE, "depth": 3}, "override": True}
    r = shore.post("/api/commands", json=body, headers=AUTH)
    assert r.status_code == 409, r.text
    detail = r.json()["detail"]
    assert "did not cover" in detail["message"], detail
    assert [v["param"] for v in detail["violations"]] == ["depth"]
    first = outbox_rows(shared_url)[0]
    assert first["override"] and first["accepted"] == "[]"  # the shore's checks found none
    assert frames_at_the_vehicle(ship) == before and shore.get("/api/commands").json() == []

    again = shore.post("/api/commands", json=body, headers=AUTH)  # the operator saw it now
    assert again.status_code == 202, again.text
    record = wait_state(shore, again.json()["id"])  # the ship sent it
    assert frames_at_the_vehicle(ship) > before
    assert record["origin"] == "relay:shore" and record["first_sent_at"]
    assert record["overrides"]["by"] == "bob"
    assert [v["param"] for v in record["overrides"]["violations"]] == ["depth"]
    second = outbox_rows(shared_url)[1]
    assert second["state"] == "taken" and "depth" in second["accepted"]


def test_the_shores_belief_and_last_sent_are_its_relayed_command(
    shared_url: str, tmp_path: Path, make_client: MakeClient
) -> None:
    """The shore transmits nothing itself, yet what it sent through the ship is its last sent
    command, and once the relayed status says the vehicle runs it, the shore believes it runs
    that record (not "a command of another station")."""
    ship, shore = ship_and_shore(shared_url, tmp_path, make_client)
    grant_the_shore(ship, shore)
    r = shore.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
    assert r.status_code == 202, r.text
    sent = wait_state(shore, r.json()["id"], ("acknowledged",))

    def believed() -> dict[str, Any] | None:
        view = shore.get("/api/vehicle").json()
        command = (view.get("belief") or {}).get("command") or {}
        return view if command.get("id") == sent["id"] else None

    view = wait_until(believed, timeout_s=15.0)
    assert view["last_sent"]["id"] == sent["id"]
    assert view["belief"]["command"]["p"] == 1.0
    assert f"command {sent['id']}" in view["belief"]["command"]["reason"]


def test_surface_from_the_shore_is_sent_by_the_ship_whoever_is_in_control(
    shared_url: str, tmp_path: Path, make_client: MakeClient
) -> None:
    ship, shore = ship_and_shore(shared_url, tmp_path, make_client)
    assert owner(ship) == ("ship", "alice")  # the shore is not in control
    r = shore.post("/api/surface", headers=AUTH)
    assert r.status_code == 202, r.text
    surface = r.json()
    assert surface["kind"] == "surface" and surface["origin"] == "relay:shore"
    assert wait_state(ship, surface["id"], ("acknowledged",))["operator"] == "bob"


def test_without_a_console_holding_the_transmitter_the_shore_says_so_and_sends_nothing(
    shared_url: str, tmp_path: Path, make_client: MakeClient
) -> None:
    shore = make_client(
        db_path=tmp_path / "shore.sqlite3",
        console_name="shore",
        target="relay",
        database_url=shared_url,
        relay_wait_s=0.5,
    )
    link = shore.get("/api/vehicle").json()["link"]
    assert link["relay"]["via"] is None and not link["connected"]
    assert "no console holding the transmitter" in link["problems"][0]
    r = shore.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
    assert r.status_code == 504, r.text
    assert "nothing was sent" in r.json()["detail"]
    (row,) = outbox_rows(shared_url)
    assert row["state"] == "withdrawn" and row["decided_by"] == "shore"


def test_the_ships_gate_judges_the_console_the_command_came_from(
    shared_url: str, tmp_path: Path, make_client: MakeClient
) -> None:
    """A row from a console that is not in control (its control lost between its own check
    and the ship's claim) is refused by the ship with 409 naming who is; nothing sent."""
    ship = make_client(
        db_path=tmp_path / "ship.sqlite3", console_name="ship", database_url=shared_url
    )
    assert owner(ship) == ("ship", "operator")
    before = frames_at_the_vehicle(ship)
    decided = shore_row_decided(shared_url, "nemesys")
    assert decided.state == "refused" and decided.status == 409 and decided.decided_by == "ship"
    assert decided.reason is not None
    assert "console 'ship' (operator 'operator') is in control" in decided.reason
    assert "the console it came from ('shore') is not" in decided.reason
    assert frames_at_the_vehicle(ship) == before
