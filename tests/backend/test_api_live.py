"""The live websocket /ws: telemetry at its rate, command states in order, and control that
needs the operator token while the connection stays open for watching."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from typing import Any

import pytest
from fastapi.testclient import TestClient
from starlette.testclient import WebSocketTestSession

from backend.api.live import MAX_CONTROL_BYTES
from backend.api.schemas.live import message_types
from backend.messages import News
from tests.backend.conftest import CIRCLE, TOKEN, WRONG_TOKEN, MakeClient, send

Message = dict[str, Any]


def receive_until(
    ws: WebSocketTestSession, done: Callable[[Message], bool], timeout_s: float = 5.0
) -> list[Message]:
    """Every message up to and including the first for which ``done`` is true. Telemetry
    arrives at 10 Hz, so the deadline is checked often."""
    deadline = time.monotonic() + timeout_s
    seen: list[Message] = []
    while True:
        msg: Message = ws.receive_json()
        seen.append(msg)
        if done(msg):
            return seen
        if time.monotonic() > deadline:
            kinds = [m["type"] for m in seen]
            raise AssertionError(f"timed out after {timeout_s} s; got {kinds[-20:]}")


#: The server's own messages, which may come between a control message and its answer.
NEWS = message_types(News)


def reply(ws: WebSocketTestSession, control: Message | str) -> Message:
    """Send a control message; its answer (the first message that is not news: telemetry,
    a command, the vehicle, its active path, the link or an event)."""
    ws.send_text(control if isinstance(control, str) else json.dumps(control))
    seen = receive_until(ws, lambda m: m["type"] not in NEWS)
    return seen[-1]


def is_telemetry(m: Message) -> bool:
    return bool(m["type"] == "telemetry")


def command_states(messages: list[Message], command_id: int) -> list[str]:
    return [
        m["command"]["state"]
        for m in messages
        if m["type"] == "command" and m["command"]["id"] == command_id
    ]


def test_telemetry_arrives_at_its_rate(make_client: MakeClient) -> None:
    client = make_client(telemetry_hz=10)
    with client.websocket_connect("/ws") as ws:
        start = time.monotonic()
        got: list[Message] = []
        while time.monotonic() - start < 1.0:
            got.append(ws.receive_json())
    telemetry = [m for m in got if is_telemetry(m)]
    assert 5 <= len(telemetry) <= 15, len(telemetry)  # 10 Hz, latest value wins
    for m in telemetry:
        assert set(m) == {"type", "pose", "status", "age_s", "dive"}
    posed = [m for m in telemetry if m["pose"] is not None]
    assert posed and posed[-1]["dive"] == 1  # the dive the first pose started
    assert {"t_s", "x_m", "y_m", "z_m", "heading_deg", "roll_deg"} <= set(posed[-1]["pose"])
    times = [m["pose"]["t_s"] for m in posed]
    assert times == sorted(times) and times[-1] > times[0]  # sim time runs (50x)
    with client.websocket_connect("/ws") as ws:
        status = receive_until(ws, lambda m: is_telemetry(m) and m["status"] is not None)[-1]
    assert {"mode", "depth_m", "battery_pct", "speed_mps", "t_s"} <= set(status["status"])
    assert status["age_s"] is not None and status["age_s"] >= 0


def test_command_states_arrive_in_order(client: TestClient) -> None:
    with client.websocket_connect("/ws") as ws:
        receive_until(ws, lambda m: is_telemetry(m) and m["pose"] is not None)
        cmd = send(client)
        seen = receive_until(
            ws, lambda m: m["type"] == "command" and m["command"]["state"] == "acknowledged"
        )
        assert command_states(seen, cmd["id"]) == ["queued", "transmitted", "acknowledged"]
        acked = [m for m in seen if m["type"] == "command"][-1]["command"]
        assert acked["ack"]["outcome"] == "accepted" and acked["attempts"] == 1
        news = receive_until(ws, lambda m: m["type"] == "vehicle")[-1]
        assert news["active"]["pattern"] == "circle"
        assert news["echo_mismatch"] is False


def test_every_client_gets_the_events(client: TestClient) -> None:
    with client.websocket_connect("/ws") as a, client.websocket_connect("/ws") as b:
        for ws in (a, b):
            receive_until(ws, is_telemetry)
        cmd = send(client)
        for ws in (a, b):
            seen = receive_until(
                ws, lambda m: m["type"] == "command" and m["command"]["state"] == "acknowledged"
            )
            assert command_states(seen, cmd["id"]) == ["queued", "transmitted", "acknowledged"]


@pytest.mark.parametrize(
    "control",
    [{"type": "surface"}, {"type": "send", "pattern": "circle", "params": CIRCLE}],
)
@pytest.mark.training
def test_control_without_auth_is_refused_and_the_socket_stays_open(
    client: TestClient, control: Message
) -> None:
    with client.websocket_connect("/ws") as ws:
        answer = reply(ws, control)
        assert answer["type"] == "error"
        assert answer["detail"].startswith("token required")
        receive_until(ws, is_telemetry)  # still watching
        receive_until(ws, is_telemetry)
        assert reply(ws, {"type": "surface"})["detail"].startswith("token required")
    assert client.get("/api/commands").json() == []


def test_wrong_token_is_refused(client: TestClient) -> None:
    with client.websocket_connect("/ws") as ws:
        for token in (WRONG_TOKEN, "", None, 42):
            answer = reply(ws, {"type": "auth", "token": token})
            assert answer == {"type": "auth_refused", "detail": "wrong operator token"}
        assert reply(ws, {"type": "surface"})["detail"].startswith("token required")
        receive_until(ws, is_telemetry)
    assert client.get("/api/commands").json() == []


def test_auth_then_surface_is_queued(client: TestClient) -> None:
    with client.websocket_connect("/ws") as ws:
        assert reply(ws, {"type": "auth", "token": TOKEN}) == {"type": "auth_ok"}
        answer = reply(ws, {"type": "surface"})
        assert answer["type"] == "queued"
        surface = answer["command"]
        assert surface["kind"] == "surface" and surface["state"] == "queued"
        seen = receive_until(
            ws,
            lambda m: (
                m["type"] == "command"
                and m["command"]["id"] == surface["id"]
                and m["command"]["state"] == "acknowledged"
            ),
        )
        assert command_states(seen, surface["id"])[-1] == "acknowledged"
    assert client.get(f"/api/commands/{surface['id']}").json()["state"] == "acknowledged"


@pytest.mark.training
def test_auth_then_send(client: TestClient) -> None:
    with client.websocket_connect("/ws") as ws:
        assert reply(ws, {"type": "auth", "token": TOKEN})["type"] == "auth_ok"
        answer = reply(ws, {"type": "send", "pattern": "circle", "params": CIRCLE})
        assert answer["type"] == "queued"
        assert answer["command"]["pattern"] == "circle" and answer["command"]["kind"] == "command"
        # refusals name what is wrong; nothing is queued
        too_fast = reply(
            ws, {"type": "send", "pattern": "circle", "params": {**CIRCLE, "speed": 1.5}}
        )
        assert too_fast["type"] == "error" and "speed" in too_fast["detail"]
        bad = reply(ws, {"type": "send", "pattern": "circle", "params": {**CIRCLE, "depth": 500}})
        assert bad["type"] == "error" and bad["field"] == "depth"
        plan = reply(ws, {"type": "send", "pattern": "circle", "params": {**CIRCLE, "radius": 0}})
        assert plan["type"] == "error" and plan["field"] == "radius"
        unknown = reply(ws, {"type": "send", "pattern": "figure8", "params": {}})
        assert unknown["type"] == "error" and "figure8" in unknown["detail"]
        shape = reply(ws, {"type": "send", "params": CIRCLE})
        assert shape["type"] == "error" and "pattern" in shape["detail"]
        shape = reply(ws, {"type": "send", "pattern": "circle", "params": [1]})
        assert shape["type"] == "error"
        boolean = reply(
            ws, {"type": "send", "pattern": "circle", "params": {**CIRCLE, "radius": True}}
        )
        assert boolean["type"] == "error" and boolean["field"] == "radius"
    assert len(client.get("/api/commands").json()) == 1


def test_ws_send_is_rate_limited_but_surface_is_not(make_client: MakeClient) -> None:
    client = make_client(max_sends_per_minute=1)
    with client.websocket_connect("/ws") as ws:
        assert reply(ws, {"type": "auth", "token": TOKEN})["type"] == "auth_ok"
        circle = {"type": "send", "pattern": "circle", "params": CIRCLE}
        assert reply(ws, circle)["type"] == "queued"
        limited = reply(ws, circle)
        assert limited["type"] == "error" and "at most 1" in limited["detail"]
        assert reply(ws, {"type": "surface"})["type"] == "queued"


@pytest.mark.parametrize(
    ("text", "detail"),
    [
        ("{not json", "not JSON"),
        ("[1, 2]", "expected a JSON object"),
        ('"auth"', "expected a JSON object"),
        (json.dumps({"type": "dance"}), "unknown message type 'dance'"),
        (json.dumps({"token": TOKEN}), "unknown message type None"),
        (
            json.dumps({"type": "auth", "token": TOKEN, "pad": "x" * MAX_CONTROL_BYTES}),
            f"message over {MAX_CONTROL_BYTES} bytes",
        ),
    ],
)
def test_bad_control_messages_are_errors_and_the_socket_stays_open(
    client: TestClient, text: str, detail: str
) -> None:
    with client.websocket_connect("/ws") as ws:
        answer = reply(ws, text)
        assert answer["type"] == "error"
        assert answer["detail"].startswith(detail), answer
        receive_until(ws, is_telemetry)
        # the oversized auth was not taken: still unauthenticated, then auth works
        assert reply(ws, {"type": "surface"})["detail"].startswith("token required")
        assert reply(ws, {"type": "auth", "token": TOKEN}) == {"type": "auth_ok"}


def test_a_binary_frame_is_an_error_and_the_socket_stays_open(client: TestClient) -> None:
    with client.websocket_connect("/ws") as ws:
        receive_until(ws, is_telemetry)
        ws.send_bytes(b'{"type": "surface"}')
        answer = receive_until(ws, lambda m: m["type"] not in NEWS)[-1]
        assert answer["type"] == "error"
        assert reply(ws, {"type": "auth", "token": TOKEN}) == {"type": "auth_ok"}
