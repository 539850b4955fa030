"""The light app's in-memory vehicle (``tests/agent_link.py``) answers as the training vehicle
does: the same commands through both consoles end in the same states with the same
acknowledgements, so an API test on the light app tests what the simulator would show."""

from __future__ import annotations

from typing import Any

from fastapi.testclient import TestClient

from station.link import Capability
from tests.agent_link import AgentLink

from .conftest import (
    AUTH,
    CIRCLE,
    MakeClient,
    MakeLightClient,
    console_of,
    wait_state,
    wait_until,
)

#: (pattern, params, override): accepted, refused by the vehicle's limits, a Surface.
SENDS: list[tuple[str, dict[str, Any], bool]] = [
    ("circle", CIRCLE, False),
    ("circle", {**CIRCLE, "speed": 1.5}, True),
    ("hover", {"duration": 60, "depth": 2, "heading": 90}, False),
    ("surface", {}, False),
]


def outcome(client: TestClient, pattern: str, params: dict[str, Any], override: bool) -> Any:
    body = {"pattern": pattern, "params": params, "override": override}
    r = client.post("/api/commands", json=body, headers=AUTH)
    assert r.status_code == 202, r.text
    rec = wait_state(client, r.json()["id"])
    ack = rec["ack"] or {}
    answer = {k: ack.get(k) for k in ("outcome", "reason", "field", "frame_hex", "command")}
    return rec["state"], rec["hex"], rec["copies_sent"], answer


def test_the_light_app_answers_as_the_training_vehicle(
    make_client: MakeClient, make_light_client: MakeLightClient
) -> None:
    training, light = make_client(), make_light_client()
    wait_until(lambda: training.get("/api/vehicle").json()["pose"], what="the simulator's pose")
    assert light.get("/api/vehicle").json()["pose"] is not None  # reported at start
    for pattern, params, override in SENDS:
        seen = outcome(training, pattern, params, override)
        assert outcome(light, pattern, params, override) == seen, (pattern, params)
        assert seen[0] == ("rejected" if override else "acknowledged"), seen
    link = console_of(light).link
    assert isinstance(link, AgentLink) and link.acks and len(link.frames) == len(SENDS)


def test_a_one_way_agent_link_answers_nothing_and_commands_end_sent(
    make_light_client: MakeLightClient,
) -> None:
    link = AgentLink(Capability.NONE)
    client = make_light_client(link, link_ber=1e-3)
    r = client.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
    assert r.status_code == 202, r.text
    rec = wait_state(client, r.json()["id"])
    assert rec["state"] == "sent" and rec["ack"] is None and rec["two_way"] is False
    assert link.frames == [rec["hex"]] * rec["copies_sent"] and link.acks == []
    assert client.get("/api/vehicle").json()["pose"] is None  # a modem reports nothing
