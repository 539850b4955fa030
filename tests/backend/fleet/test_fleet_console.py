"""The console with a fleet of three in-memory vehicles on one channel (issue 23): each the real
onboard agent with its address, every one hearing every frame (``tests/agent_link.py``'s
``agent_fleet``), each answering on its own link.

A command to one vehicle changes only that one's active command; Surface to all surfaces all
three, each record ending ``acknowledged`` by its own vehicle; every request names its vehicle
(422 naming the vehicles otherwise); the vehicles' views, the transmitter's airtime budget, the
mission log's filters and exports, /ws and scripts, per vehicle."""

from __future__ import annotations

import csv
import io
from collections.abc import Iterator
from typing import Any

import pytest
from fastapi.testclient import TestClient

from codec import decode_addressed_frame
from station.link import Capability
from station.link_fleet import FleetLink
from tests.agent_link import AgentLink, agent_fleet
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    SQUARE,
    MakeLightClient,
    console_of,
    wait_state,
    wait_until,
)
from tests.backend.test_live_messages import validator
from vehicle_contract.fleet import parse_vehicles

FLEET = parse_vehicles("3")
NAMES = [v.name for v in FLEET]


@pytest.fixture
def fleet_link() -> FleetLink:
    return agent_fleet(FLEET)


@pytest.fixture
def fleet(make_light_client: MakeLightClient, fleet_link: FleetLink) -> Iterator[TestClient]:
    client = make_light_client(fleet_link, vehicles="3")  # type: ignore[arg-type]
    wait_until(lambda: all(v["pose"] for v in client.get("/api/vehicles").json()))
    yield client


def agents(link: FleetLink) -> dict[str, AgentLink]:
    out = {}
    for name, vehicle in link.vehicles.items():
        assert isinstance(vehicle, AgentLink)
        out[name] = vehicle
    return out


def post(client: TestClient, path: str, body: dict[str, Any]) -> Any:
    return client.post(path, json=body, headers=AUTH)


def send(client: TestClient, vehicle: str, pattern: str, params: dict[str, Any]) -> Any:
    r = post(client, "/api/commands", {"pattern": pattern, "params": params, "vehicle": vehicle})
    assert r.status_code == 202, r.text
    return r.json()


def vehicle_error(response: Any) -> str:
    """The message of a 422 at ``vehicle``."""
    assert response.status_code == 422, response.text
    detail = response.json()["detail"][0]
    assert detail["loc"][-1] == "vehicle", detail
    message: str = detail["msg"]
    return message


def test_every_vehicle_is_listed_with_its_address_pose_health_and_belief(
    fleet: TestClient,
) -> None:
    vehicles = fleet.get("/api/vehicles").json()
    assert [(v["name"], v["address"]) for v in vehicles] == [("auv1", 1), ("auv2", 2), ("auv3", 3)]
    east = [v["pose"]["y_m"] for v in vehicles]
    assert east == [0.0, 20.0, 40.0]  # each its own telemetry
    assert all(v["link"]["acknowledges"] and v["belief"]["vehicle"] == v["name"] for v in vehicles)
    one = fleet.get("/api/vehicles/auv2").json()
    assert one["name"] == "auv2" and one["pose"]["y_m"] == 20.0
    missing = fleet.get("/api/vehicles/auv9")
    assert missing.status_code == 404
    assert all(n in missing.json()["detail"] for n in NAMES)


def test_a_command_to_one_vehicle_changes_only_its_active_command(
    fleet: TestClient, fleet_link: FleetLink
) -> None:
    rec = send(fleet, "auv2", "circle", CIRCLE)
    assert rec["vehicle"] == "auv2"
    assert decode_addressed_frame(rec["hex"]).address == 2
    done = wait_state(fleet, rec["id"])
    assert done["state"] == "acknowledged" and done["ack"]["address"] == 2
    active = {n: a.agent.active for n, a in agents(fleet_link).items()}
    assert active["auv2"] is not None and active["auv2"].pattern == "circle"
    assert active["auv1"] is None and active["auv3"] is None
    # the others heard the frame and said it was not theirs
    for name in ("auv1", "auv3"):
        assert agents(fleet_link)[name].acks[-1]["reason"] == "other_vehicle"
    views = {v["name"]: v for v in fleet.get("/api/vehicles").json()}
    assert views["auv2"]["active"]["pattern"] == "circle"
    assert views["auv2"]["last_sent"]["id"] == rec["id"]
    assert views["auv1"]["last_sent"] is None and views["auv3"]["active"] is None
    assert not any(v["echo_mismatch"] for v in views.values())


def test_surface_all_surfaces_all_three_each_record_ending_acknowledged(
    fleet: TestClient, fleet_link: FleetLink
) -> None:
    for name in NAMES:
        wait_state(fleet, send(fleet, name, "square", SQUARE)["id"])
    r = post(fleet, "/api/surface", {"vehicle": "all"})
    assert r.status_code == 202, r.text
    body = r.json()
    assert body["vehicle"] == "all"
    records = body["commands"]
    assert [c["vehicle"] for c in records] == NAMES
    assert {decode_addressed_frame(c["hex"]).address for c in records} == {0}
    ended = [wait_state(fleet, c["id"]) for c in records]
    assert [c["state"] for c in ended] == ["acknowledged"] * 3
    assert all(c["ack"]["address"] == 0 for c in ended)
    assert all(a.agent.active.pattern == "surface" for a in agents(fleet_link).values())  # type: ignore[union-attr]
    transmitter = fleet.get("/api/transmitter").json()
    assert transmitter["addressed"] and transmitter["queued"] == []
    assert transmitter["airtime_budget_s"] == 0.0


def test_every_request_names_its_vehicle(fleet: TestClient) -> None:
    msg = vehicle_error(post(fleet, "/api/commands", {"pattern": "circle", "params": CIRCLE}))
    assert "required" in msg and all(n in msg for n in NAMES)
    msg = vehicle_error(
        post(fleet, "/api/commands", {"pattern": "circle", "params": CIRCLE, "vehicle": "all"})
    )
    assert "Surface only" in msg
    msg = vehicle_error(
        post(fleet, "/api/commands", {"pattern": "circle", "params": CIRCLE, "vehicle": "x"})
    )
    assert "'x'" in msg and "auv3" in msg
    assert "all" in vehicle_error(post(fleet, "/api/surface", {}))
    assert vehicle_error(fleet.post("/api/preview", json={"pattern": "circle", "params": CIRCLE}))
    assert vehicle_error(fleet.post("/api/predict", json={"pattern": "circle", "params": CIRCLE}))
    assert fleet.get("/api/commands").json() == []  # nothing was written


def test_a_retry_names_its_vehicle_and_may_go_to_another(
    make_light_client: MakeLightClient,
) -> None:
    link = agent_fleet(FLEET)
    client = make_light_client(link, vehicles="3", ack_timeout_s=0.2)  # type: ignore[arg-type]
    agents(link)["auv1"].answer = False  # auv1 out of range: its command times out
    lost = wait_state(client, send(client, "auv1", "circle", CIRCLE)["id"])
    assert lost["state"] == "timed_out"
    msg = vehicle_error(post(client, f"/api/commands/{lost['id']}/retry", {}))
    assert all(n in msg for n in NAMES)
    r = post(client, f"/api/commands/{lost['id']}/retry", {"vehicle": "auv3"})
    assert r.status_code == 202, r.text
    again = wait_state(client, r.json()["id"])
    assert again["vehicle"] == "auv3" and again["retry_of"] == lost["id"]
    assert again["state"] == "acknowledged" and again["ack"]["address"] == 3


def test_preview_is_from_that_vehicle_with_its_addressed_frame(fleet: TestClient) -> None:
    body = {"pattern": "circle", "params": CIRCLE, "vehicle": "auv3"}
    doc = fleet.post("/api/preview", json=body).json()
    assert len(doc["bits"]) == 108 and decode_addressed_frame(doc["hex"]).address == 3
    assert [s["name"] for s in doc["sections"]][2:4] == ["address", "address_check"]
    assert doc["airtime_ms"] == pytest.approx(3.0)
    assert doc["from"]["y_m"] == pytest.approx(40.0)  # auv3's place


def test_the_log_filters_and_exports_by_vehicle(fleet: TestClient) -> None:
    for name, pattern, params in (("auv1", "circle", CIRCLE), ("auv2", "square", SQUARE)):
        wait_state(fleet, send(fleet, name, pattern, params)["id"])
    only = fleet.get("/api/commands", params={"vehicle": "auv2"}).json()
    assert [c["pattern"] for c in only] == ["square"]
    rows = list(csv.reader(io.StringIO(fleet.get("/api/log.csv").text)))
    header = rows[0]
    assert header[header.index("target") + 1] == "vehicle"
    assert [r[header.index("vehicle")] for r in rows[1:]] == ["auv1", "auv2"]
    dive = only[0]["dive"]
    detail = fleet.get(f"/api/dives/{dive}", params={"vehicle": "auv1"}).json()
    assert [c["vehicle"] for c in detail["commands"]] == ["auv1"]
    console = console_of(fleet)
    assert console.log is not None
    console.log.flush_track()
    points = console.log.track_rows(dive, vehicle="auv2")
    assert points and all(p["y_m"] == 20.0 for p in points)
    # a name the fleet has not is a 422 naming its vehicles, never an empty answer
    for path in ("/api/commands", "/api/log.csv", "/api/log.json", f"/api/dives/{dive}"):
        r = fleet.get(path, params={"vehicle": "auv9"})
        assert r.status_code == 422, (path, r.text)
        (problem,) = r.json()["detail"]
        assert problem["loc"] == ["query", "vehicle"]
        assert all(name in problem["msg"] for name in NAMES), problem["msg"]


def test_live_news_name_their_vehicle_and_surface_all_answers_every_record(
    fleet: TestClient,
) -> None:
    documented = validator()
    with fleet.websocket_connect("/ws") as ws:
        ws.send_json({"type": "auth", "token": AUTH["Authorization"].split()[1]})
        telemetry: set[str] = set()
        queued = None
        ws.send_json({"type": "surface"})  # no vehicle: refused, naming them
        while queued is None or len(telemetry) < 3:
            msg = ws.receive_json()
            assert msg["type"] != "telemetry", "a fleet's telemetry comes in fleet_telemetry"
            if msg["type"] == "fleet_telemetry":  # as docs/live.md says
                assert not [e.message for e in documented.iter_errors(msg)]
                telemetry.update(t["vehicle"] for t in msg["telemetry"])
            elif msg["type"] == "error":
                assert msg["field"] == "vehicle" and msg["status"] == 422
                assert all(n in msg["detail"] for n in NAMES)
                ws.send_json({"type": "surface", "vehicle": "all"})
            elif msg["type"] == "queued":
                queued = msg
        assert telemetry == set(NAMES)
        assert [c["vehicle"] for c in queued["commands"]] == NAMES


def test_a_script_drives_one_vehicle_named_in_every_step(fleet: TestClient) -> None:
    step = {"pattern": "circle", "params": CIRCLE, "trigger": {"kind": "at", "t_s": 0}}
    script = {"format": "nemesys-mission-script", "version": 1, "name": "s", "steps": [step]}
    r = fleet.post("/api/scripts/preview", json=script)
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["body", "steps", 0, "vehicle"]
    mixed = {**script, "steps": [{**step, "vehicle": "auv1"}, {**step, "vehicle": "auv2"}]}
    r = fleet.post("/api/scripts/preview", json=mixed)
    assert r.status_code == 422 and "one vehicle" in r.json()["detail"][0]["msg"]
    ok = {**script, "steps": [{**step, "vehicle": "auv2"}]}
    doc = fleet.post("/api/scripts/preview", json=ok).json()
    assert doc["path"]["y_m"][0] == pytest.approx(20.0, abs=1.0)  # from auv2's place
    onboard = fleet.post("/api/scripts/export", json=ok).json()
    assert decode_addressed_frame(onboard["frames"][0]["hex"]).address == 2
    # the run's log names the vehicle of every step, and of the one proposed next
    two = {**ok, "steps": [{**step, "vehicle": "auv2"}, {**step, "vehicle": "auv2"}]}
    run = post(fleet, "/api/scripts/run", {"script": two, "mode": "step"})
    assert run.status_code == 200, run.text
    assert [s["vehicle"] for s in run.json()["steps"]] == ["auv2", "auv2"]
    assert run.json()["next"]["vehicle"] == "auv2"
    state = fleet.get("/api/scripts/run").json()
    assert [s["vehicle"] for s in state["steps"]] == ["auv2", "auv2"]
    stopped = post(fleet, "/api/scripts/run/stop", {})
    assert [s["vehicle"] for s in stopped.json()["steps"]] == ["auv2", "auv2"]


def test_one_way_fleet_vehicles_share_the_transmitters_health(
    make_light_client: MakeLightClient,
) -> None:
    link = agent_fleet(FLEET, Capability.NONE)
    client = make_light_client(
        link,  # type: ignore[arg-type]  # a fleet's link (the fixture's type names the single one)
        vehicles="3",
        link_ber=1e-2,
        surface_repeat_s=0.05,
    )
    r = post(client, "/api/surface", {"vehicle": "all"})
    records = r.json()["commands"]
    assert all(c["copies"] >= 3 and c["two_way"] is False for c in records)
    budget = client.get("/api/transmitter").json()["airtime_budget_s"]
    assert budget > 0
    ended = [wait_state(client, c["id"], timeout_s=30) for c in records]
    assert [c["state"] for c in ended] == ["sent"] * 3
    assert all(a.agent.active.pattern == "surface" for a in agents(link).values())  # type: ignore[union-attr]
    health = [v["link"] for v in client.get("/api/vehicles").json()]
    assert all(h["capability"] == "none" and not h["acknowledges"] for h in health)
