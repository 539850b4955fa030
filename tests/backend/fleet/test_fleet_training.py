"""Training with a fleet of three (issue 23's test): the console on the fleet simulator (three
twins on one shared emulated ME link behind one rosbridge, ``sim.fleet``), each vehicle's
telemetry and acknowledgements under its namespace, every frame published once on the
station's transmitter topic.

A command to one vehicle changes only that one's active command; Surface to all surfaces all
three, each record ending ``acknowledged`` by its own vehicle; ``GET /api/training`` gives each
vehicle's receiver's counters (every frame reached all three) and their sums."""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient

from codec import decode_addressed_frame
from tests.backend.conftest import AUTH, CIRCLE, MakeClient, console_of, wait_state, wait_until

NAMES = ["auv1", "auv2", "auv3"]

pytestmark = pytest.mark.training


def vehicles(client: TestClient) -> dict[str, dict[str, Any]]:
    return {v["name"]: v for v in client.get("/api/vehicles").json()}


def ready(client: TestClient) -> bool:
    views = vehicles(client).values()
    return all(v["pose"] and v["link"]["acknowledges"] for v in views)


def test_training_with_three_vehicles(make_client: MakeClient) -> None:
    client = make_client(vehicles="3")
    wait_until(lambda: ready(client), timeout_s=30, what="three vehicles heard, two-way")
    console = console_of(client)
    assert console.fleet_sim is not None
    starts = {n: vehicles(client)[n]["pose"]["y_m"] for n in NAMES}
    assert len(set(starts.values())) == 3  # each its own twin, its own place

    body = {"pattern": "circle", "params": CIRCLE, "vehicle": "auv2"}
    r = client.post("/api/commands", json=body, headers=AUTH)
    assert r.status_code == 202, r.text
    done = wait_state(client, r.json()["id"], timeout_s=30)
    assert done["state"] == "acknowledged" and done["ack"]["address"] == 2
    wait_until(
        lambda: (vehicles(client)["auv2"]["status"] or {}).get("pattern") == "circle",
        timeout_s=30,
        what="auv2 flying its circle",
    )
    others = {n: vehicles(client)[n] for n in ("auv1", "auv3")}
    assert all(v["status"]["pattern"] != "circle" for v in others.values())
    assert all(v["active"] is None and v["last_sent"] is None for v in others.values())
    assert console.fleet_sim.sim("auv1").agent.active is None

    r = client.post("/api/surface", json={"vehicle": "all"}, headers=AUTH)
    assert r.status_code == 202, r.text
    records = r.json()["commands"]
    assert [c["vehicle"] for c in records] == NAMES
    assert decode_addressed_frame(records[0]["hex"]).address == 0
    ended = [wait_state(client, c["id"], timeout_s=30) for c in records]
    assert [c["state"] for c in ended] == ["acknowledged"] * 3
    assert {c["ack"]["address"] for c in ended} == {0}
    assert all(
        console.fleet_sim.sim(n).agent.active.pattern == "surface"  # type: ignore[union-attr]
        for n in NAMES
    )
    # the shared link's counters, each vehicle's receiver's: every frame reached all three
    training = client.get("/api/training").json()
    assert training["enabled"]
    each = training["vehicle_channel_stats"]
    assert [(v["vehicle"], v["address"]) for v in each] == [(n, i + 1) for i, n in enumerate(NAMES)]
    sent = console.fleet_sim.transmissions
    assert sent >= 2  # the circle, Surface all
    for v in each:
        own = console.fleet_sim.sim(v["vehicle"]).channel.stats
        assert v["channel_stats"]["frames_in"] == own.frames_in == sent
        assert v["channel_stats"]["bits_sent"] == own.bits_sent
    totals = training["channel_stats"]
    for counter, total in totals.items():
        assert total == sum(v["channel_stats"][counter] for v in each), counter
    assert totals["frames_in"] == 3 * sent
