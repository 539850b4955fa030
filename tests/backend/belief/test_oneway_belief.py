"""The belief on a one-way link (an in-memory modem: nothing comes back), through the API:
a circle (2 copies) superseded by a Surface after its first copy, the Surface's copies, then
a retry of the circle. ``belief.last_sent`` is the retried circle (its first copy left last),
``belief.command`` that circle with its own p(delivered) (nothing newer was sent), the Surface
the runner-up with p_s (1 - p_retry), and the rest the unknown state before them; the
position is assumed (no fix ever) and says what it assumed."""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient

from station.link import Capability
from tests.agent_link import AgentLink
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    MakeLightClient,
    advance,
    record,
)
from tests.manual_clock import ManualClock

#: Copies leave 2 s apart (the clock moves by hand), Surface repeats 1 s apart.
COPY_INTERVAL_S = 2.0
SURFACE_REPEAT_S = 1.0


def belief(client: TestClient) -> dict[str, Any]:
    r = client.get("/api/vehicle")
    assert r.status_code == 200, r.text
    out: dict[str, Any] = r.json()["belief"]
    return out


@pytest.fixture
def one_way(make_light_client: MakeLightClient) -> tuple[TestClient, ManualClock]:
    clock = ManualClock()
    client = make_light_client(
        AgentLink(Capability.NONE),
        clock=clock,
        copy_interval_s=COPY_INTERVAL_S,
        surface_repeat_s=SURFACE_REPEAT_S,
    )
    return client, clock


def test_circle_surface_retry(one_way: tuple[TestClient, ManualClock]) -> None:
    client, clock = one_way
    before = belief(client)
    assert before["last_sent"] is None and not before["two_way"]
    assert before["command"]["kind"] == "unknown" and before["command"]["p"] == 1.0
    assert before["position"]["source"] == "assumed" and before["position"]["sigma_m"] is None
    assert "origin" in before["position"]["basis"]

    r = client.post(
        "/api/commands", json={"pattern": "circle", "params": CIRCLE, "copies": 2}, headers=AUTH
    )
    assert r.status_code == 202, r.text
    circle = r.json()
    advance(client, clock, 0.0)  # the first copy leaves
    assert record(client, circle["id"])["copies_sent"] == 1
    surface = client.post("/api/surface", headers=AUTH).json()
    advance(client, clock, 30 * SURFACE_REPEAT_S)  # every Surface copy
    s = record(client, surface["id"])
    assert s["state"] == "sent", s
    assert record(client, circle["id"])["state"] == "superseded"
    assert belief(client)["surface"]["id"] == surface["id"]
    assert not belief(client)["surface"]["in_progress"]

    r = client.post(f"/api/commands/{circle['id']}/retry", json={}, headers=AUTH)
    assert r.status_code == 202, r.text
    retried = r.json()
    advance(client, clock, 30 * COPY_INTERVAL_S)
    retried = record(client, retried["id"])
    assert retried["state"] == "sent"
    c1 = record(client, circle["id"])

    b = belief(client)
    assert b["last_sent"] == {
        "id": retried["id"],
        "pattern": "circle",
        "params": retried["params"],
    }
    p_r, p_s, p_c = retried["p_delivered"], s["p_delivered"], c1["p_delivered"]
    command, runner_up = b["command"], b["runner_up"]
    assert command["kind"] == "command" and command["id"] == retried["id"]
    assert command["p"] == pytest.approx(p_r)
    assert runner_up["id"] == surface["id"] and runner_up["pattern"] == "surface"
    assert runner_up["p"] == pytest.approx(p_s * (1 - p_r))
    assert p_c * (1 - p_s) * (1 - p_r) < runner_up["p"]
    print(b)
