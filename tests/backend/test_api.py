"""The console's REST API against docs/api.md: every endpoint and every error, on the
simulated vehicle (training mode, 50x) through the app's lifespan; one app per test."""

from __future__ import annotations

import csv
import io
import itertools
import json
import math
import socket
from typing import Any
from urllib.parse import parse_qs, urlsplit

import pytest
from fastapi.testclient import TestClient

from backend.mission_log.export import csv_rows
from codec import copies_for, decode_frame, delivery_probability, encode_frame
from tests.agent_link import AgentLink
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    SQUARE,
    TIME_SCALE,
    TOKEN,
    WRONG_AUTH,
    MakeClient,
    MakeLightClient,
    advance,
    console_of,
    loc_of,
    record,
    send,
    wait_state,
    wait_until,
)
from tests.manual_clock import ManualClock

PATTERNS = {
    "straight": 0,
    "square": 1,
    "lawnmower": 2,
    "circle": 3,
    "spiral": 4,
    "helix": 5,
    "hover": 6,
    "box_orbit": 7,
    "surface": 15,
}
#: Every /api path docs/api.md lists.
API_PATHS = {
    "/api/session",
    "/api/dictionary",
    "/api/preview",
    "/api/encode",
    "/api/decode",
    "/api/commands",
    "/api/commands/{command_id}",
    "/api/commands/{command_id}/retry",
    "/api/control",
    "/api/surface",
    "/api/log.csv",
    "/api/log.json",
    "/api/dives",
    "/api/dives/{dive}",
    "/api/dives/{dive}/replay",
    "/api/dives/{dive}/timeline",
    "/api/dives/{dive}/export.mcap",
    "/api/series",
    "/api/vehicle",
    "/api/link",
    "/api/link/test",
    "/api/training",
    "/api/training/channel",
    "/api/training/current",
    "/api/training/time_scale",
    "/api/training/reset",
    "/api/training/scenario/{name}",
    "/api/scripts/preview",
    "/api/survey/preview",
    "/api/scripts/export",
    "/api/scripts/run",
    "/api/scripts/run/next",
    "/api/scripts/run/stop",
    "/api/chart",
    "/api/datum",
    "/api/tiles/{z}/{x}/{y}",
    "/api/replay",
    "/api/replay/at",
    "/api/predict",
    "/api/vehicles",  # issue 23: every vehicle, and the one transmitter
    "/api/vehicles/{name}",
    "/api/transmitter",
}
SCRIPT: dict[str, Any] = {
    "format": "nemesys-mission-script",
    "version": 1,
    "name": "two steps",
    "steps": [
        {"pattern": "square", "params": SQUARE, "trigger": {"kind": "at", "t_s": 0}},
        {
            "pattern": "circle",
            "params": {"speed": 0.18, "depth": 2.5, "radius": 4, "direction": "ccw"},
            "trigger": {"kind": "at", "t_s": 20},
        },
    ],
}
ESTIMATE_KEYS = {"length_m", "duration_s", "depth_min_m", "depth_max_m", "battery_pct"}


def script_with(**changes: Any) -> dict[str, Any]:
    """A deep copy of SCRIPT with top-level changes."""
    doc: dict[str, Any] = json.loads(json.dumps(SCRIPT))
    doc.update(changes)
    return doc


def preview(client: TestClient, pattern: str, params: dict[str, Any]) -> Any:
    return client.post("/api/preview", json={"pattern": pattern, "params": params})


def first_pose(client: TestClient) -> dict[str, Any]:
    def probe() -> dict[str, Any] | None:
        pose: dict[str, Any] | None = client.get("/api/vehicle").json()["pose"]
        return pose

    return wait_until(probe, what="a pose from the vehicle")


def put_channel(client: TestClient, **values: float) -> None:
    r = client.put("/api/training/channel", json=values, headers=AUTH)
    assert r.status_code == 200, r.text


# --- session ------------------------------------------------------------------------------


@pytest.mark.training
def test_session_without_token_is_read_only(client: TestClient) -> None:
    s = client.get("/api/session").json()
    assert s["mode"] == "training"
    assert s["target"] == "sim"
    assert s["viewer_url"] is None  # viewer=False
    assert s["bitrate_bps"] == 36000
    assert s["operator"] == "operator"
    assert s["authenticated"] is False
    # the dive starts when the simulated vehicle is first heard (null until then)
    assert s["dive"] in (None, 1)
    wait_until(lambda: client.get("/api/session").json()["dive"] == 1, what="the first dive")


@pytest.mark.parametrize(
    ("headers", "authenticated"),
    [
        ({"Authorization": f"Bearer {TOKEN}"}, True),
        ({"Authorization": f"bearer {TOKEN}"}, True),
        ({"X-Nemesys-Token": TOKEN}, True),
        (WRONG_AUTH, False),
        ({"X-Nemesys-Token": "y" * 20}, False),
        ({"Authorization": f"Basic {TOKEN}"}, False),
    ],
)
def test_session_reflects_the_token_sent(
    client: TestClient, headers: dict[str, str], authenticated: bool
) -> None:
    assert client.get("/api/session", headers=headers).json()["authenticated"] is authenticated


def test_session_has_the_documented_version(client: TestClient) -> None:
    assert client.get("/api/session").json()["version"] == client.app.version  # type: ignore[attr-defined]


def test_viewer_port_page_and_session_url(make_client: MakeClient) -> None:
    client = make_client(viewer=True)
    url = client.get("/api/session").json()["viewer_url"]
    assert url is not None and url.startswith("/viewer/?")
    query = parse_qs(urlsplit(url).query, keep_blank_values=True)
    assert "hideViserLogo" in query
    ws = urlsplit(query["websocket"][0])
    assert ws.scheme == "ws" and ws.hostname == "testserver"  # the host the page was asked on
    assert ws.port is not None and ws.port > 0  # viewer_port 0: a free port was chosen
    with socket.create_connection(("127.0.0.1", ws.port), timeout=2.0):
        pass  # viser listens there, on loopback
    page = client.get("/viewer/")
    assert page.status_code == 200
    assert page.headers["content-type"].startswith("text/html")
    # the view is drawn on preview and replay without errors
    assert preview(client, "circle", CIRCLE).status_code == 200
    assert client.post("/api/dives/1/replay", headers=AUTH).status_code == 200


# --- dictionary ---------------------------------------------------------------------------


def test_dictionary_has_every_pattern_with_fields_and_units(client: TestClient) -> None:
    d = client.get("/api/dictionary").json()
    assert {p["name"]: p["id"] for p in d} == PATTERNS
    for p in d:
        assert {"id", "name", "label", "doc", "fields"} <= set(p)
        for f in p["fields"]:
            assert {"name", "label", "unit", "doc", "default", "kind", "error"} <= set(f), f
            if f["kind"] == "choice":
                assert f["choices"], f
            else:
                assert f["min"] <= f["default"] <= f["max"], f
                assert f["segments"], f
    fields = {p["name"]: {f["name"]: f for f in p["fields"]} for p in d}
    assert fields["surface"] == {}
    assert fields["circle"]["speed"]["unit"] == "m/s"
    assert fields["circle"]["depth"]["unit"] == "m"
    assert fields["circle"]["radius"]["unit"] == "m"
    assert set(fields["circle"]["direction"]["choices"]) == {"cw", "ccw"}
    assert fields["straight"]["duration"]["unit"] == "s"
    assert fields["straight"]["heading"]["unit"] == "deg"
    assert fields["circle"]["depth"]["max"] == 107.5


# --- preview ------------------------------------------------------------------------------


def test_preview_frame_snaps_and_sections(client: TestClient) -> None:
    r = preview(client, "circle", {**CIRCLE, "radius": 5.1})
    assert r.status_code == 200, r.text
    p = r.json()
    assert p["pattern"] == "circle" and p["pattern_id"] == 3
    assert p["requested"]["radius"] == 5.1
    assert p["params"]["radius"] == 5.0
    snaps = {s["field"]: s for s in p["snaps"]}
    assert snaps["radius"]["requested"] == 5.1
    assert snaps["radius"]["sent"] == 5.0
    assert snaps["radius"]["changed"] is True
    assert snaps["radius"]["unit"] == "m"
    assert snaps["speed"]["changed"] is False
    bits = p["bits"]
    assert len(bits) == 100 and set(bits) <= {"0", "1"}
    assert len(p["hex"]) == 25 and int(p["hex"], 16) == int(bits, 2)
    start = 0
    for sec in p["sections"]:
        assert sec["start"] == start, p["sections"]
        assert sec["bits"] == bits[start : start + sec["length"]]
        start += sec["length"]
    assert start == 100
    names = [s["name"] for s in p["sections"]]
    assert names[:3] == ["preamble", "delimiter", "pattern"]
    assert "radius" in names
    assert p["airtime_ms"] == pytest.approx(2.778, abs=1e-3)
    assert p["bitrate_bps"] == 36000
    assert decode_frame(bits).command.params == p["params"]


@pytest.mark.training
def test_preview_path_estimate_and_start(client: TestClient) -> None:
    p = preview(client, "circle", CIRCLE).json()
    path = p["path"]
    n = len(path["x_m"])
    assert n > 2
    assert len(path["y_m"]) == len(path["z_m"]) == len(path["t_s"]) == n
    assert 0 <= path["body_start"] < n
    assert path["repeats"] is True
    assert path["t_s"] == sorted(path["t_s"])
    assert max(path["z_m"]) == pytest.approx(3.0, abs=0.01)
    est = p["estimate"]
    assert set(est) >= ESTIMATE_KEYS, est
    assert est["length_m"] > 0 and est["duration_s"] > 0
    assert est["depth_max_m"] == pytest.approx(3.0)
    assert 0 < est["battery_pct"] < 100
    assert p["violations"] == []
    assert p["diff"] is None  # nothing active yet
    assert {"x_m", "y_m", "z_m", "heading_deg", "t_s"} <= set(p["from"])
    assert p["from"]["z_m"] == pytest.approx(2.0, abs=0.1)  # the simulator starts at 2 m
    # what sending it would do: the training vehicle answers, one copy, at the channel's BER 0
    assert (p["two_way"], p["copies"], p["p_delivered"]) == (True, 1, 1.0)


@pytest.mark.training
def test_preview_copies_follow_the_training_channel(client: TestClient) -> None:
    r = client.put("/api/training/channel", json={"ber": 0.02, "loss": 0.1}, headers=AUTH)
    assert r.status_code == 200, r.text
    p = preview(client, "circle", CIRCLE).json()
    assert p["copies"] == 1  # two-way: one copy unless the operator asks
    assert p["p_delivered"] == pytest.approx(delivery_probability(0.02, 1, loss=0.1))
    assert client.get("/api/vehicle").json()["link"]["ber"] == 0.02


def test_preview_estimate_has_the_documented_join_keys(client: TestClient) -> None:
    est = preview(client, "circle", CIRCLE).json()["estimate"]
    assert {"join_length_m", "join_duration_s"} <= set(est)


def test_preview_violation_names_speed(client: TestClient) -> None:
    p = preview(client, "circle", {**CIRCLE, "speed": 1.5}).json()
    (v,) = p["violations"]
    assert v["param"] == "speed"
    assert v["value"] == 1.5 and v["limit"] == 1.0 and v["unit"] == "m/s"
    assert v["overridable"] is True
    assert "speed" in v["message"]


def test_preview_diff_against_the_acknowledged_command(client: TestClient) -> None:
    first_pose(client)
    cmd = send(client, "circle", CIRCLE)
    assert wait_state(client, cmd["id"])["state"] == "acknowledged"
    diff = wait_until(
        lambda: preview(client, "circle", {**CIRCLE, "depth": 4}).json()["diff"],
        what="a diff against the mirrored plan",
    )
    assert diff["active"] == "circle"
    assert diff["changes"] == [{"param": "depth", "old": 3.0, "new": 4.0, "unit": "m"}]
    assert diff["pattern_changed"] is False
    same = preview(client, "circle", CIRCLE).json()["diff"]
    assert same["changes"] == []


@pytest.mark.parametrize(
    ("params", "field"),
    [
        ({**CIRCLE, "speed": 9}, "speed"),
        ({**CIRCLE, "depth": 200}, "depth"),
        ({**CIRCLE, "radius": 900}, "radius"),
        ({**CIRCLE, "radius": -1}, "radius"),
        ({**CIRCLE, "direction": "up"}, "direction"),
        ({**CIRCLE, "colour": 1}, "colour"),
    ],
)
@pytest.mark.parametrize("endpoint", ["/api/preview", "/api/encode"])
def test_out_of_range_is_422_naming_the_field(
    client: TestClient, endpoint: str, params: dict[str, Any], field: str
) -> None:
    r = client.post(endpoint, json={"pattern": "circle", "params": params})
    assert r.status_code == 422
    assert loc_of(r.json()) == ["body", "params", field]
    assert r.json()["detail"][0]["msg"]


@pytest.mark.parametrize("endpoint", ["/api/preview", "/api/encode"])
def test_unknown_pattern_is_422_at_pattern(client: TestClient, endpoint: str) -> None:
    r = client.post(endpoint, json={"pattern": "figure8", "params": {}})
    assert r.status_code == 422
    assert loc_of(r.json()) == ["body", "pattern"]
    assert "circle" in r.json()["detail"][0]["msg"]  # says what is known


def test_missing_params_are_422_naming_one(client: TestClient) -> None:
    r = preview(client, "circle", {"speed": 0.18, "depth": 3})
    assert r.status_code == 422
    loc = loc_of(r.json())
    assert loc[:2] == ["body", "params"] and loc[-1] in {"radius", "direction"}


@pytest.mark.parametrize(
    ("body", "loc"),
    [
        ({"pattern": "circle", "params": CIRCLE, "extra": 1}, ["body", "extra"]),
        ({"params": CIRCLE}, ["body", "pattern"]),
        ({"pattern": "", "params": CIRCLE}, ["body", "pattern"]),
        ({"pattern": "circle", "params": [1, 2]}, ["body", "params"]),
    ],
)
def test_malformed_bodies_are_422(client: TestClient, body: dict[str, Any], loc: list[Any]) -> None:
    r = client.post("/api/preview", json=body)
    assert r.status_code == 422
    assert loc_of(r.json()) == loc


def test_extra_keys_are_forbidden(client: TestClient) -> None:
    r = client.post("/api/preview", json={"pattern": "circle", "params": CIRCLE, "extra": 1})
    assert r.json()["detail"][0]["type"] == "extra_forbidden"


@pytest.mark.parametrize("value", [True, False])
def test_booleans_are_not_parameters(client: TestClient, value: bool) -> None:
    r = preview(client, "circle", {**CIRCLE, "radius": value})
    assert r.status_code == 422
    for error in r.json()["detail"]:
        assert error["loc"][:3] == ["body", "params", "radius"]


def test_plan_error_is_422_at_the_param(client: TestClient) -> None:
    r = preview(client, "circle", {**CIRCLE, "radius": 0})
    assert r.status_code == 422
    (error,) = r.json()["detail"]
    assert error["loc"] == ["body", "params", "radius"]
    assert error["type"] == "plan_error"
    assert "radius" in error["msg"]


# --- encode / decode ----------------------------------------------------------------------


def test_encode_is_the_frame_only(client: TestClient) -> None:
    r = client.post("/api/encode", json={"pattern": "circle", "params": {**CIRCLE, "radius": 5.1}})
    assert r.status_code == 200
    e = r.json()
    assert {
        "pattern",
        "pattern_id",
        "params",
        "requested",
        "snaps",
        "bits",
        "hex",
        "sections",
        "airtime_ms",
        "bitrate_bps",
    } <= set(e)
    assert "path" not in e and "estimate" not in e
    expected = encode_frame("circle", {**CIRCLE, "radius": 5.1}).frame
    assert e["bits"] == expected.bits and e["hex"] == expected.hex
    assert e["airtime_ms"] == pytest.approx(100 / 36000 * 1000)
    # surface has no parameters
    s = client.post("/api/encode", json={"pattern": "surface", "params": {}}).json()
    assert s["pattern_id"] == 15 and s["params"] == {}


def test_decode_good_frame_bits_and_hex(client: TestClient) -> None:
    frame = encode_frame("square", SQUARE).frame
    for text in (frame.bits, frame.hex, frame.hex.upper()):
        r = client.post("/api/decode", json={"frame": text})
        assert r.status_code == 200, r.text
        d = r.json()
        assert d["ok"] is True
        assert d["command"]["pattern"] == "square" and d["command"]["pattern_id"] == 1
        assert d["command"]["params"]["side_span"] == 6
        assert d["corrected"] == 0 and d["sync_errors"] == 0


def test_decode_corrects_two_flipped_codeword_bits(client: TestClient) -> None:
    bits = list(encode_frame("circle", CIRCLE).frame.bits)
    for i in (30, 60):  # in the speed and j5 fields, inside the BCH codeword
        bits[i] = "1" if bits[i] == "0" else "0"
    r = client.post("/api/decode", json={"frame": "".join(bits)})
    assert r.status_code == 200, r.text
    d = r.json()
    assert d["corrected"] == 2
    assert d["command"]["params"] == encode_frame("circle", CIRCLE).command.params


@pytest.mark.parametrize(
    ("frame", "reason"),
    [("zz", "malformed"), ("01" * 49, "malformed"), ("0" * 100, "no_sync")],
)
def test_decode_garbage_is_422_with_reason(client: TestClient, frame: str, reason: str) -> None:
    r = client.post("/api/decode", json={"frame": frame})
    assert r.status_code == 422
    detail = r.json()["detail"]
    assert detail["reason"] == reason
    assert detail["message"]
    assert "field" in detail


def test_decode_body_is_validated(client: TestClient) -> None:
    assert client.post("/api/decode", json={"frame": ""}).status_code == 422
    assert client.post("/api/decode", json={"frame": "0" * 201}).status_code == 422
    r = client.post("/api/decode", json={"frame": "0" * 100, "x": 1})
    assert r.status_code == 422 and loc_of(r.json()) == ["body", "x"]


# --- sending ------------------------------------------------------------------------------


def test_send_needs_the_token(client: TestClient) -> None:
    body = {"pattern": "circle", "params": CIRCLE}
    r = client.post("/api/commands", json=body)
    assert r.status_code == 401
    assert r.headers["www-authenticate"] == "Bearer"
    assert "token" in r.json()["detail"]
    r = client.post("/api/commands", json=body, headers=WRONG_AUTH)
    assert r.status_code == 403
    assert client.get("/api/commands").json() == []  # nothing logged
    r = client.post("/api/commands", json=body, headers={"X-Nemesys-Token": TOKEN})
    assert r.status_code == 202


def test_send_is_queued_then_acknowledged(client: TestClient) -> None:
    first_pose(client)
    queued = send(client, "circle", {**CIRCLE, "radius": 5.1})
    assert queued["state"] == "queued"
    assert queued["attempts"] == 0
    assert queued["kind"] == "command"
    assert queued["dive"] == 1
    assert queued["operator"] == "operator"
    assert queued["requested"]["radius"] == 5.1 and queued["params"]["radius"] == 5.0
    assert queued["hex"] == encode_frame("circle", {**CIRCLE, "radius": 5.1}).frame.hex
    assert queued["sent_at"] is None and queued["acked_at"] is None and queued["ack"] is None
    rec = wait_state(client, queued["id"])
    assert rec["state"] == "acknowledged", rec
    assert rec["attempts"] == 1
    assert rec["created_at"] <= rec["sent_at"] <= rec["acked_at"]
    assert rec["reason"] is None
    ack = rec["ack"]
    assert ack["outcome"] == "accepted"
    assert ack["corrected_bits"] == 0
    assert ack["decode_latency_ms"] >= 0 and ack["replan_latency_ms"] >= 0
    assert ack["frame_hex"] == rec["hex"]
    assert ack["command"]["params"] == rec["params"]
    assert {r["id"] for r in client.get("/api/commands").json()} == {rec["id"]}


def test_overridable_violation_is_409_without_override(client: TestClient) -> None:
    body = {"pattern": "circle", "params": {**CIRCLE, "speed": 1.5}}
    r = client.post("/api/commands", json=body, headers=AUTH)
    assert r.status_code == 409
    (v,) = r.json()["detail"]["violations"]
    assert v["param"] == "speed" and v["overridable"] is True
    assert "override" in r.json()["detail"]["message"]
    assert client.get("/api/commands").json() == []


def test_override_sends_and_the_vehicle_rejects(client: TestClient) -> None:
    first_pose(client)
    body = {"pattern": "circle", "params": {**CIRCLE, "speed": 1.5}, "override": True}
    r = client.post("/api/commands", json=body, headers=AUTH)
    assert r.status_code == 202, r.text
    rec = wait_state(client, r.json()["id"])
    assert rec["state"] == "rejected"
    assert rec["reason"].startswith("limit_violation")
    assert "speed" in rec["reason"]
    assert rec["ack"]["outcome"] == "rejected" and rec["ack"]["field"] == "speed"


def test_beyond_the_rating_is_422_even_with_override(client: TestClient) -> None:
    for override in (False, True):
        body = {"pattern": "circle", "params": {**CIRCLE, "depth": 105}, "override": override}
        r = client.post("/api/commands", json=body, headers=AUTH)
        assert r.status_code == 422, r.text
        (v,) = r.json()["detail"]["violations"]
        assert v["param"] == "depth" and v["overridable"] is False and v["limit"] == 100
    assert client.get("/api/commands").json() == []


def test_send_validation_errors_are_422(client: TestClient) -> None:
    r = client.post(
        "/api/commands",
        json={"pattern": "circle", "params": {**CIRCLE, "radius": 0}},
        headers=AUTH,
    )
    assert r.status_code == 422 and loc_of(r.json()) == ["body", "params", "radius"]
    r = client.post(
        "/api/commands", json={"pattern": "circle", "params": CIRCLE, "x": 1}, headers=AUTH
    )
    assert r.status_code == 422 and loc_of(r.json()) == ["body", "x"]
    assert client.get("/api/commands").json() == []


def test_rate_limit_429_with_retry_after_but_never_surface(make_client: MakeClient) -> None:
    client = make_client(max_sends_per_minute=3)
    first_pose(client)
    too_fast = {"pattern": "circle", "params": {**CIRCLE, "speed": 1.5}, "override": True}
    rejected = client.post("/api/commands", json=too_fast, headers=AUTH).json()
    assert wait_state(client, rejected["id"])["state"] == "rejected"
    for _ in range(2):
        send(client)
    r = client.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
    assert r.status_code == 429
    retry_after = int(r.headers["retry-after"])
    assert 1 <= retry_after <= 60
    assert "3" in r.json()["detail"] and "Surface" in r.json()["detail"]
    assert len(client.get("/api/commands").json()) == 3  # the refused one is not logged
    for _ in range(2):
        s = client.post("/api/surface", headers=AUTH)
        assert s.status_code == 202
        assert s.json()["kind"] == "surface"
    # a retry is a transmission too
    body = {"override": True}  # checked like a send: its speed needs the override again
    r = client.post(f"/api/commands/{rejected['id']}/retry", json=body, headers=AUTH)
    assert r.status_code == 429 and "retry-after" in r.headers


# --- the log ------------------------------------------------------------------------------


def test_commands_list_filters_and_order(client: TestClient) -> None:
    first_pose(client)
    a = send(client, "circle", CIRCLE)
    wait_state(client, a["id"])
    b = send(client, "square", SQUARE)
    wait_state(client, b["id"])
    r = client.post(
        "/api/commands",
        json={"pattern": "circle", "params": {**CIRCLE, "speed": 1.5}, "override": True},
        headers=AUTH,
    )
    c = wait_state(client, r.json()["id"])
    assert c["state"] == "rejected"
    rows = client.get("/api/commands").json()
    assert [x["id"] for x in rows] == [c["id"], b["id"], a["id"]]  # newest first
    acked = client.get("/api/commands", params={"state": "acknowledged"}).json()
    assert [x["id"] for x in acked] == [b["id"], a["id"]]
    circles = client.get("/api/commands", params={"pattern": "circle"}).json()
    assert [x["id"] for x in circles] == [c["id"], a["id"]]
    both = client.get("/api/commands", params={"pattern": "circle", "state": "rejected"}).json()
    assert [x["id"] for x in both] == [c["id"]]
    assert [x["id"] for x in client.get("/api/commands", params={"limit": 1}).json()] == [c["id"]]
    assert len(client.get("/api/commands", params={"limit": 1000}).json()) == 3
    assert len(client.get("/api/commands", params={"dive": 1}).json()) == 3
    assert client.get("/api/commands", params={"dive": 2}).json() == []
    assert client.get("/api/commands", params={"since": "9999"}).json() == []
    assert len(client.get("/api/commands", params={"until": "9999"}).json()) == 3
    since = client.get("/api/commands", params={"since": b["created_at"]}).json()
    assert [x["id"] for x in since] == [c["id"], b["id"]]
    assert client.get("/api/commands", params={"pattern": "hover"}).json() == []
    # the single vehicle's name stands for its records: all of them
    assert len(client.get("/api/commands", params={"vehicle": "nemesys"}).json()) == 3


@pytest.mark.parametrize(
    ("query", "name"),
    [
        ({"limit": 0}, "limit"),
        ({"limit": 1001}, "limit"),
        ({"limit": "many"}, "limit"),
        ({"state": "lost"}, "state"),
        ({"dive": 0}, "dive"),
        ({"pattern": "p" * 33}, "pattern"),
        ({"vehicle": "auv2"}, "vehicle"),  # no fleet: only the single vehicle, nemesys
    ],
)
def test_commands_list_bad_queries_are_422(
    client: TestClient, query: dict[str, Any], name: str
) -> None:
    r = client.get("/api/commands", params=query)
    assert r.status_code == 422
    assert loc_of(r.json()) == ["query", name]


@pytest.mark.training
def test_commands_filter_by_the_session_target(client: TestClient) -> None:
    cmd = send(client)
    assert cmd["target"] == client.get("/api/session").json()["target"]
    assert [x["id"] for x in client.get("/api/commands", params={"target": "sim"}).json()] == [
        cmd["id"]
    ]


def test_command_404(client: TestClient) -> None:
    r = client.get("/api/commands/999")
    assert r.status_code == 404
    assert "999" in r.json()["detail"]
    assert client.get("/api/commands/abc").status_code == 422


def test_log_csv_and_json(client: TestClient) -> None:
    first_pose(client)
    a = wait_state(client, send(client, "circle", CIRCLE)["id"])
    b = wait_state(client, send(client, "square", SQUARE)["id"])
    r = client.get("/api/log.csv")
    assert r.status_code == 200
    assert r.headers["content-type"].startswith("text/csv")
    assert r.headers["content-disposition"] == 'attachment; filename="nemesys-log.csv"'
    rows = list(csv.reader(io.StringIO(r.text)))
    header = next(iter(csv_rows([])))
    assert rows[0] == header
    assert [row[0] for row in rows[1:]] == [str(a["id"]), str(b["id"])]  # oldest first
    first = dict(zip(header, rows[1], strict=True))
    assert first["pattern"] == "circle"
    assert first["state"] == "acknowledged"
    assert json.loads(first["params"]) == a["params"]
    assert first["hex"] == a["hex"] and first["bits"] == a["bits"]
    assert first["corrected_bits"] == "0"
    assert float(first["decode_latency_ms"]) >= 0
    assert first["reason"] == ""
    only = list(csv.reader(io.StringIO(client.get("/api/log.csv?pattern=square").text)))
    assert [row[0] for row in only[1:]] == [str(b["id"])]

    j = client.get("/api/log.json")
    assert j.status_code == 200
    assert j.headers["content-disposition"] == 'attachment; filename="nemesys-log.json"'
    assert [x["id"] for x in j.json()] == [b["id"], a["id"]]
    assert j.json()[0]["ack"]["outcome"] == "accepted"
    assert client.get("/api/log.json?state=rejected").json() == []
    assert client.get("/api/log.json?limit=0").status_code == 422
    assert client.get("/api/log.csv?state=nope").status_code == 422


# --- retry --------------------------------------------------------------------------------


def test_retry_errors(client: TestClient) -> None:
    first_pose(client)
    assert client.post("/api/commands/999/retry", headers=AUTH).status_code == 404
    rec = wait_state(client, send(client)["id"])
    assert rec["state"] == "acknowledged"
    r = client.post(f"/api/commands/{rec['id']}/retry", headers=AUTH)
    assert r.status_code == 409
    assert "acknowledged" in r.json()["detail"]
    assert client.post(f"/api/commands/{rec['id']}/retry").status_code == 401
    assert client.post(f"/api/commands/{rec['id']}/retry", headers=WRONG_AUTH).status_code == 403


def test_retry_a_timed_out_command(make_client: MakeClient) -> None:
    client = make_client(ack_timeout_s=0.3)
    first_pose(client)
    put_channel(client, loss=1.0)
    cmd = send(client)
    rec = wait_state(client, cmd["id"])
    assert rec["state"] == "timed_out"
    assert rec["attempts"] == 1 and rec["sent_at"] is not None and rec["ack"] is None
    assert "acknowledgement" in rec["reason"]
    put_channel(client, loss=0.0)
    r = client.post(f"/api/commands/{cmd['id']}/retry", headers=AUTH)
    assert r.status_code == 202
    retried = r.json()  # a new command, naming the one it retries
    assert retried["id"] != cmd["id"] and retried["retry_of"] == cmd["id"]
    done = wait_state(client, retried["id"], ("acknowledged",))
    assert done["attempts"] == 1 and done["reason"] is None
    assert wait_state(client, cmd["id"])["state"] == "timed_out"  # the old one stays as it was
    rows = client.get("/api/commands").json()  # newest first, in wire order
    assert [r["id"] for r in rows] == [retried["id"], cmd["id"]]


# --- surface ------------------------------------------------------------------------------


def test_surface_needs_the_token(client: TestClient) -> None:
    assert client.post("/api/surface").status_code == 401
    assert client.post("/api/surface", headers=WRONG_AUTH).status_code == 403


def test_surface_repeats_until_acknowledged(make_light_client: MakeLightClient) -> None:
    clock, link = ManualClock(), AgentLink()
    link.answer = False  # the vehicle hears nothing yet
    client = make_light_client(link, clock=clock, surface_repeat_s=2.0)
    r = client.post("/api/surface", headers=AUTH)
    assert r.status_code == 202
    s = r.json()
    assert s["kind"] == "surface" and s["pattern"] == "surface" and s["params"] == {}
    advance(client, clock, 2 * 2.0)  # the first copy and two repeats
    grown = record(client, s["id"])
    assert grown["attempts"] == 3 and grown["state"] == "transmitted"
    link.answer = True
    advance(client, clock, 2.0)  # the next repeat is answered
    acked = record(client, s["id"])
    assert acked["state"] == "acknowledged" and acked["attempts"] == 4
    assert acked["ack"]["command"]["pattern"] == "surface"
    advance(client, clock, 5 * 2.0)  # five repeat periods: no timer left to send another
    assert clock.pending() == []
    later = record(client, s["id"])
    assert later["attempts"] == 4 and len(link.frames) == 4
    assert later["state"] == "acknowledged"


# --- dives --------------------------------------------------------------------------------


@pytest.mark.training
def test_dives_and_track(client: TestClient) -> None:
    first_pose(client)
    cmd = wait_state(client, send(client)["id"])
    dives = client.get("/api/dives").json()
    assert [d["id"] for d in dives] == [1]
    assert dives[0]["target"] == "sim" and dives[0]["commands"] == 1
    assert dives[0]["started_at"]
    dive = wait_until(
        lambda: (d := client.get("/api/dives/1").json()) and len(d["track"]) >= 5 and d,
        what="track points",
    )
    assert dive["dive"] == 1
    assert [c["id"] for c in dive["commands"]] == [cmd["id"]]
    t = [p["t_s"] for p in dive["track"]]
    assert t == sorted(t)
    assert all(b - a >= 1.0 - 1e-6 for a, b in itertools.pairwise(t))  # 1 Hz (sim time)
    keys = {"t_s", "x_m", "y_m", "z_m", "heading_deg", "lat_deg", "lon_deg"}
    assert set(dive["track"][0]) == keys
    r = client.get("/api/dives/99")
    assert r.status_code == 404 and "99" in r.json()["detail"]


def test_dive_replay(client: TestClient) -> None:
    first_pose(client)
    assert client.post("/api/dives/1/replay").status_code == 401
    assert client.post("/api/dives/1/replay", headers=WRONG_AUTH).status_code == 403
    assert client.post("/api/dives/99/replay", headers=AUTH).status_code == 404
    r = client.post("/api/dives/1/replay", headers=AUTH)
    assert r.status_code == 200
    assert r.json()["dive"] == 1
    assert r.json()["commands"] == 0
    # the dive's track as it was then: the log has at least as many points now
    assert 0 <= r.json()["track_points"] <= len(client.get("/api/dives/1").json()["track"])


# --- vehicle ------------------------------------------------------------------------------


@pytest.mark.training
def test_vehicle_pose_status_and_echo(client: TestClient) -> None:
    pose = first_pose(client)
    assert {"t_s", "x_m", "y_m", "z_m", "heading_deg", "roll_deg"} <= set(pose)
    v = client.get("/api/vehicle").json()
    assert v["active"] is None and v["last_sent"] is None and v["echo_mismatch"] is False
    link = v["link"]
    assert (link["target"], link["connected"], link["capability"]) == (
        "sim",
        True,
        "acks_and_telemetry",
    )
    assert link["acknowledges"] and link["telemetry"] and link["copies"] == 1
    assert link["surface_copies"] is None  # until acknowledged
    assert link["level"] == "green" and link["problems"] == [], link
    assert v["age_s"] is not None and 0 <= v["age_s"] < 5
    status = wait_until(lambda: client.get("/api/vehicle").json()["status"], what="status")
    assert {"mode", "depth_m", "battery_pct", "speed_mps"} <= set(status)
    cmd = wait_state(client, send(client)["id"])
    v = client.get("/api/vehicle").json()
    assert v["active"]["pattern"] == "circle"
    assert v["active"]["params"] == cmd["params"]
    assert v["last_sent"]["id"] == cmd["id"]
    assert v["echo_mismatch"] is False
    square = wait_state(client, send(client, "square", SQUARE)["id"])
    v = client.get("/api/vehicle").json()
    assert v["active"]["params"] == square["params"]
    assert v["echo_mismatch"] is False
    moved = wait_until(
        lambda: (
            (p := client.get("/api/vehicle").json()["pose"])
            and math.hypot(p["x_m"] - pose["x_m"], p["y_m"] - pose["y_m"]) > 0.5
            and p
        ),
        what="the vehicle moving",
    )
    assert moved["t_s"] > pose["t_s"]


@pytest.mark.training
def test_echo_mismatch_when_another_station_retasks_the_vehicle(client: TestClient) -> None:
    first_pose(client)
    circle = wait_state(client, send(client)["id"])
    assert circle["state"] == "acknowledged"
    assert client.get("/api/vehicle").json()["echo_mismatch"] is False
    # a frame this console did not send reaches the vehicle, which accepts it
    other = encode_frame("square", SQUARE).frame.to_bytes()
    assert client.portal is not None
    sim = console_of(client).sim
    assert sim is not None
    client.portal.call(sim.submit_frame, other)
    v = wait_until(
        lambda: (v := client.get("/api/vehicle").json())["echo_mismatch"] and v,
        what="the echo mismatch",
    )
    assert v["active"]["pattern"] == "square"
    assert v["last_sent"]["id"] == circle["id"]
    assert [c["id"] for c in client.get("/api/commands").json()] == [circle["id"]]
    # the activity this console did not cause is in the mission log, once
    log = console_of(client).log
    assert log is not None
    events = wait_until(lambda: log.events(circle["dive"]), what="the event")
    assert [e["kind"] for e in events] == ["echo_mismatch"]
    assert "square" in events[0]["detail"] and "circle" in events[0]["detail"]
    assert events[0]["data"]["last_accepted_id"] == circle["id"]
    # once this console has sent what the vehicle runs, the echo agrees again
    square = wait_state(client, send(client, "square", SQUARE)["id"])
    assert square["state"] == "acknowledged"
    assert client.get("/api/vehicle").json()["echo_mismatch"] is False
    assert len(log.events(circle["dive"])) == 1  # logged when it began, not on every status


# --- training -----------------------------------------------------------------------------


@pytest.mark.training
def test_training_state(client: TestClient) -> None:
    t = client.get("/api/training").json()
    assert t["enabled"] is True
    assert t["scenarios"] == ["wreck", "panel", "pod", "tank"]
    assert t["time_scale"] == TIME_SCALE
    assert {
        "ber",
        "burst_rate",
        "burst_length_bits",
        "loss",
        "range_m",
        "delay_s",
        "bitrate_bps",
    } <= set(t["channel"])
    assert {"north_mps", "east_mps", "speed_sigma_mps", "direction_sigma_deg"} <= set(t["current"])


@pytest.mark.parametrize(
    ("method", "path", "body"),
    [
        ("PUT", "/api/training/channel", {"ber": 0.001}),
        ("PUT", "/api/training/current", {"north_mps": 0.1}),
        ("PUT", "/api/training/time_scale", {"time_scale": 10}),
        ("POST", "/api/training/reset", None),
        ("POST", "/api/training/scenario/pod", None),
    ],
)
@pytest.mark.training
def test_training_controls_need_the_token(
    client: TestClient, method: str, path: str, body: dict[str, Any] | None
) -> None:
    assert client.request(method, path, json=body).status_code == 401
    assert client.request(method, path, json=body, headers=WRONG_AUTH).status_code == 403
    assert client.request(method, path, json=body, headers=AUTH).status_code == 200


@pytest.mark.training
def test_training_channel(client: TestClient) -> None:
    body = {"ber": 0.001, "loss": 0.25, "delay_s": 0.5, "range_m": 500, "burst_rate": 0.1}
    r = client.put("/api/training/channel", json=body, headers=AUTH)
    assert r.status_code == 200
    assert r.json()["ber"] == 0.001 and r.json()["loss"] == 0.25
    channel = client.get("/api/training").json()["channel"]
    assert channel["delay_s"] == 0.5 and channel["range_m"] == 500
    assert channel["burst_length_bits"] == 8  # unset fields take their defaults


@pytest.mark.parametrize(
    ("path", "body", "field"),
    [
        ("/api/training/channel", {"ber": 0.7}, "ber"),
        ("/api/training/channel", {"loss": 1.5}, "loss"),
        ("/api/training/channel", {"burst_length_bits": 0}, "burst_length_bits"),
        ("/api/training/channel", {"bitrate_bps": 0}, "bitrate_bps"),
        ("/api/training/channel", {"noise": 1}, "noise"),
        ("/api/training/current", {"north_mps": 9}, "north_mps"),
        ("/api/training/current", {"direction_sigma_deg": -1}, "direction_sigma_deg"),
        ("/api/training/time_scale", {"time_scale": -1}, "time_scale"),
        ("/api/training/time_scale", {"time_scale": 51}, "time_scale"),
        ("/api/training/time_scale", {}, "time_scale"),
    ],
)
def test_training_values_are_422_naming_the_field(
    client: TestClient, path: str, body: dict[str, Any], field: str
) -> None:
    r = client.put(path, json=body, headers=AUTH)
    assert r.status_code == 422
    assert loc_of(r.json()) == ["body", field]


@pytest.mark.training
def test_training_current_and_time_scale(client: TestClient) -> None:
    body = {"north_mps": 0.2, "east_mps": -0.1, "speed_sigma_mps": 0.01, "direction_sigma_deg": 5}
    r = client.put("/api/training/current", json=body, headers=AUTH)
    assert r.status_code == 200
    assert r.json()["north_mps"] == 0.2 and r.json()["east_mps"] == -0.1
    assert client.get("/api/training").json()["current"]["direction_sigma_deg"] == 5
    r = client.put("/api/training/time_scale", json={"time_scale": 20}, headers=AUTH)
    assert r.status_code == 200 and r.json() == {"time_scale": 20}
    assert client.get("/api/training").json()["time_scale"] == 20


@pytest.mark.training
def test_training_reset_starts_a_new_dive_at_the_start(client: TestClient) -> None:
    start = first_pose(client)
    send(client, "straight", {"speed": 0.18, "depth": 2, "duration": 600, "heading": 90})
    wait_until(
        lambda: (p := client.get("/api/vehicle").json()["pose"]) and p["y_m"] > start["y_m"] + 3,
        what="the vehicle heading east",
    )
    r = client.post("/api/training/reset", headers=AUTH)
    assert r.status_code == 200
    assert r.json() == {"dive": 2}
    assert client.get("/api/session").json()["dive"] == 2
    assert [d["id"] for d in client.get("/api/dives").json()] == [2, 1]
    back = wait_until(
        lambda: (
            (p := client.get("/api/vehicle").json()["pose"])
            and math.hypot(p["x_m"] - start["x_m"], p["y_m"] - start["y_m"]) < 0.5
            and p
        ),
        what="the vehicle back at its start",
    )
    assert back["z_m"] == pytest.approx(2.0, abs=0.2)
    v = client.get("/api/vehicle").json()
    assert v["active"] is None and v["echo_mismatch"] is False
    # the next command belongs to the new dive
    assert send(client)["dive"] == 2


@pytest.mark.parametrize("name", ["wreck", "panel", "pod", "tank"])
@pytest.mark.training
def test_training_scenarios(client: TestClient, name: str) -> None:
    first_pose(client)
    r = client.post(f"/api/training/scenario/{name}", headers=AUTH)
    assert r.status_code == 200, r.text
    sc = r.json()
    assert sc["dive"] == 2 and sc["scenario"] == name and sc["title"]
    assert sc["sent"]["dive"] == 2
    rec = wait_state(client, sc["sent"]["id"])
    assert rec["state"] == "acknowledged", rec
    assert sc["next"]["pattern"] in PATTERNS and sc["next"]["at_s"] > 0
    # the proposed retask is ready to preview
    assert preview(client, sc["next"]["pattern"], sc["next"]["params"]).status_code == 200


@pytest.mark.training
def test_training_unknown_scenario_is_404(client: TestClient) -> None:
    r = client.post("/api/training/scenario/atlantis", headers=AUTH)
    assert r.status_code == 404
    assert "wreck" in r.json()["detail"]
    assert client.get("/api/session").json()["dive"] == 1  # nothing was reset


def test_vehicle_mode_has_no_training_and_commands_end_sent(
    make_client: MakeClient,
) -> None:
    client = make_client(target="loop://")
    s = client.get("/api/session").json()
    assert s["mode"] == "vehicle" and s["target"] == "loop://"
    assert client.get("/api/training").json() == {"enabled": False, "scenarios": []}
    for method, path, body in (
        ("PUT", "/api/training/channel", {}),
        ("PUT", "/api/training/current", {}),
        ("PUT", "/api/training/time_scale", {"time_scale": 1}),
        ("POST", "/api/training/reset", None),
        ("POST", "/api/training/scenario/wreck", None),
    ):
        r = client.request(method, path, json=body, headers=AUTH)
        assert r.status_code == 409, (path, r.text)
        assert "sim" in r.json()["detail"]
    cmd = send(client)
    assert cmd["target"] == "loop://"
    # a modem link has no acknowledgements: copies chosen from link_ber (1e-3 -> 1), then sent
    assert cmd["copies"] == 1 and cmd["two_way"] is False
    rec = wait_state(client, cmd["id"])
    assert rec["state"] == "sent" and rec["attempts"] == 1 and rec["copies_sent"] == 1
    assert rec["p_delivered"] == pytest.approx(delivery_probability(1e-3, 1))
    v = client.get("/api/vehicle").json()
    assert v["pose"] is None and v["status"] is None
    link = v["link"]
    assert (link["target"], link["connected"], link["capability"]) == ("loop://", True, "none")
    assert link["acknowledges"] is False and link["level"] == "amber"
    assert "one-way" in link["problems"][0]
    assert link["frames"]["dive"]["frames"] == 1 and link["frames"]["dive"]["sent"] == 1
    assert v["last_sent"]["id"] == cmd["id"]
    assert client.get("/api/session").json()["link"] == {
        "capability": "none",
        "acknowledges": False,
        "telemetry": False,
    }


# --- scripts ------------------------------------------------------------------------------


def test_script_preview(client: TestClient) -> None:
    r = client.post("/api/scripts/preview", json=SCRIPT)
    assert r.status_code == 200, r.text
    p = r.json()
    assert p["name"] == "two steps"
    assert [s["pattern"] for s in p["steps"]] == ["square", "circle"]
    path = p["path"]
    n = len(path["x_m"])
    assert n > 2 and len(path["y_m"]) == len(path["z_m"]) == len(path["t_s"]) == n
    assert len(path["step_start"]) == 2
    assert [e["step"] for e in p["timeline"]][:2] == [0, 1]
    assert [e["t_s"] for e in p["timeline"]][:2] == [0.0, 20.0]
    assert p["duration_s"] > 20


@pytest.mark.parametrize(
    ("step", "params", "loc"),
    [
        (1, {"radius": 900}, ["body", "steps", 1, "params", "radius"]),  # codec range
        (1, {"radius": 0}, ["body", "steps", 1, "params", "radius"]),  # planner
        (0, {"speed": True}, ["body", "steps", 0, "params", "speed"]),
        (0, {"side_span": "wide"}, ["body", "steps", 0, "params", "side_span"]),
    ],
)
def test_script_preview_422_names_the_step_and_param(
    client: TestClient, step: int, params: dict[str, Any], loc: list[Any]
) -> None:
    script = script_with()
    script["steps"][step]["params"].update(params)
    r = client.post("/api/scripts/preview", json=script)
    assert r.status_code == 422
    assert loc_of(r.json())[: len(loc)] == loc
    assert client.post("/api/scripts/export", json=script).status_code == 422


def test_script_preview_structure_errors(client: TestClient) -> None:
    assert client.post("/api/scripts/preview", json=script_with(steps=[])).status_code == 422
    r = client.post("/api/scripts/preview", json=script_with(format="other"))
    assert r.status_code == 422 and loc_of(r.json()) == ["body", "format"]
    bad = script_with()
    bad["steps"][1]["trigger"]["t_s"] = -5
    r = client.post("/api/scripts/preview", json=bad)
    assert r.status_code == 422 and loc_of(r.json())[:3] == ["body", "steps", 1]


def test_script_export_json_and_csv(client: TestClient) -> None:
    r = client.post("/api/scripts/export", json=SCRIPT)
    assert r.status_code == 200
    assert r.headers["content-disposition"] == 'attachment; filename="two-steps-onboard.json"'
    doc = r.json()
    assert doc["format"] == "nemesys-onboard-script" and doc["version"] == 1
    assert [(f["t_s"], f["pattern"]) for f in doc["frames"]] == [(0.0, "square"), (20.0, "circle")]
    for f in doc["frames"]:
        assert decode_frame(f["hex"]).command.pattern.name == f["pattern"]
        assert len(f["bits"]) == 100
    c = client.post("/api/scripts/export", params={"format": "csv"}, json=SCRIPT)
    assert c.status_code == 200
    assert c.headers["content-type"].startswith("text/csv")
    assert c.headers["content-disposition"] == 'attachment; filename="two-steps-onboard.csv"'
    lines = c.text.splitlines()
    assert lines[0] == "t_s,pattern,hex"
    assert lines[1:] == [
        f"0.000,square,{doc['frames'][0]['hex']}",
        f"20.000,circle,{doc['frames'][1]['hex']}",
    ]
    assert (
        client.post("/api/scripts/export", params={"format": "xml"}, json=SCRIPT).status_code == 422
    )


def run_state(client: TestClient) -> dict[str, Any]:
    state: dict[str, Any] = client.get("/api/scripts/run").json()
    return state


@pytest.mark.training
def test_script_run_auto(client: TestClient) -> None:
    first_pose(client)
    body = {"script": SCRIPT, "mode": "auto"}
    assert client.post("/api/scripts/run", json=body).status_code == 401
    assert client.post("/api/scripts/run", json=body, headers=WRONG_AUTH).status_code == 403
    r = client.post("/api/scripts/run", json=body, headers=AUTH)
    assert r.status_code == 200, r.text
    assert r.json()["running"] is True and r.json()["mode"] == "auto"
    again = client.post("/api/scripts/run", json=body, headers=AUTH)
    assert again.status_code == 409
    done = wait_until(
        lambda: (s := run_state(client))["running"] is False and s,
        timeout_s=10,
        what="the run to finish",
    )
    # the last step is a circle: it repeats, so the run leaves it running until retasked
    assert done["outcome"] == "until_retasked", done
    assert [s["state"] for s in done["steps"]] == ["acknowledged", "acknowledged"]
    assert all(s["transmitted"] for s in done["steps"])
    ids = [done["commands"][k] for k in ("0", "1")]
    rows = client.get("/api/commands").json()
    assert [x["id"] for x in rows] == ids[::-1]
    assert [(x["pattern"], x["kind"], x["state"]) for x in rows] == [
        ("circle", "script", "acknowledged"),
        ("square", "script", "acknowledged"),
    ]


@pytest.mark.slow  # a script run's real polling
def test_script_run_step_mode(client: TestClient) -> None:
    first_pose(client)
    r = client.post("/api/scripts/run", json={"script": SCRIPT, "mode": "step"}, headers=AUTH)
    assert r.status_code == 200
    s = r.json()
    assert s["waiting_for"] == "operator"
    assert s["next"]["index"] == 0 and s["next"]["pattern"] == "square"
    # the run's loop polls again (its clock moves on), proposing without sending: nothing
    # leaves without the operator's go
    wait_until(
        lambda: run_state(client)["elapsed_s"] > (s["elapsed_s"] or 0.0) + 0.01,
        what="the run's loop to poll again",
    )
    assert client.get("/api/commands").json() == []
    assert client.post("/api/scripts/run/next").status_code == 401
    r = client.post("/api/scripts/run/next", headers=AUTH)
    assert r.status_code == 200, r.text
    assert r.json()["steps"][0]["state"] in ("sent", "acknowledged")
    assert "0" in r.json()["commands"]
    proposed = wait_until(
        lambda: (st := run_state(client))["next"] is not None and st,
        what="step 1 proposed",
    )
    assert proposed["next"]["index"] == 1
    assert proposed["steps"][0]["state"] == "acknowledged"
    assert client.post("/api/scripts/run/next", headers=AUTH).status_code == 200
    done = wait_until(
        lambda: (st := run_state(client))["running"] is False and st, what="the run to finish"
    )
    assert done["outcome"] == "until_retasked"  # the circle repeats until retasked
    assert [x["pattern"] for x in client.get("/api/commands").json()] == ["circle", "square"]


def test_script_next_409_without_a_proposal(client: TestClient) -> None:
    first_pose(client)
    r = client.post("/api/scripts/run/next", headers=AUTH)
    assert r.status_code == 409 and "no script" in r.json()["detail"]
    later = script_with()
    later["steps"][1]["trigger"]["t_s"] = 3600  # far beyond this test
    r = client.post("/api/scripts/run", json={"script": later, "mode": "auto"}, headers=AUTH)
    assert r.status_code == 200
    waiting = wait_until(
        lambda: (st := run_state(client))["waiting_for"] == "time" and st,
        what="step 0 acknowledged",
    )
    assert waiting["steps"][0]["state"] == "acknowledged"
    r = client.post("/api/scripts/run/next", headers=AUTH)
    assert r.status_code == 409 and "time" in r.json()["detail"]
    assert client.post("/api/scripts/run/stop").status_code == 401
    r = client.post("/api/scripts/run/stop", headers=AUTH)
    assert r.status_code == 200
    assert r.json()["running"] is False and r.json()["outcome"] == "stopped"
    r = client.post("/api/scripts/run/next", headers=AUTH)
    assert r.status_code == 409 and "over" in r.json()["detail"]
    # a new run may start after a stop
    r = client.post("/api/scripts/run", json={"script": later, "mode": "step"}, headers=AUTH)
    assert r.status_code == 200 and r.json()["running"] is True


def test_script_stop_without_a_run(client: TestClient) -> None:
    r = client.post("/api/scripts/run/stop", headers=AUTH)
    assert r.status_code == 200
    assert r.json()["running"] is False


def test_script_run_body_is_validated(client: TestClient) -> None:
    r = client.post("/api/scripts/run", json={"script": SCRIPT, "mode": "fast"}, headers=AUTH)
    assert r.status_code == 422 and loc_of(r.json()) == ["body", "mode"]
    bad = script_with()
    bad["steps"][1]["params"]["radius"] = 900
    r = client.post("/api/scripts/run", json={"script": bad}, headers=AUTH)
    assert r.status_code == 422
    assert loc_of(r.json())[:6] == ["body", "script", "steps", 1, "params", "radius"]


def test_script_run_state_before_any_run_has_the_documented_keys(client: TestClient) -> None:
    assert {"running", "mode", "step", "next", "waiting_for", "steps"} <= set(run_state(client))


# --- the page and the docs ----------------------------------------------------------------


def test_openapi_lists_every_api_path_and_docs_serve(client: TestClient) -> None:
    spec = client.get("/openapi.json").json()
    paths = {p for p in spec["paths"] if p.startswith("/api")}
    assert paths == API_PATHS
    assert set(spec["paths"]["/api/commands"]) == {"get", "post"}
    assert set(spec["paths"]["/api/scripts/run"]) == {"get", "post"}
    docs = client.get("/docs")
    assert docs.status_code == 200
    assert docs.headers["content-type"].startswith("text/html")


def test_page_and_static_assets(client: TestClient) -> None:
    page = client.get("/")
    assert page.status_code == 200
    assert page.headers["content-type"].startswith("text/html")
    assert page.headers["cache-control"] == "no-cache"
    assert "/static/app.js" in page.text
    assert client.get("/static/app.js").status_code == 200
    assert client.get("/static/nope.js").status_code == 404


# --- the link's assumptions ---------------------------------------------------------------


def test_put_link_sets_the_assumed_ber_and_target(make_client: MakeClient) -> None:
    client = make_client(target="loop://")
    assert client.put("/api/link", json={"link_ber": 0.02}).status_code == 401
    r = client.put("/api/link", json={"link_ber": 0.02, "delivery_target": 0.9999}, headers=AUTH)
    assert r.status_code == 200, r.text
    link = r.json()
    assert link["ber"] == 0.02 and link["copies"] == copies_for(0.02, 0.9999) == 6
    cmd = send(client)
    assert cmd["copies"] == 6 and cmd["ber"] == 0.02
    kept = client.put("/api/link", json={}, headers=AUTH).json()
    assert kept["ber"] == 0.02 and kept["copies"] == 6  # a field left out keeps its value


@pytest.mark.parametrize(
    ("body", "field", "interval"),
    [
        ({"link_ber": 0.5}, "link_ber", "[0, 0.5)"),
        ({"link_ber": -0.001}, "link_ber", "[0, 0.5)"),
        ({"link_ber": "0.01"}, "link_ber", "[0, 0.5)"),
        ({"link_ber": True}, "link_ber", "[0, 0.5)"),
        ({"delivery_target": 1}, "delivery_target", "(0, 1)"),
        ({"delivery_target": 0.0}, "delivery_target", "(0, 1)"),
        ({"delivery_target": "high"}, "delivery_target", "(0, 1)"),
    ],
)
def test_put_link_refuses_out_of_range_naming_field_and_range(
    make_client: MakeClient, body: dict[str, Any], field: str, interval: str
) -> None:
    client = make_client(target="loop://")
    r = client.put("/api/link", json=body, headers=AUTH)
    assert r.status_code == 422, r.text
    assert loc_of(r.json()) == ["body", field]
    assert field in r.json()["detail"][0]["msg"] and interval in r.json()["detail"][0]["msg"]
    assert client.get("/api/vehicle").json()["link"]["ber"] == 1e-3  # nothing changed


@pytest.mark.training
def test_put_link_ber_in_training_is_409(client: TestClient) -> None:
    r = client.put("/api/link", json={"link_ber": 0.01}, headers=AUTH)
    assert r.status_code == 409 and "/api/training/channel" in r.json()["detail"]
    r = client.put("/api/link", json={"delivery_target": 0.99}, headers=AUTH)
    assert r.status_code == 200
