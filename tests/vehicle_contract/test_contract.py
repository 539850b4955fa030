"""The vehicle contract: its schemas are valid draft 2020-12, the simulator's real messages
(every outcome it can produce) validate, the console's parsing copes with everything the
schemas accept, a message missing a required field fails naming it, ``nemesys contract``
prints it, and ``docs/vehicle.md`` is generated from it."""

from __future__ import annotations

import asyncio
import copy
import io
import json
import re
from pathlib import Path
from typing import Any

import pytest
from jsonschema import Draft202012Validator

from backend.commands.manager import CommandManager
from backend.commands.mirror import VehicleMirror
from backend.messages import message_json
from backend.mission_log.store import MissionLog
from backend.telemetry import TelemetryHub
from cli.main import main
from codec import Encoded, Frame, encode_frame
from onboard.agent import command_json
from planner import Limits
from rosbridge.protocol import TOPIC_TYPES, same_type
from sim.simulation import SimConfig, Simulation
from station.link import Capability, Link
from tests.manual_clock import ManualClock
from tests.onboard.test_agent import REJECTS
from vehicle_contract import codes, contract, payloads
from vehicle_contract.doc import DOC_PATH, REGENERATE, render_markdown
from vehicle_contract.messages import STATUS_NUMBERS, status_from_message

ROOT = Path(__file__).resolve().parents[2]
CIRCLE = encode_frame("circle", speed=0.2, depth=2, radius=3, direction="cw")
HOVER = encode_frame("hover", duration=60, depth=2, heading=90)
SURFACE = encode_frame("surface", {})
STATE = {
    "x_m": 1.5,
    "y_m": -2.0,
    "z_m": 2.0,
    "heading_deg": 90.0,
    "speed_mps": 0.2,
    "t_s": 12.5,
    "segment": None,
}


# --- the contract itself ------------------------------------------------------------------


@pytest.mark.parametrize("name", ["ack", "status", "datum"])
def test_the_schemas_are_valid_draft_2020_12(name: str) -> None:
    schema = payloads.SCHEMAS[name]
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    Draft202012Validator.check_schema(schema)


def test_the_required_fields_are_what_the_console_reads() -> None:
    assert set(payloads.ACK_SCHEMA["required"]) == {
        "outcome", "frame_hex", "reason", "detail", "command", "duplicate", "active", "from",
        "t_s",
    }  # fmt: skip
    assert set(payloads.STATUS_SCHEMA["required"]) == {
        "t_s", "depth_m", "heading_deg", "speed_mps", "battery_pct", "mode", "pattern",
    }  # fmt: skip
    # every status number the console reads may be null (NaN through rosbridge)
    properties = payloads.STATUS_SCHEMA["properties"]
    for key in STATUS_NUMBERS:
        assert "null" in properties[key]["type"], key


def test_the_contract_topics_are_the_bridges() -> None:
    assert set(contract.TOPIC_TYPES) == set(TOPIC_TYPES)
    for name, type_name in contract.TOPIC_TYPES.items():
        assert same_type(type_name, TOPIC_TYPES[name]), name
        assert re.fullmatch(r"\w+/msg/\w+", type_name), "the ROS 2 spelling"


def test_nemesys_contract_prints_the_contract_as_json() -> None:
    out = io.StringIO()
    assert main(["contract"], out=out) == 0
    doc = json.loads(out.getvalue())
    assert {"version", "topics", "schemas"} <= set(doc)
    assert re.fullmatch(r"\d+\.\d+\.\d+", doc["version"])
    assert doc["version"] == contract.CONTRACT_VERSION
    assert set(doc["schemas"]) == {"ack", "status", "datum"}
    assert doc["schemas"]["status"] == payloads.STATUS_SCHEMA
    assert [t["name"] for t in doc["topics"]] == [t.name for t in contract.TOPICS]
    assert doc == contract.contract_json()


def test_contract_json_is_a_copy() -> None:
    doc = contract.contract_json()
    doc["schemas"]["ack"]["required"].clear()
    assert payloads.ACK_SCHEMA["required"]


def test_docs_vehicle_md_is_generated_from_the_contract() -> None:
    committed = (ROOT / DOC_PATH).read_text(encoding="utf-8")
    assert committed == render_markdown(), f"docs/vehicle.md is out of date: run {REGENERATE}"
    out = io.StringIO()
    assert main(["contract", "--markdown"], out=out) == 0
    assert out.getvalue() == committed


def test_the_doc_lists_the_topics_the_schemas_and_their_required_fields() -> None:
    doc = render_markdown()
    assert f"**Version {contract.CONTRACT_VERSION}.**" in doc
    for t in contract.TOPICS:
        assert f"| `{t.name}` | `{t.type}` |" in doc
    for name, schema in payloads.SCHEMAS.items():
        listed = ", ".join(f"`{f}`" for f in schema["required"])
        assert f"Required fields (the console reads them): {listed}." in doc, name
        assert f'"$id": "{schema["$id"]}"' in doc
    assert doc.count("```json") == len(payloads.SCHEMAS)


# --- the simulator's real messages --------------------------------------------------------


def _run(sim: Simulation, data: bytes) -> dict[str, Any]:
    sim.submit_frame(data)
    sim.advance(0.3)
    acks = sim.take_missions()
    assert len(acks) == 1, acks
    return acks[0]


def _bytes(bits: int) -> bytes:
    return Frame(bits).to_bytes()


def test_every_real_simulator_message_validates() -> None:
    sim = Simulation(SimConfig(seed=3, limits=Limits(max_depth_m=10.0)))
    statuses = [sim.status()]
    assert statuses[0]["active"] is None
    acks = [_run(sim, CIRCLE.frame.to_bytes())]
    assert acks[0]["outcome"] == "accepted" and acks[0]["from"] is not None
    sim.advance(5.0)
    statuses.append(sim.status())
    assert statuses[-1]["active"] == command_json(CIRCLE.command)
    acks.append(_run(sim, CIRCLE.frame.to_bytes()))
    assert acks[-1]["duplicate"] is True and acks[-1]["from"] is None
    reasons = set()
    for make, reason, _ in REJECTS.values():
        bits = make()
        ack = _run(sim, b"\x00" * 12 if bits is None else _bytes(bits))
        assert ack["outcome"] == "rejected" and ack["reason"] == reason
        reasons.add(reason)
        acks.append(ack)
    # every reason the contract names but no_navigation (the simulator always knows where it is)
    # and other_vehicle (a vehicle with an address only: tests/onboard/test_agent_address.py)
    assert reasons == set(codes.REJECT_REASONS) - {codes.NO_NAVIGATION, codes.OTHER_VEHICLE}
    acks.append(_run(sim, HOVER.frame.to_bytes()))
    acks.append(_run(sim, SURFACE.frame.to_bytes()))
    for _ in range(40):
        sim.advance(2.0)
        statuses.append(sim.status())
    modes = {s["mode"] for s in statuses}
    assert {"idle", "running", "surfacing", "surfaced"} <= modes
    empty = Simulation(SimConfig(battery_start_h=100.0))
    empty.advance(0.5)
    statuses.append(empty.status())
    assert statuses[-1]["mode"] == "battery_empty"
    for ack in acks:
        assert "channel_flipped_bits" in ack or ack["frame_hex"] is None
        assert payloads.validate_ack(json.loads(json.dumps(ack))) == [], ack
    for status in statuses:
        assert payloads.validate_status(json.loads(json.dumps(status))) == [], status


# --- what the schemas accept, the console copes with --------------------------------------

STATUS_EXAMPLES: dict[str, dict[str, Any]] = {
    "required only, every number null": {
        "t_s": None,
        "depth_m": None,
        "heading_deg": None,
        "speed_mps": None,
        "battery_pct": None,
        "mode": "idle",
        "pattern": None,
    },
    "numbers at their bounds, an active command": {
        "t_s": 1.7e9,
        "x_m": -1e4,
        "y_m": None,
        "depth_m": 0,
        "heading_deg": 359.99,
        "speed_mps": 0,
        "battery_pct": 0,
        "mode": "running",
        "pattern": "circle",
        "active": command_json(CIRCLE.command),
    },
    "active null, a link with nulls, fields of a later version": {
        "t_s": 3,
        "depth_m": 2.5,
        "heading_deg": -10,
        "speed_mps": 0.4,
        "battery_pct": 100,
        "mode": "battery_empty",
        "pattern": "surface",
        "active": None,
        "link": {"last_frame_t_s": None, "distance_m": None, "in_range": True},
        "contract": "1.1.0",
        "water_temp_c": 11.5,
    },
}


@pytest.mark.parametrize("name", list(STATUS_EXAMPLES))
def test_the_console_reads_every_status_the_schema_accepts(name: str) -> None:
    msg = STATUS_EXAMPLES[name]
    assert payloads.validate_status(msg) == []
    status, unknown = status_from_message(json.loads(json.dumps(msg)))
    for key in STATUS_NUMBERS:
        assert status[key] is None or isinstance(status[key], float)
    assert unknown == sum(msg.get(k) is None for k in STATUS_NUMBERS)
    hub = TelemetryHub()
    hub.set_status(msg)
    json.loads(message_json(hub.telemetry()))  # the page's telemetry message
    mirror = VehicleMirror(hub, dive=lambda: 1)
    mirror.accepted = {"id": 1, "dive": 1, "pattern": "hover", "params": {}, "ack": {"t_s": None}}
    assert isinstance(mirror.echo_mismatch, bool)


def _ack(**fields: Any) -> dict[str, Any]:
    """An acknowledgement of CIRCLE with only the required fields, then ``fields``."""
    base = {
        "t_s": None,
        "outcome": "accepted",
        "frame_hex": CIRCLE.frame.hex,
        "reason": None,
        "detail": "",
        "command": command_json(CIRCLE.command),
        "duplicate": False,
        "active": command_json(CIRCLE.command),
        "from": dict(STATE),
    }
    return {**base, **fields}


ACK_EXAMPLES: dict[str, dict[str, Any]] = {
    "accepted, required fields only": _ack(),
    "a duplicate: 13-byte upper-case frame_hex, from null": _ack(
        frame_hex=CIRCLE.frame.to_bytes().hex().upper(), duplicate=True, **{"from": None}
    ),
    "not a frame at all": _ack(
        outcome="rejected",
        frame_hex=None,
        reason="malformed",
        command=None,
        active=None,
        t_s=0,
        **{"from": None},
    ),
    "refused after decoding, another frame_hex": _ack(
        outcome="rejected",
        frame_hex=HOVER.frame.hex,
        reason="limit_violation",
        detail="speed 1.5 m/s is above 1 m/s",
        field="speed",
        active=command_json(SURFACE.command),
        **{"from": None},
    ),
    "from at ROS epoch time, fields of a later version": _ack(
        seq=7,
        corrected_bits=None,
        sync_errors=0,
        decode_latency_ms=None,
        waypoints=0,
        vendor={"note": "extra"},
        **{"from": {**STATE, "t_s": 1.7e9, "z_m": 0, "segment": 0}},
    ),
}


class _TwoWay(Link):
    def __init__(self) -> None:
        super().__init__("fake://vehicle")
        self.capability = Capability.ACKS_AND_TELEMETRY
        self.frames: list[Frame] = []

    @property
    def connected(self) -> bool:
        return True

    async def transmit(self, frame: Frame) -> str | None:
        self.frames.append(frame)
        return None


async def _console_takes(ack: dict[str, Any], enc: Encoded, db: Path) -> dict[str, Any]:
    """Send ``enc`` through a console command manager, hand it ``ack``; the record after."""
    log = MissionLog(db)
    dive = log.new_dive("fake")
    link = _TwoWay()
    clock = ManualClock()
    cm = CommandManager(
        log,
        link,
        TelemetryHub(),
        dive=lambda: dive,
        operator="op",
        ack_timeout_s=5.0,
        surface_repeat_s=0.05,
        max_sends_per_minute=100,
        clock=clock,
    )
    try:
        record = await cm.submit(enc)

        def transmitted() -> bool:  # the copy is out and written down: an answer is awaited
            now = log.command(record["id"])
            return bool(link.frames) and now is not None and now["state"] == "transmitted"

        await clock.advance_until(transmitted, within_s=0.0)
        cm.on_mission(copy.deepcopy(ack))
        assert isinstance(cm.echo_mismatch, bool)
        after = log.command(record["id"])
        assert after is not None
        return after
    finally:
        await cm.close()


@pytest.mark.parametrize("name", list(ACK_EXAMPLES))
def test_the_console_takes_every_acknowledgement_the_schema_accepts(
    name: str, tmp_path: Path
) -> None:
    ack = ACK_EXAMPLES[name]
    assert payloads.validate_ack(ack) == []
    record = asyncio.run(_console_takes(json.loads(json.dumps(ack)), CIRCLE, tmp_path / "m.db"))
    expected = "acknowledged" if ack["outcome"] == "accepted" else "rejected"
    assert record["state"] == expected, record


def test_the_console_mirrors_the_plan_of_an_acknowledgement_with_only_required_fields() -> None:
    mirror = VehicleMirror(TelemetryHub(), dive=lambda: 1)
    mirror.on_ack(ACK_EXAMPLES["accepted, required fields only"], None)
    assert mirror.plan is not None and mirror.plan.pattern == "circle"
    assert mirror.active == command_json(CIRCLE.command)


# --- what the schemas refuse --------------------------------------------------------------


def _valid(name: str) -> dict[str, Any]:
    sim = Simulation()
    if name == "status":
        return sim.status()
    return _run(sim, CIRCLE.frame.to_bytes())


@pytest.mark.parametrize(
    ("name", "field"),
    [("ack", f) for f in payloads.ACK_SCHEMA["required"]]
    + [("status", f) for f in payloads.STATUS_SCHEMA["required"]],
)
def test_a_missing_required_field_fails_naming_it(name: str, field: str) -> None:
    msg = _valid(name)
    validate = payloads.validate_ack if name == "ack" else payloads.validate_status
    assert validate(msg) == []
    del msg[field]
    assert validate(msg) == [f"'{field}' is a required property"]


@pytest.mark.parametrize(
    ("name", "change", "problem"),
    [
        ("status", {"depth_m": "2 m"}, "depth_m: '2 m' is not of type 'number', 'null'"),
        ("status", {"mode": "RUNNING"}, "mode: 'RUNNING' is not one of"),
        ("status", {"battery_pct": 101}, "battery_pct: 101 is greater than the maximum of 100"),
        ("status", {"active": {"pattern": "circle"}}, "active: 'pattern_id' is a required"),
        ("ack", {"outcome": "ok"}, "outcome: 'ok' is not one of ['accepted', 'rejected']"),
        ("ack", {"reason": "crc_mismatch"}, "reason: None was expected"),
        ("ack", {"frame_hex": "aaaa"}, "frame_hex: 'aaaa' does not match"),
        ("ack", {"duplicate": "no"}, "duplicate: 'no' is not of type 'boolean'"),
        ("ack", {"t_s": "now"}, "t_s: 'now' is not of type 'number', 'null'"),
    ],
)
def test_a_wrong_value_fails_naming_the_field(
    name: str, change: dict[str, Any], problem: str
) -> None:
    msg = {**_valid(name), **change}
    validate = payloads.validate_ack if name == "ack" else payloads.validate_status
    problems = validate(msg)
    assert any(p.startswith(problem) for p in problems), problems


def test_nested_problems_name_the_nested_field() -> None:
    ack = _valid("ack")
    ack["command"]["params"]["speed"] = 9
    del ack["from"]["x_m"]
    problems = payloads.validate_ack(ack)
    assert "command.params.speed: 9 is greater than the maximum of 2.55" in problems
    assert "from: 'x_m' is a required property" in problems
    status = {**_valid("status"), "active": 5}
    assert payloads.validate_status(status) == ["active: 5 is not of type 'object' or 'null'"]
