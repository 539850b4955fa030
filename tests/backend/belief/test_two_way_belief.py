"""The belief on a two-way link (the light app's in-memory vehicle running the onboard agent):
``p`` is 1 or 0, with the reason in words, from the acknowledgement and the status echo."""

from __future__ import annotations

import time
from typing import Any

from fastapi.testclient import TestClient

from tests.agent_link import AgentLink
from tests.backend.conftest import (
    CIRCLE,
    MakeLightClient,
    advance,
    console_of,
    record,
    send,
    wait_state,
    wait_until,
)
from tests.manual_clock import ManualClock


def belief(client: TestClient) -> dict[str, Any]:
    out: dict[str, Any] = client.get("/api/vehicle").json()["belief"]
    return out


def test_acknowledged_command_is_believed_with_p_1(client: TestClient) -> None:
    b = belief(client)
    assert b["two_way"] and b["command"]["kind"] == "last_known"
    assert b["command"]["pattern"] is None and b["command"]["p"] == 1.0  # holding, as reported
    assert b["position"]["source"] in ("telemetry", "dead_reckoning")
    cmd = wait_state(client, send(client)["id"])
    assert cmd["state"] == "acknowledged"
    b = wait_until(lambda: (x := belief(client))["command"]["id"] == cmd["id"] and x)
    assert b["command"]["p"] == 1.0 and b["command"]["pattern"] == "circle"
    assert "acknowledg" in b["command"]["reason"]
    assert b["runner_up"] is None
    assert b["last_sent"]["id"] == cmd["id"]


def test_a_command_on_its_way_is_the_runner_up_with_p_0(
    make_light_client: MakeLightClient,
) -> None:
    clock, link = ManualClock(), AgentLink()
    client = make_light_client(link, clock=clock)
    first = send(client)
    advance(client, clock, 0.0)
    wait_state(client, first["id"], ("acknowledged",))
    link.answer = False  # the next acknowledgement is lost
    second = send(client, "circle", {**CIRCLE, "radius": 7})
    advance(client, clock, 0.0)
    assert record(client, second["id"])["state"] == "transmitted"
    b = belief(client)
    assert b["command"]["id"] == first["id"] and b["command"]["p"] == 1.0
    assert b["runner_up"]["id"] == second["id"] and b["runner_up"]["p"] == 0.0
    assert b["runner_up"]["reason"] == "on its way: not acknowledged yet"
    assert b["last_sent"]["id"] == second["id"]
    assert console_of(client).beliefs is not None


def test_a_change_is_pushed_as_a_belief_message(client: TestClient) -> None:
    with client.websocket_connect("/ws") as ws:
        cmd = send(client)
        deadline = time.monotonic() + 10.0
        while True:
            msg: dict[str, Any] = ws.receive_json()
            b = msg.get("belief") if msg["type"] == "belief" else None
            if b is not None and b["command"]["id"] == cmd["id"]:
                break
            assert time.monotonic() < deadline, "no belief naming the new command"
    assert b["last_sent"]["id"] == cmd["id"] and b["command"]["p"] == 1.0
    assert b["seq"] >= 1
    assert client.get("/api/vehicle").json()["belief"]["seq"] >= b["seq"]
