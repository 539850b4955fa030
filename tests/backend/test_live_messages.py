"""The /ws messages as models (backend/messages.py, backend/api/schemas/live.py): docs/live.md
is generated from them, every message on the wire validates against the documented JSON
Schema and parses as its model, a message always carries its type and no field it was not
given, and a command message is the mission log's row."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from jsonschema import Draft202012Validator
from pydantic import TypeAdapter, ValidationError

from backend.api.live_doc import DOC_PATH, REGENERATE, live_schema, render_markdown, write
from backend.api.schemas.live import (
    CLIENT_MESSAGE,
    CLIENT_TYPES,
    AuthMessage,
    ClientMessage,
    ErrorReply,
    LiveMessage,
    SendMessage,
    ServerMessage,
    SurfaceMessage,
    message_types,
)
from backend.messages import CommandMessage, News, TelemetryMessage, message_json
from backend.mission_log.records import command_record
from backend.mission_log.store import MissionLog
from tests.backend.conftest import AUTH, CIRCLE, TOKEN, WRONG_TOKEN, command_fields

ROOT = Path(__file__).resolve().parents[2]
#: Models whose shape is the vehicle's, open by design (fields outside the contract kept).
OPEN_MODELS = {"Ack", "VehicleStatus"}


def closed(schema: Any) -> Any:
    """The schema with every object that names its properties closed to others (a model's
    ``extra="allow"`` says ``additionalProperties: true`` and stays open), as
    tests/backend/test_openapi.py closes the OpenAPI's."""
    if isinstance(schema, list):
        return [closed(s) for s in schema]
    if not isinstance(schema, dict):
        return schema
    out = {k: closed(v) for k, v in schema.items()}
    if "properties" in out and "additionalProperties" not in out:
        out["additionalProperties"] = False
    return out


def validator() -> Draft202012Validator:
    schema = closed(live_schema())
    opened = {n for n, d in schema["$defs"].items() if d.get("additionalProperties") is True}
    assert opened == OPEN_MODELS
    return Draft202012Validator(schema)


# --- the document ---------------------------------------------------------------------------


def test_docs_live_md_is_generated_from_the_models(tmp_path: Path) -> None:
    committed = (ROOT / DOC_PATH).read_text(encoding="utf-8")
    assert committed == render_markdown(), f"docs/live.md is out of date: run {REGENERATE}"
    (tmp_path / "docs").mkdir()
    assert write(tmp_path).read_text(encoding="utf-8") == committed


def test_the_doc_lists_every_message_with_its_fields() -> None:
    doc = render_markdown()
    schema = live_schema()
    for kind in message_types(LiveMessage):
        assert f"### `{kind}` (" in doc, kind
        assert f"| `{kind}` |" in doc, kind
    for name in ("CommandMessage", "ErrorReply", "SendMessage"):
        for field in schema["$defs"][name]["properties"]:
            assert f"| `{field}` |" in doc, (name, field)
    assert "docs/live.md" in (ROOT / "docs" / "api.md").read_text(encoding="utf-8")


def test_the_union_is_every_message_once_discriminated_by_type() -> None:
    server, client = message_types(ServerMessage), message_types(ClientMessage)
    assert set(message_types(News)) <= set(server)
    assert client == CLIENT_TYPES == ("auth", "surface", "send")
    every = message_types(LiveMessage)
    assert len(every) == len(set(every)) == len(server) + len(client)
    assert set(every) == set(server) | set(client)
    schema = live_schema()
    assert schema["discriminator"]["propertyName"] == "type"
    assert set(schema["discriminator"]["mapping"]) == set(every)
    for ref in schema["discriminator"]["mapping"].values():
        target = schema["$defs"][ref.rsplit("/", 1)[1]]
        assert "type" in target["required"], ref  # always sent, default or not


# --- the models -----------------------------------------------------------------------------


def test_a_message_carries_its_type_and_only_the_fields_given() -> None:
    assert json.loads(message_json(ErrorReply(detail="not JSON"))) == {
        "type": "error",
        "detail": "not JSON",
    }
    given = ErrorReply(detail="radius: too small", field=None, status=422)
    assert json.loads(message_json(given)) == {
        "type": "error",
        "detail": "radius: too small",
        "field": None,
        "status": 422,
    }
    telemetry = TelemetryMessage.model_validate({"pose": None, "status": None, "age_s": None})
    assert json.loads(message_json(telemetry))["type"] == "telemetry"
    # what a page receives parses back as the model that was sent
    parsed = TypeAdapter(ServerMessage).validate_json(message_json(given))
    assert isinstance(parsed, ErrorReply) and parsed.status == 422


def test_a_command_message_is_the_log_row(tmp_path: Path) -> None:
    """The record a page gets is the row as written: the acknowledgement's fields the
    vehicle left out stay out, its extra ones stay in, ``from`` keeps its name."""
    log = MissionLog(tmp_path / "missions.sqlite3")
    try:
        dive = log.new_dive("sim")
        row = log.insert_command(dive, command_fields())
        ack = {
            "seq": 1,
            "outcome": "accepted",
            "reason": None,
            "from": {
                "x_m": 1.0,
                "y_m": 2.0,
                "z_m": 3.0,
                "heading_deg": 90.0,
                "speed_mps": 0.0,
                "t_s": 12.5,
                "segment": None,
            },
            "channel_flipped_bits": 0,
        }
        row = log.update_command(row["id"], state="acknowledged", ack=ack, two_way=True)
    finally:
        log.close()
    sent = json.loads(message_json(CommandMessage(command=command_record(row))))
    assert sent == {"type": "command", "command": row}
    assert set(sent["command"]["ack"]) == set(ack)
    assert not validator().is_valid({"type": "command", "command": {**row, "stray": 1}})
    assert validator().is_valid(sent)


def test_client_messages_parse_as_their_models() -> None:
    assert isinstance(CLIENT_MESSAGE.validate_python({"type": "surface"}), SurfaceMessage)
    auth = CLIENT_MESSAGE.validate_python({"type": "auth", "token": TOKEN})
    assert isinstance(auth, AuthMessage) and auth.token == TOKEN
    msg = {"type": "send", "pattern": "circle", "params": CIRCLE, "copies": 2}
    parsed = CLIENT_MESSAGE.validate_python(msg)
    assert isinstance(parsed, SendMessage) and parsed.copies == 2 and not parsed.override
    assert validator().is_valid(msg)


@pytest.mark.parametrize(
    ("msg", "where"),
    [
        ({"type": "send", "params": CIRCLE}, ("send", "pattern")),
        ({"type": "send", "pattern": "circle", "params": {"radius": True}}, ("params", "radius")),
        ({"type": "send", "pattern": "circle", "params": [1]}, ("send", "params")),
        ({"type": "send", "pattern": "circle", "override": 1}, ("send", "override")),
        ({"type": "send", "pattern": "circle", "copies": 21}, ("send", "copies")),
        ({"type": "send", "pattern": "circle", "speed": 0.1}, ("send", "speed")),
        ({"type": "auth", "token": 7}, ("auth", "token")),
    ],
)
def test_a_client_message_that_does_not_fit_names_the_field(
    msg: dict[str, Any], where: tuple[str, ...]
) -> None:
    with pytest.raises(ValidationError) as err:
        CLIENT_MESSAGE.validate_python(msg)
    loc = tuple(str(p) for p in err.value.errors()[0]["loc"])
    assert loc[-len(where) :] == where, loc


# --- the wire -------------------------------------------------------------------------------


@pytest.mark.slow  # a live session long enough for every message type
def test_every_message_on_the_wire_is_documented(client: TestClient) -> None:
    """A session that sees every server message: each validates against docs/live.md's
    schema (closed objects: no field the document does not name) and parses as its model."""
    check, server = validator(), TypeAdapter(ServerMessage)
    seen: dict[str, dict[str, Any]] = {}

    def receive(ws: Any, until: str, timeout_s: float = 10.0) -> dict[str, Any]:
        """Messages up to the first of type ``until`` (seen before: at once)."""
        deadline = time.monotonic() + timeout_s
        while until not in seen:
            msg: dict[str, Any] = ws.receive_json()
            problems = [e.message[:200] for e in check.iter_errors(msg)]
            assert not problems, (msg["type"], problems)
            server.validate_python(msg)
            seen.setdefault(msg["type"], msg)
            assert time.monotonic() < deadline, f"no {until}; got {sorted(seen)}"
        return seen[until]

    with client.websocket_connect("/ws") as ws:
        ws.send_text(json.dumps({"type": "auth", "token": WRONG_TOKEN}))
        receive(ws, "auth_refused")
        ws.send_text(json.dumps({"type": "auth", "token": TOKEN}))
        receive(ws, "auth_ok")
        ws.send_text(json.dumps({"type": "send", "pattern": "circle", "params": {"radius": 0}}))
        receive(ws, "error")
        ws.send_text(json.dumps({"type": "send", "pattern": "circle", "params": CIRCLE}))
        queued = receive(ws, "queued")
        assert queued["command"]["origin"] == "ws"
        receive(ws, "command")  # its states
        receive(ws, "vehicle")  # its acknowledgement's echo
        receive(ws, "active_path")  # the path the vehicle now flies
        put = client.put("/api/datum", json={"lat_deg": 29.53, "lon_deg": -82.3}, headers=AUTH)
        assert put.status_code == 200, put.text
        assert receive(ws, "event")["event"]["kind"] == "datum"
        receive(ws, "link")  # every second
        took = client.post("/api/control", json={"action": "request"}, headers=AUTH)
        assert took.status_code == 200, took.text
        assert receive(ws, "control")["control"]["vehicle"] == "nemesys"
    # a fleet's telemetry: checked against the document by tests/backend/fleet's console test
    assert set(seen) == set(message_types(ServerMessage)) - {"fleet_telemetry"}
