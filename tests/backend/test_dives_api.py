"""A dive read back from the mission log: ``GET /api/series`` (the plots; a fleet's, of the
vehicle it names, on both back-ends: ``log_backend``), ``GET /api/dives/{dive}/timeline`` and
``PUT /api/replay/at`` (the replay's slider), and ``GET /api/dives/{dive}/export.mcap`` (on
both back-ends)."""

from __future__ import annotations

from collections import Counter
from io import BytesIO
from typing import Any

import pytest
from fastapi.testclient import TestClient
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from backend.chart.geo import Datum
from planner import VehicleState
from station.link import Capability
from station.link_fleet import FleetLink
from tests.agent_link import HOLDING, AgentLink, agent_fleet
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    MakeLightClient,
    console_of,
    send,
    wait_state,
    wait_until,
)
from tests.backend.log_backend import LogBackend
from vehicle_contract.fleet import parse_vehicles

FLEET = parse_vehicles("3")
NAMES = [v.name for v in FLEET]


def test_before_any_dive_the_series_is_empty(make_light_client: MakeLightClient) -> None:
    client = make_light_client(AgentLink(Capability.NONE))
    assert client.get("/api/series").json() == {
        "dive": None,
        "started_at": None,
        "start_t_s": None,
        "interval_s": None,
        "t_s": [],
        "depth_m": [],
        "commanded_depth_m": [],
        "battery_pct": [],
        "speed_mps": [],
        "heading_deg": [],
        "mode": [],
        "nav_valid": [],
        "nav_age_s": [],
    }


def test_the_series_is_the_dives_track_from_its_start(client: TestClient) -> None:
    console = console_of(client)
    assert console.log is not None and console.dive == 1  # the first pose started it
    circle = {"pattern": "circle", "params": {"depth": 3.0}}
    for k in range(1, 10):
        status = {
            "depth_m": 2.0 + k / 10,
            "battery_pct": 100 - k,
            "speed_mps": 0.3,
            "active": circle,
        }
        console.log.add_track(1, HOLDING.t_s + k, 0.0, 0.0, 2.0, 0.0, status)
    s = client.get("/api/series").json()
    assert s["dive"] == 1 and s["started_at"] == client.get("/api/dives").json()[0]["started_at"]
    assert s["start_t_s"] == HOLDING.t_s  # the first pose heard
    assert s["t_s"] == [float(k) for k in range(10)]
    assert s["depth_m"][0] == 2.0 and s["depth_m"][-1] == pytest.approx(2.9)
    assert s["commanded_depth_m"] == [None] + [3.0] * 9
    assert s["battery_pct"][1:] == [100 - k for k in range(1, 10)]
    # the same dive named, thinned evenly to three samples (first and last kept)
    thin = client.get("/api/series", params={"dive": 1, "limit": 3}).json()
    assert thin["t_s"] == [0.0, 4.0, 9.0] and thin["interval_s"] == 4.5


def test_the_series_shows_a_navigation_fault_as_points_without_position(
    client: TestClient,
) -> None:
    console = console_of(client)
    assert console.log is not None and console.dive == 1
    ok = {"nav_valid": True, "nav_age_s": 0.1, "heading_deg": 10.0, "mode": "running"}
    console.log.add_track(1, HOLDING.t_s + 1, 1.0, 0.0, 2.0, 10.0, ok)
    fault = {"nav_valid": False, "nav_age_s": 7.0, "heading_deg": None, "mode": "nav_fault"}
    console.log.add_status_point(1, HOLDING.t_s + 2, fault)
    s = client.get("/api/series").json()
    assert s["t_s"][-2:] == [1.0, 2.0]
    assert s["nav_valid"][-2:] == [True, False] and s["nav_age_s"][-2:] == [0.1, 7.0]
    assert s["mode"][-2:] == ["running", "nav_fault"] and s["heading_deg"][-2:] == [10.0, None]
    # the replay's timeline keeps the positions only
    timeline = client.get("/api/dives/1/timeline").json()
    assert [p["t_s"] for p in timeline["samples"]][-1] == 1.0


@pytest.mark.parametrize(
    ("params", "where", "allowed"),
    [
        ({"dive": 0}, "dive", "greater than or equal to 1"),
        ({"dive": "current"}, "dive", "valid integer"),
        ({"limit": 1}, "limit", "greater than or equal to 2"),
        ({"limit": 100_000}, "limit", "less than or equal to 86400"),
        ({"limit": "all"}, "limit", "valid integer"),
    ],
)
def test_bad_input_is_422_naming_what_is_allowed(
    client: TestClient, params: dict[str, object], where: str, allowed: str
) -> None:
    r = client.get("/api/series", params=params)
    assert r.status_code == 422, r.text
    (item,) = r.json()["detail"]
    assert item["loc"] == ["query", where]
    assert allowed in item["msg"], item


def test_a_dive_that_does_not_exist_is_404(client: TestClient) -> None:
    r = client.get("/api/series", params={"dive": 99})
    assert r.status_code == 404 and r.json() == {"detail": "no dive 99"}


def test_the_single_vehicle_may_be_named_and_no_other(client: TestClient) -> None:
    plain = client.get("/api/series").json()
    assert "vehicle" not in plain and plain["dive"] == 1  # as it always was
    assert client.get("/api/series", params={"vehicle": "nemesys"}).json() == plain
    r = client.get("/api/series", params={"vehicle": "auv1"})
    assert r.status_code == 422, r.text
    (item,) = r.json()["detail"]
    assert item["loc"] == ["query", "vehicle"] and "'nemesys'" in item["msg"], item


def test_a_fleets_series_is_the_named_vehicles_alone(
    make_light_client: MakeLightClient, log_backend: LogBackend
) -> None:
    """Three vehicles' tracks in one dive: each series holds its vehicle's samples only (its
    own depths and commanded depth), says whose it is, and a fleet's request names one of
    its vehicles (422 at the query's ``vehicle`` naming them otherwise)."""
    link: FleetLink = agent_fleet(FLEET)
    client = make_light_client(link, vehicles="3", **log_backend.settings())  # type: ignore[arg-type]
    wait_until(lambda: all(v["pose"] for v in client.get("/api/vehicles").json()))
    console = console_of(client)
    assert console.log is not None and console.dive is not None
    dive = console.dive
    start = max(r["t_s"] for r in console.log.track_rows(dive, positioned=False))
    for k in range(1, 4):
        for i, name in enumerate(NAMES):
            status = {
                "depth_m": 10.0 * (i + 1) + k,
                "battery_pct": 90 - i,
                "active": {"pattern": "circle", "params": {"depth": 5.0 + i}},
            }
            console.log.add_track(dive, start + k, 0.0, 20.0 * i, 2.0, 0.0, status, vehicle=name)
    for i, name in enumerate(NAMES):
        s = client.get("/api/series", params={"vehicle": name}).json()
        assert s["vehicle"] == name and s["dive"] == dive
        rows = console.log.track_rows(dive, positioned=False, vehicle=name)
        assert len(s["t_s"]) == len(rows) >= 4  # its first pose's point, then the three
        assert s["depth_m"][-3:] == [10.0 * (i + 1) + k for k in range(1, 4)]
        assert s["commanded_depth_m"][-3:] == [5.0 + i] * 3
        assert s["battery_pct"][-3:] == [90 - i] * 3
        assert s["t_s"][-1] - s["t_s"][-3] == 2.0
    thin = client.get("/api/series", params={"vehicle": "auv2", "dive": dive, "limit": 2})
    assert thin.json()["depth_m"][-1] == 23.0 and len(thin.json()["t_s"]) == 2
    for params in ({}, {"vehicle": "auv9"}, {"vehicle": "all"}, {"dive": 99}):
        r = client.get("/api/series", params=params)
        assert r.status_code == 422, r.text  # the vehicle first, before the dive
        (item,) = r.json()["detail"]
        assert item["loc"] == ["query", "vehicle"], item
        assert all(n in item["msg"] for n in NAMES), item
    r = client.get("/api/series", params={"vehicle": "auv1", "dive": 99})
    assert r.status_code == 404 and r.json() == {"detail": "no dive 99"}


# --- the replay's timeline and its slider ----------------------------------------------------


def moved(link: AgentLink, client: TestClient, dt_s: float, x_m: float) -> None:
    """The in-memory vehicle reports itself ``dt_s`` later at ``x_m`` north: its pose, then
    its status (a track point keeps the status before it: the circle from the next one)."""
    link.state = VehicleState(x_m, 0.0, 2.0, heading_deg=0.0, t_s=HOLDING.t_s + dt_s)
    client.portal.call(link.report)  # type: ignore[union-attr]


def circle_flown(link: AgentLink, client: TestClient) -> dict[str, Any]:
    """A circle sent and acknowledged, then the vehicle heard at 2 s (4 m) and 3 s (6 m)."""
    sent = send(client)
    wait_state(client, sent["id"], ("acknowledged",))
    moved(link, client, 2.0, 4.0)
    moved(link, client, 3.0, 6.0)
    return sent


def test_the_timeline_has_the_samples_the_command_running_and_the_link_events(
    make_light_client: MakeLightClient,
) -> None:
    link = AgentLink()
    client = make_light_client(link)
    sent = circle_flown(link, client)
    doc = client.get("/api/dives/1/timeline").json()
    assert doc["dive"] == 1 and doc["start_t_s"] == HOLDING.t_s
    assert [s["t_s"] for s in doc["samples"]] == [0.0, 2.0, 3.0]
    assert [s["pattern"] for s in doc["samples"]] == [None, None, "circle"]
    assert [s["command_id"] for s in doc["samples"]] == [None, None, sent["id"]]
    assert doc["samples"][1]["lat_deg"] is None  # no datum on this console
    # (in time order; this vehicle's clock stands still between reports, so the order of a
    # copy and its acknowledgement here says nothing)
    kinds = sorted((e["kind"], e["command_id"]) for e in doc["events"])
    assert kinds == [("acknowledged", sent["id"]), ("sent", sent["id"])]
    times = [e["t_s"] for e in doc["events"]]
    assert times == sorted(times) and doc["from_t_s"] <= times[0]
    assert doc["duration_s"] >= 2.0 and doc["unplaced_events"] == 0
    assert [c["id"] for c in doc["commands"]] == [sent["id"]]
    assert client.get("/api/dives/9/timeline").status_code == 404
    assert client.get("/api/dives/0/timeline").status_code == 422


def test_the_slider_gives_the_vehicle_at_a_time_and_refuses_one_outside_the_dive(
    make_light_client: MakeLightClient,
) -> None:
    link = AgentLink()
    client = make_light_client(link)
    sent = circle_flown(link, client)
    r = client.put("/api/replay/at", json={"dive": 1, "t_s": 1.5})
    assert r.status_code == 200, r.text
    at = r.json()
    assert at["drawn"] is False  # no 3D view in this app, and no X-Nemesys-View
    assert at["position"]["x_m"] == pytest.approx(3.0)  # 3/4 of the way from 0 to 4 m
    assert at["position"]["command_id"] is None  # the sample before: not running it yet
    at = client.put("/api/replay/at", json={"dive": 1, "t_s": 3.0}).json()
    assert at["position"]["command_id"] == sent["id"] and at["position"]["x_m"] == 6.0
    end = client.get("/api/dives/1/timeline").json()["duration_s"]
    r = client.put("/api/replay/at", json={"dive": 1, "t_s": end + 1})
    assert r.status_code == 422
    (item,) = r.json()["detail"]
    assert item["loc"] == ["body", "t_s"] and "t_s must be within" in item["msg"], item
    assert client.put("/api/replay/at", json={"dive": 4, "t_s": 0}).status_code == 404
    for bad in ({"dive": 1, "t_s": "1"}, {"dive": 1}, {"dive": True, "t_s": 0}):
        assert client.put("/api/replay/at", json=bad).status_code == 422, bad


def test_a_fleets_replay_is_the_named_vehicles_alone(make_light_client: MakeLightClient) -> None:
    """Three vehicles in one dive, each on its own lane: the timeline, the slider and the 3D
    replay of one are its samples, its commands, its events and those naming no vehicle,
    never another's; a fleet's replay names its vehicle (422 naming them otherwise)."""
    link: FleetLink = agent_fleet(FLEET)
    client = make_light_client(link, vehicles="3")  # type: ignore[arg-type]
    wait_until(lambda: all(v["pose"] for v in client.get("/api/vehicles").json()))
    console = console_of(client)
    log, dive = console.log, console.dive
    assert log is not None and dive is not None
    body = {"pattern": "circle", "params": CIRCLE, "vehicle": "auv2"}
    sent = client.post("/api/commands", json=body, headers=AUTH).json()
    wait_state(client, sent["id"], ("acknowledged",))
    start = max(r["t_s"] for r in log.track_rows(dive, positioned=False))
    for k in range(1, 4):
        for i, name in enumerate(NAMES):
            log.add_track(dive, start + k, 2.0 * k, 20.0 * i, 2.0, 0.0, {}, vehicle=name)
    log.add_event(dive, "echo_mismatch", "auv1 runs another", vehicle="auv1")
    log.add_event(dive, "datum", "datum set")
    doc = client.get(f"/api/dives/{dive}/timeline", params={"vehicle": "auv2"}).json()
    assert doc["vehicle"] == "auv2"
    rows = log.track_rows(dive, vehicle="auv2")
    assert len(doc["samples"]) == len(rows) >= 4  # its first pose's point, then the three
    assert {s["y_m"] for s in doc["samples"][-3:]} == {20.0}  # auv2's lane only
    assert [c["id"] for c in doc["commands"]] == [sent["id"]]
    texts = [e["text"] for e in doc["events"]]
    assert "datum set" in texts and "auv1 runs another" not in texts
    assert {e["command_id"] for e in doc["events"]} == {sent["id"], None}
    other = client.get(f"/api/dives/{dive}/timeline", params={"vehicle": "auv1"}).json()
    assert other["commands"] == [] and "auv1 runs another" in [e["text"] for e in other["events"]]
    assert {s["y_m"] for s in other["samples"]} == {0.0}
    t_s = doc["samples"][-1]["t_s"]
    at = client.put("/api/replay/at", json={"dive": dive, "t_s": t_s, "vehicle": "auv3"}).json()
    assert at["vehicle"] == "auv3" and at["position"]["y_m"] == 40.0, at
    r = client.post(f"/api/dives/{dive}/replay", params={"vehicle": "auv2"}, headers=AUTH)
    assert r.json() == {"dive": dive, "vehicle": "auv2", "track_points": len(rows), "commands": 1}
    for named in ({}, {"vehicle": "auv9"}, {"vehicle": "all"}):
        asked = (
            client.get(f"/api/dives/{dive}/timeline", params=named),
            client.put("/api/replay/at", json={"dive": dive, "t_s": 0.0, **named}),
            client.post(f"/api/dives/{dive}/replay", params=named, headers=AUTH),
        )
        for r, where in zip(asked, ("query", "body", "query"), strict=True):
            assert r.status_code == 422, r.text
            (item,) = r.json()["detail"]
            assert item["loc"] == [where, "vehicle"], item
            assert all(n in item["msg"] for n in NAMES), item


def test_the_single_vehicles_replay_may_name_it_and_no_other(client: TestClient) -> None:
    plain = client.get("/api/dives/1/timeline").json()
    assert "vehicle" not in plain
    assert client.get("/api/dives/1/timeline", params={"vehicle": "nemesys"}).json() == plain
    at = client.put("/api/replay/at", json={"dive": 1, "t_s": 0.0}).json()
    assert "vehicle" not in at
    named = client.put("/api/replay/at", json={"dive": 1, "t_s": 0.0, "vehicle": "nemesys"})
    assert named.json() == at
    assert set(client.post("/api/dives/1/replay", headers=AUTH).json()) == {
        "dive",
        "track_points",
        "commands",
    }
    r = client.put("/api/replay/at", json={"dive": 1, "t_s": 0.0, "vehicle": "auv1"})
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["body", "vehicle"]


def test_a_dive_downloads_as_mcap_with_the_logs_rows(
    make_light_client: MakeLightClient, log_backend: LogBackend
) -> None:
    client = make_light_client(**log_backend.settings())
    console = console_of(client)
    assert console.log is not None and console.dive == 1
    for k in range(1, 6):
        console.log.add_track(1, HOLDING.t_s + k, float(k), 0.0, 2.0, 0.0, {"nav_valid": True})
    console.log.add_status_point(1, HOLDING.t_s + 6, {"nav_valid": False})
    send(client, "circle", None)
    rows = console.log.track_rows(1, positioned=False)
    commands = console.log.commands(dive=1, limit=100)
    r = client.get("/api/dives/1/export.mcap")
    assert r.status_code == 200, r.text
    assert r.headers["content-disposition"] == 'attachment; filename="nemesys-dive-1.mcap"'
    reader = make_reader(BytesIO(r.content), decoder_factories=[DecoderFactory()])
    got = Counter(ch.topic for _, ch, _, _ in reader.iter_decoded_messages())
    assert got["/nemesys/typed/status"] == len(rows)
    assert got["/nemesys/odom"] == len(rows) - 1 and "/nemesys/fix" not in got  # no datum
    assert got["/nemesys/console/commands"] == len(commands) >= 1
    # the console's datum places the fixes when the log has none
    console.datum = Datum(43.0, 5.0)
    r = client.get("/api/dives/1/export.mcap")
    reader = make_reader(BytesIO(r.content), decoder_factories=[DecoderFactory()])
    got = Counter(ch.topic for _, ch, _, _ in reader.iter_decoded_messages())
    assert got["/nemesys/fix"] == len(rows) - 1


def test_exporting_a_dive_that_does_not_exist_is_404_naming_it(
    make_light_client: MakeLightClient, log_backend: LogBackend
) -> None:
    client = make_light_client(**log_backend.settings())
    r = client.get("/api/dives/99/export.mcap")
    assert r.status_code == 404 and r.json() == {"detail": "no dive 99"}
    r = client.get("/api/dives/0/export.mcap")
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["path", "dive"]
