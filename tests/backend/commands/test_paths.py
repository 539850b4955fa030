"""Every path a frame can leave the console by goes through the command service: a hard
violation is refused with nothing transmitted (the bytes at a one-way TCP modem; the training
vehicle's acknowledgements), a soft one needs the override and the override is recorded, and
the record names the path it came by.

The paths and their tests (the scripts' and ``nemesys send``'s are in
tests/backend/scripts/test_checks.py and tests/cli/test_cli_send.py):

==================  ====================================================================
REST send           test_rest_send_*
/ws send            test_ws_send_*
Surface (REST, ws)  test_surface_paths_are_recorded_and_never_refused
retry               test_retry_is_checked_like_a_send
training scenario   test_a_scenario_whose_first_command_breaks_a_limit_sends_nothing
==================  ====================================================================
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterator
from typing import Any

import pytest
from fastapi.testclient import TestClient
from starlette.testclient import WebSocketTestSession

from bench._gateway import FrameGateway
from tests.backend.conftest import AUTH, TOKEN, MakeClient, console_of, wait_until
from tests.backend.test_api_live import reply

#: Beyond the 100 m depth rating: no operator can override it.
DEEP = {"speed": 0.18, "depth": 105, "duration": 40, "heading": 90}
#: Above the vehicle's top speed (0.19 m/s in these tests): the operator may override it.
FAST = {"speed": 0.5, "depth": 2, "duration": 40, "heading": 90}
OK = {"speed": 0.18, "depth": 2, "duration": 40, "heading": 90}


@pytest.fixture
def modem() -> Iterator[FrameGateway]:
    gateway = FrameGateway()
    try:
        yield gateway
    finally:
        gateway.close()
        assert not gateway.rejected


@pytest.fixture
def oneway(make_client: MakeClient, modem: FrameGateway) -> TestClient:
    """A console on a one-way TCP modem, with the twin's top speed."""
    return make_client(target=modem.target, top_speed_mps=0.19)


def commands(client: TestClient) -> list[dict[str, Any]]:
    rows: list[dict[str, Any]] = client.get("/api/commands").json()
    return rows


def violations_of(body: dict[str, Any]) -> list[tuple[str, str]]:
    return [(v["param"], v["kind"]) for v in body["detail"]["violations"]]


# --- REST --------------------------------------------------------------------------------------


def test_rest_send_refuses_hard_with_or_without_override(
    oneway: TestClient, modem: FrameGateway
) -> None:
    for override in (False, True):
        body = {"pattern": "straight", "params": DEEP, "override": override}
        r = oneway.post("/api/commands", json=body, headers=AUTH)
        assert r.status_code == 422, r.text
        assert ("depth", "hard") in violations_of(r.json())
    assert commands(oneway) == [] and modem.count() == 0


def test_rest_send_needs_the_override_and_records_it(
    oneway: TestClient, modem: FrameGateway
) -> None:
    r = oneway.post("/api/commands", json={"pattern": "straight", "params": FAST}, headers=AUTH)
    assert r.status_code == 409, r.text
    assert violations_of(r.json()) == [("speed", "soft")]
    assert commands(oneway) == [] and modem.count() == 0
    body = {"pattern": "straight", "params": FAST, "override": True}
    r = oneway.post("/api/commands", json=body, headers=AUTH)
    assert r.status_code == 202, r.text
    record = r.json()
    assert record["origin"] == "api" and record["overrides"]["violations"][0]["param"] == "speed"
    wait_until(lambda: modem.count(record["hex"]) >= 1, what="the frame at the modem")


# --- /ws ---------------------------------------------------------------------------------------


def authed(client: TestClient) -> Iterator[WebSocketTestSession]:
    with client.websocket_connect("/ws") as ws:
        assert reply(ws, {"type": "auth", "token": TOKEN})["type"] == "auth_ok"
        yield ws


def test_ws_send_refuses_hard_and_needs_the_override_for_soft(
    oneway: TestClient, modem: FrameGateway
) -> None:
    for ws in authed(oneway):
        for override in (False, True):
            msg = {"type": "send", "pattern": "straight", "params": DEEP, "override": override}
            answer = reply(ws, msg)
            assert answer["type"] == "error" and answer["status"] == 422, answer
            assert [(v["param"], v["kind"]) for v in answer["violations"]] == [("depth", "hard")]
        answer = reply(ws, {"type": "send", "pattern": "straight", "params": FAST})
        assert answer["type"] == "error" and answer["status"] == 409, answer
        assert commands(oneway) == [] and modem.count() == 0
        bad = reply(ws, {"type": "send", "pattern": "straight", "params": FAST, "override": 1})
        assert bad["status"] == 422 and bad["field"] == "override"
        msg = {"type": "send", "pattern": "straight", "params": FAST, "override": True}
        answer = reply(ws, msg)
        assert answer["type"] == "queued", answer
        record = answer["command"]
        assert record["origin"] == "ws" and record["overrides"]["by"]
    wait_until(lambda: modem.count(record["hex"]) >= 1, what="the frame at the modem")


def test_ws_send_answers_503_when_the_log_cannot_be_written(
    oneway: TestClient, modem: FrameGateway
) -> None:
    console = console_of(oneway)
    assert console.log is not None
    console.log._db.execute("PRAGMA query_only = ON")  # every write now fails
    try:
        for ws in authed(oneway):
            answer = reply(ws, {"type": "send", "pattern": "straight", "params": OK})
            assert answer["type"] == "error" and answer["status"] == 503, answer
            assert "mission log cannot be written" in answer["detail"]
    finally:
        console.log._db.execute("PRAGMA query_only = OFF")
    assert commands(oneway) == [] and modem.count() == 0


# --- Surface -----------------------------------------------------------------------------------


def test_surface_paths_are_recorded_and_never_refused(
    make_client: MakeClient, modem: FrameGateway
) -> None:
    # a depth limit the surface frame cannot break, a rate limit it ignores
    client = make_client(target=modem.target, max_depth_m=1, max_sends_per_minute=1)
    r = client.post("/api/surface", headers=AUTH)
    assert r.status_code == 202 and r.json()["origin"] == "surface"
    wait_until(lambda: r.json()["hex"] and modem.count(r.json()["hex"]) >= 1, what="surface")
    for ws in authed(client):
        answer = reply(ws, {"type": "surface"})
        assert answer["type"] == "queued" and answer["command"]["kind"] == "surface"
    body = {"pattern": "surface", "params": {}}
    r = client.post("/api/commands", json=body, headers=AUTH)
    assert r.status_code == 202 and r.json()["kind"] == "surface"


# --- retry -------------------------------------------------------------------------------------


def test_retry_is_checked_like_a_send(make_client: MakeClient, modem: FrameGateway) -> None:
    """A command sent within the limits of the moment, interrupted, then retried once the
    limits are tighter (the vehicle profile or limits now rule): refused as a send would be."""
    client = make_client(target=modem.target, top_speed_mps=0.19)
    r = client.post("/api/commands", json={"pattern": "straight", "params": OK}, headers=AUTH)
    first = r.json()
    wait_until(lambda: commands(client)[0]["state"] == "sent", what="sent")
    console = console_of(client)
    assert console.log is not None
    console.log.update_command(first["id"], state="interrupted")
    console.profile = dataclasses.replace(console.profile, top_speed_mps=0.1)
    r = client.post(f"/api/commands/{first['id']}/retry", headers=AUTH)
    assert r.status_code == 409 and violations_of(r.json()) == [("speed", "soft")], r.text
    assert len(commands(client)) == 1
    r = client.post(f"/api/commands/{first['id']}/retry", json={"override": True}, headers=AUTH)
    assert r.status_code == 202, r.text
    retried = r.json()
    assert retried["retry_of"] == first["id"] and retried["id"] != first["id"]
    assert retried["origin"] == "retry" and retried["overrides"]["violations"]
    assert json.dumps(first["params"]) == json.dumps(retried["params"])


# --- training scenario -------------------------------------------------------------------------


def test_a_scenario_whose_first_command_breaks_a_limit_sends_nothing(
    make_client: MakeClient,
) -> None:
    """The training vehicle's acknowledgements say nothing arrived: the scenario's first
    command (the paper's wreck inspection, deeper than 0.5 m) is refused by the depth limit."""
    client = make_client(max_depth_m=0.5)
    r = client.post("/api/training/scenario/wreck", headers=AUTH)
    assert r.status_code == 409, r.text
    assert ("depth", "soft") in violations_of(r.json())
    assert commands(client) == []
    console = console_of(client)
    assert console.commands is not None and console.commands.ledger.totals().dive.frames == 0
