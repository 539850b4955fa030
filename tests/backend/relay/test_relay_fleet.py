"""A shore console with a fleet (issues 23 and 24): the ship in training with three vehicles
(the fleet simulator: one shared emulated ME link) holds the transmitter; the shore
(``target relay``, the same ``NEMESYS_VEHICLES=3``) sees each vehicle from the ship's track in
the shared PostgreSQL log and commands them through the outbox, each request naming its
vehicle, the control gate judging per vehicle. Two real consoles in this process on one real
PostgreSQL; every wait is on a condition."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import psycopg
import pytest
from fastapi.testclient import TestClient

from codec import decode_addressed_frame
from tests.backend.conftest import AUTH, CIRCLE, MakeClient, console_of, wait_state, wait_until
from tests.backend.control.consoles import act
from tests.backend.relay.rows import shore_row_decided

NAMES = ["auv1", "auv2", "auv3"]

pytestmark = [pytest.mark.slow, pytest.mark.training]


def vehicles(client: TestClient) -> dict[str, dict[str, Any]]:
    r = client.get("/api/vehicles")
    assert r.status_code == 200, r.text
    return {v["name"]: v for v in r.json()}


def owners(client: TestClient) -> dict[str, tuple[str | None, str | None]]:
    r = client.get("/api/control")
    assert r.status_code == 200, r.text
    return {v["vehicle"]: (v["console"], v["operator"]) for v in r.json()}


def outbox_rows(url: str) -> list[dict[str, Any]]:
    with psycopg.connect(url) as pg:
        cur = pg.cursor(row_factory=psycopg.rows.dict_row)
        return list(cur.execute("SELECT * FROM outbox ORDER BY id").fetchall())


def heard_two_way(ship: TestClient) -> None:
    """Wait until every vehicle of a training ship is heard, two-way."""
    wait_until(
        lambda: all(v["pose"] and v["link"]["acknowledges"] for v in vehicles(ship).values()),
        timeout_s=30,
        what="the ship's vehicles heard, two-way",
    )


def ship_and_shore(
    shared_url: str, tmp_path: Path, make_client: MakeClient, ship_fleet: str, shore_fleet: str
) -> tuple[TestClient, TestClient]:
    """The ship (a training fleet, in control of its vehicles at start) and the shore (relay,
    its own fleet setting), on ``shared_url``; the ship's vehicles heard, two-way."""
    common: dict[str, Any] = {"database_url": shared_url, "control_timeout_s": 5.0}
    ship = make_client(
        db_path=tmp_path / "ship.sqlite3",
        console_name="ship",
        operator="alice",
        vehicles=ship_fleet,
        **common,
    )
    heard_two_way(ship)
    shore = make_client(
        db_path=tmp_path / "shore.sqlite3",
        console_name="shore",
        operator="bob",
        target="relay",
        vehicles=shore_fleet,
        **common,
    )
    return ship, shore


def test_a_shore_with_the_ships_fleet_sees_and_commands_each_vehicle(
    shared_url: str, tmp_path: Path, make_client: MakeClient
) -> None:
    ship, shore = ship_and_shore(shared_url, tmp_path, make_client, "3", "3")
    sims = console_of(ship).fleet_sim
    assert sims is not None

    # every vehicle on the shore: relay via the ship, its position the ship's track's
    def relayed() -> dict[str, dict[str, Any]] | None:
        views = vehicles(shore)
        ok = all(
            v["pose"] and v["pose"]["x_m"] is not None and v["link"]["relay"]["telemetry_via"]
            for v in views.values()
        )
        return views if ok else None

    seen = wait_until(relayed, timeout_s=20, what="the three vehicles relayed to the shore")
    assert list(seen) == NAMES
    assert [v["address"] for v in seen.values()] == [1, 2, 3]
    for name, v in seen.items():
        link = v["link"]
        assert link["target"] == "relay" and link["relay"]["via"] == "ship", link
        assert link["relay"]["vehicles"] == NAMES and link["connected"], link
        assert v["belief"] is not None
        own = vehicles(ship)[name]["pose"]  # where the ship hears it now
        assert v["pose"]["y_m"] == pytest.approx(own["y_m"], abs=5.0), name  # each its place
    assert len({round(v["pose"]["y_m"]) for v in seen.values()}) == 3
    assert vehicles(ship)["auv1"]["link"]["relay"] is None  # the ship hears them itself

    # control per vehicle: the shore asks for auv2, the ship grants; auv3 stays the ship's
    assert act(shore, "request", vehicle="auv2").json()["outcome"] == "pending"
    assert act(ship, "grant", vehicle="auv2").json()["outcome"] == "granted"
    wait_until(lambda: owners(shore)["auv2"] == ("shore", "bob"))
    assert owners(shore)["auv3"] == ("ship", "alice")

    # a circle from the shore to auv2: sent by the ship as auv2's addressed frame
    before = sims.transmissions
    body = {"pattern": "circle", "params": CIRCLE, "vehicle": "auv2"}
    r = shore.post("/api/commands", json=body, headers=AUTH)
    assert r.status_code == 202, r.text
    sent = r.json()
    assert sent["vehicle"] == "auv2" and sent["origin"] == "relay:shore"
    assert sent["console"] == "ship" and sent["operator"] == "bob"
    assert decode_addressed_frame(sent["hex"]).address == 2
    done = wait_state(shore, sent["id"], ("acknowledged",), timeout_s=30)
    assert done["ack"]["address"] == 2
    assert sims.transmissions == before + 1
    wait_until(
        lambda: (a := sims.sim("auv2").agent.active) is not None and a.pattern == "circle",
        timeout_s=30,
        what="auv2 flying its circle",
    )
    assert sims.sim("auv1").agent.active is None and sims.sim("auv3").agent.active is None
    # the shore sees auv2 fly it (its relayed status, from the ship's track), the others not
    wait_until(
        lambda: (
            ((vehicles(shore)["auv2"]["status"] or {}).get("active") or {}).get("pattern")
            == "circle"
        ),
        what="the shore seeing auv2 fly its circle",
    )
    assert all("active" not in vehicles(shore)[n]["status"] for n in ("auv1", "auv3"))

    # auv3 is the ship's: the shore's own gate refuses, naming the ship; nothing written
    rows = len(outbox_rows(shared_url))
    body = {"pattern": "circle", "params": CIRCLE, "vehicle": "auv3"}
    r = shore.post("/api/commands", json=body, headers=AUTH)
    assert r.status_code == 409, r.text
    assert "console 'ship' (operator 'alice') is in control of vehicle auv3" in r.json()["detail"]
    assert len(outbox_rows(shared_url)) == rows

    # Surface all from the shore: one outbox row, one address-0 frame, a record per vehicle
    before = sims.transmissions
    r = shore.post("/api/surface", json={"vehicle": "all"}, headers=AUTH)
    assert r.status_code == 202, r.text
    records = r.json()["commands"]
    assert [c["vehicle"] for c in records] == NAMES
    assert len({c["hex"] for c in records}) == 1
    assert decode_addressed_frame(records[0]["hex"]).address == 0
    assert all(c["origin"] == "relay:shore" and c["operator"] == "bob" for c in records)
    row = outbox_rows(shared_url)[-1]
    assert row["vehicle"] == "all" and row["state"] == "taken"
    assert row["command_id"] == records[0]["id"]
    ended = [wait_state(shore, c["id"], ("acknowledged",), timeout_s=30) for c in records]
    assert {c["ack"]["address"] for c in ended} == {0}
    assert sims.transmissions > before
    for name in NAMES:
        active = sims.sim(name).agent.active
        assert active is not None and active.pattern == "surface", name


def test_a_shore_whose_fleet_the_ship_lacks_is_told_naming_the_ships_vehicles(
    shared_url: str, tmp_path: Path, make_client: MakeClient
) -> None:
    ship, shore = ship_and_shore(shared_url, tmp_path, make_client, "2", "3")
    sims = console_of(ship).fleet_sim
    assert sims is not None
    said = (
        "console 'ship', holding the transmitter, has no vehicle 'auv3' (its vehicles: auv1, auv2)"
    )

    # the shore's page: auv3 not connected, saying why; the others relay via the ship
    lacking = wait_until(
        lambda: (v := vehicles(shore)["auv3"]["link"])["relay"]["vehicles"] and v,
        what="the ship's vehicles read",
    )
    assert not lacking["connected"] and any(said in p for p in lacking["problems"]), lacking
    assert vehicles(shore)["auv1"]["link"]["connected"]
    checks = shore.post("/api/link/test", headers=AUTH)  # the link test names it too
    assert checks.status_code == 200, checks.text
    assert not checks.json()["ok"]
    assert any(said in (c["reason"] or "") for c in checks.json()["checks"]), checks.json()

    # a command to auv3 (nobody else controls it: the shore took it at start) is refused by
    # the ship, naming its vehicles; nothing sent
    assert act(shore, "request", vehicle="auv3").json()["outcome"] in ("granted", "unchanged")
    assert owners(shore)["auv3"] == ("shore", "bob")
    before = sims.transmissions
    body = {"pattern": "circle", "params": CIRCLE, "vehicle": "auv3"}
    r = shore.post("/api/commands", json=body, headers=AUTH)
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    message = detail if isinstance(detail, str) else str(detail)
    assert "console 'ship' (holding the transmitter) refused it" in message, message
    assert "auv1, auv2" in message, message
    (row,) = outbox_rows(shared_url)
    assert row["state"] == "refused" and row["decided_by"] == "ship" and row["vehicle"] == "auv3"
    assert sims.transmissions == before


def test_a_single_vehicle_shores_row_to_a_fleet_ship_is_refused_naming_its_vehicles(
    shared_url: str, make_client: MakeClient
) -> None:
    """A shore without a fleet writes rows for ``nemesys``, a vehicle the ship's fleet lacks:
    the ship takes the row once it waited, and refuses it naming its vehicles (never left
    waiting until the shore gives up); nothing sent."""
    ship = make_client(console_name="ship", database_url=shared_url, vehicles="2")
    sims = console_of(ship).fleet_sim
    assert sims is not None
    before = sims.transmissions
    decided = shore_row_decided(shared_url, "nemesys")
    assert decided.state == "refused" and decided.status == 422 and decided.decided_by == "ship"
    assert decided.reason is not None and "auv1, auv2" in decided.reason, decided.reason
    assert sims.transmissions == before


def test_a_shores_surface_all_reaches_every_transmitting_consoles_vehicles(
    shared_url: str, tmp_path: Path, make_client: MakeClient
) -> None:
    """Two ships, each holding a transmitter to its own vehicles (auv1 and auv2; auv3): the
    shore shows each vehicle through its own ship (link and track). Its Surface to all is
    taken by one ship, which surfaces its own vehicles with one address-0 frame and hands one
    Surface row per vehicle of the other on; the other sends each. Every vehicle surfaces,
    each record ending acknowledged."""
    two = '[{"name": "auv1", "address": 1}, {"name": "auv2", "address": 2}]'
    ship_a, shore = ship_and_shore(shared_url, tmp_path, make_client, two, "3")
    ship_b = make_client(
        db_path=tmp_path / "ship_b.sqlite3",
        console_name="ship_b",
        operator="carol",
        vehicles='[{"name": "auv3", "address": 3}]',
        database_url=shared_url,
        control_timeout_s=5.0,
    )
    sims = {"ship": console_of(ship_a).fleet_sim, "ship_b": console_of(ship_b).fleet_sim}
    assert sims["ship"] is not None and sims["ship_b"] is not None

    # both ships say they hold a transmitter, with their vehicles
    def beating() -> bool:
        with psycopg.connect(shared_url) as pg:
            said = pg.execute("SELECT console, health FROM transmitters").fetchall()
        return {c: json.loads(h)["vehicles"] for c, h in said} == {
            "ship": ["auv1", "auv2"],
            "ship_b": ["auv3"],
        }

    wait_until(beating, timeout_s=30, what="both ships' transmitters on the log")
    heard_two_way(ship_b)

    # the shore: each vehicle connected through its own ship, shown from that ship's track
    ships = {"auv1": "ship", "auv2": "ship", "auv3": "ship_b"}

    def each_via_its_ship() -> bool:
        views = vehicles(shore)
        shown = all(v["link"]["connected"] and v["pose"] for v in views.values())
        via = {
            n: (v["link"]["relay"]["via"], v["link"]["relay"]["telemetry_via"])
            for n, v in views.items()
        }
        return shown and via == {n: (s, s) for n, s in ships.items()}

    wait_until(each_via_its_ship, timeout_s=30, what="each vehicle relayed via its own ship")
    assert [v["link"]["relay"]["vehicles"] for v in vehicles(shore).values()] == [
        ["auv1", "auv2"],
        ["auv1", "auv2"],
        ["auv3"],
    ]

    r = shore.post("/api/surface", json={"vehicle": "all"}, headers=AUTH)
    assert r.status_code == 202, r.text
    taken = outbox_rows(shared_url)[0]
    assert taken["vehicle"] == "all" and taken["state"] == "taken"
    first, other = (
        (sims["ship"], sims["ship_b"])
        if taken["decided_by"] == "ship"
        else (
            sims["ship_b"],
            sims["ship"],
        )
    )
    assert first is not None and other is not None

    def decided() -> list[dict[str, Any]] | None:
        rows = outbox_rows(shared_url)[1:]
        return rows if rows and all(row["state"] != "waiting" for row in rows) else None

    handed = wait_until(decided, timeout_s=30, what="the handed-on rows decided")
    handed_names = sorted(row["vehicle"] for row in handed)
    assert [row["id"] for row in handed] == json.loads(taken["detail"])["handed_on"]
    assert all(row["state"] == "taken" and row["pattern"] == "surface" for row in handed), handed
    assert all(row["decided_by"] != taken["decided_by"] for row in handed)
    assert handed_names == (["auv3"] if taken["decided_by"] == "ship" else ["auv1", "auv2"])

    # every vehicle's Surface record, from the shore's operator, ends acknowledged
    ids = [int(taken["command_id"]), *(int(row["command_id"]) for row in handed)]
    if isinstance(extra := json.loads(taken["detail"]).get("commands"), list):
        ids = [*extra, *(int(row["command_id"]) for row in handed)]
    ended = [wait_state(shore, i, ("acknowledged",), timeout_s=30) for i in ids]
    assert sorted(c["vehicle"] for c in ended) == NAMES
    assert all(c["pattern"] == "surface" and c["operator"] == "bob" for c in ended)
    assert all(c["origin"] == "relay:shore" for c in ended)

    def surfacing() -> bool:
        flying = [
            sim.sim(name).agent.active
            for sim, names in ((sims["ship"], ("auv1", "auv2")), (sims["ship_b"], ("auv3",)))
            if sim is not None
            for name in names
        ]
        return len(flying) == 3 and all(a is not None and a.pattern == "surface" for a in flying)

    wait_until(surfacing, timeout_s=30, what="all three vehicles surfacing")
