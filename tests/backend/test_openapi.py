"""The typed contract: every response of the API has a model in the OpenAPI document, real
responses validate against it, no field of the handlers' output is dropped by a model, the
documented errors are the ones the API answers, operator calls declare the token's security
schemes, and docs/api.md's endpoint table is the OpenAPI's.

Every call here goes through :meth:`Contract.check`: its status must be documented for the
operation, and its body must validate against the documented schema (JSON Schema 2020-12,
``$ref``s resolved through a :mod:`referencing` registry), with every object closed
(``additionalProperties: false`` unless the model is an open one), so a JSON-returning handler
(preview, the exports) cannot grow a field the contract does not name.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import asdict
from pathlib import Path
from typing import Any

import httpx
import pytest
from fastapi.testclient import TestClient
from jsonschema import Draft202012Validator
from pydantic import BaseModel
from referencing import Registry, Resource
from referencing.jsonschema import DRAFT202012
from starlette.requests import Request

from backend.api import authoring, commands, scripts, training
from backend.api.commands import LogFilter
from backend.mission_log.store import LogWriteError
from codec import describe_dictionary, encode_frame
from tests.backend.api.test_survey import SURVEY
from tests.backend.chart.test_tiles import tile_dir
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    SQUARE,
    TOKEN,
    WRONG_AUTH,
    WRONG_TOKEN,
    MakeClient,
    command_fields,
    console_of,
    wait_state,
    wait_until,
)

DOCS = Path(__file__).resolve().parents[2] / "docs" / "api.md"
SPEC_URI = "urn:nemesys:console:openapi"
#: Models whose shape is the vehicle's, open by design (fields outside the contract kept).
OPEN_MODELS = {"Ack", "VehicleStatus"}
#: Path parameters that name something that exists, for calls that must reach the handler.
PATH_VALUES = {"command_id": "1", "dive": "1", "name": "wreck", "z": "3", "x": "2", "y": "5"}
#: The operator's endpoints (docs/api.md marks them 🔒).
OPERATOR_OPS = {
    ("POST", "/api/commands"),
    ("POST", "/api/commands/{}/retry"),
    ("POST", "/api/surface"),
    ("POST", "/api/control"),
    ("POST", "/api/dives/{}/replay"),
    ("PUT", "/api/link"),
    ("POST", "/api/link/test"),
    ("PUT", "/api/datum"),
    ("PUT", "/api/training/channel"),
    ("PUT", "/api/training/current"),
    ("PUT", "/api/training/time_scale"),
    ("POST", "/api/training/reset"),
    ("POST", "/api/training/scenario/{}"),
    ("POST", "/api/scripts/run"),
    ("POST", "/api/scripts/run/next"),
    ("POST", "/api/scripts/run/stop"),
}
SCRIPT: dict[str, Any] = {
    "format": "nemesys-mission-script",
    "version": 1,
    "name": "contract",
    "steps": [
        {"pattern": "square", "params": SQUARE, "trigger": {"kind": "at", "t_s": 0}},
        {"pattern": "circle", "params": CIRCLE, "trigger": {"kind": "operator"}},
    ],
}


def normal(path: str) -> str:
    """A path with its parameters unnamed: ``/api/dives/{}``."""
    return re.sub(r"\{[^}]*\}", "{}", path)


def close(schema: Any) -> Any:
    """The schema with every object that names its properties closed to others (a model's
    ``extra="allow"`` says ``additionalProperties: true`` and stays open)."""
    if isinstance(schema, list):
        return [close(s) for s in schema]
    if not isinstance(schema, dict):
        return schema
    out = {k: close(v) for k, v in schema.items()}
    if "properties" in out and "additionalProperties" not in out:
        out["additionalProperties"] = False
    return out


def pointer(*parts: str) -> str:
    return "".join("/" + p.replace("~", "~0").replace("/", "~1") for p in parts)


class Contract:
    """The app's OpenAPI document, and the check of real responses against it."""

    def __init__(self, client: TestClient) -> None:
        self.client = client
        r = client.get("/openapi.json")
        assert r.status_code == 200
        self.spec: dict[str, Any] = r.json()
        closed = close(self.spec)
        self.registry: Registry[Any] = Registry().with_resource(
            SPEC_URI, Resource.from_contents(closed, default_specification=DRAFT202012)
        )
        self._routes = [
            (re.compile("^" + re.sub(r"\{[^}]*\}", "[^/]+", path) + "$"), path)
            for path in self.spec["paths"]
        ]
        #: (method, normalised path, status) of every call checked.
        self.seen: set[tuple[str, str, int]] = set()

    def operations(self) -> Iterator[tuple[str, str, dict[str, Any]]]:
        """(METHOD, path template, operation) of every API operation."""
        for path, ops in self.spec["paths"].items():
            if path.startswith("/api"):
                for method, op in ops.items():
                    yield method.upper(), path, op

    def operation(self, method: str, url_path: str) -> tuple[str, dict[str, Any]]:
        matches = [path for regex, path in self._routes if regex.match(url_path)]
        # a literal segment wins over a parameter (/api/commands/x vs /api/log.json)
        matches.sort(key=lambda p: p.count("{"))
        for path in matches:
            op = self.spec["paths"][path].get(method.lower())
            if op is not None:
                return path, op
        raise AssertionError(f"{method} {url_path} is no documented operation")

    def check(self, response: httpx.Response) -> httpx.Response:
        """The response's status is documented for its operation and its body validates
        against the documented schema; returns it."""
        method, url_path = response.request.method, response.request.url.path
        path, op = self.operation(method, url_path)
        code = str(response.status_code)
        where = f"{method} {path} answered {code}"
        assert code in op["responses"], f"{where}, not documented: {response.text[:300]}"
        content = op["responses"][code].get("content", {})
        media = response.headers.get("content-type", "").split(";")[0]
        assert media in content, f"{where} as {media}; documented: {sorted(content)}"
        if media == "application/json":
            at = pointer("paths", path, method.lower(), "responses", code, "content", media)
            validator = Draft202012Validator(
                {"$ref": f"{SPEC_URI}#{at}/schema"}, registry=self.registry
            )
            problems = [
                f"{'/'.join(map(str, e.absolute_path))}: {e.message[:300]}"
                for e in validator.iter_errors(response.json())
            ]
            assert not problems, f"{where}: the body does not match its schema: {problems}"
        else:
            assert content[media]["schema"] == {"type": "string"}
        if code == "429":
            assert response.headers["retry-after"].isdigit()
        self.seen.add((method, normal(path), response.status_code))
        return response

    def call(self, method: str, url: str, **kwargs: Any) -> httpx.Response:
        return self.check(self.client.request(method, url, **kwargs))


def contract(client: TestClient) -> Contract:
    return Contract(client)


def same_keys(api: Any, raw: Any, where: str = "") -> None:
    """Every key of the handler's own output is in the response, and no other, at every
    depth (values may differ: times move on)."""
    if isinstance(raw, dict):
        assert isinstance(api, dict), where
        assert set(api) == {str(k) for k in raw}, f"{where}: {set(api) ^ set(map(str, raw))}"
        for k, v in raw.items():
            same_keys(api[str(k)], v, f"{where}.{k}")
    elif isinstance(raw, list | tuple):
        assert isinstance(api, list), where
        for i, (a, r) in enumerate(zip(api, raw, strict=False)):
            same_keys(a, r, f"{where}[{i}]")


def interrupted_record(client: TestClient) -> int:
    """A retryable record, written to the log as a crash would leave it."""
    log, dives = console_of(client).log, console_of(client).dives
    assert log is not None and dives is not None
    rec = log.insert_command(dives.ensure(), command_fields())
    log.update_command(rec["id"], state="interrupted")
    return int(rec["id"])


def first_pose(client: TestClient) -> None:
    wait_until(lambda: client.get("/api/vehicle").json()["pose"], what="the first pose")


# --- the document ---------------------------------------------------------------------------


def test_every_success_response_is_typed(client: TestClient) -> None:
    c = contract(client)
    schemas = c.spec["components"]["schemas"]

    def typed(schema: dict[str, Any]) -> bool:
        if "$ref" in schema:
            name = schema["$ref"].rsplit("/", 1)[1]
            target = schemas[name]
            if target.get("type") == "object" and name not in OPEN_MODELS:
                return bool(target.get("properties")) and not target.get("additionalProperties")
            return True
        if schema.get("type") == "array":
            return typed(schema["items"])
        alternatives = schema.get("anyOf") or schema.get("oneOf")
        if alternatives:
            return all(typed(s) for s in alternatives)
        return schema.get("type") == "string"  # a file (CSV)

    for method, path, op in c.operations():
        responses = op["responses"]
        ok = [code for code in responses if code.startswith("2")]
        assert len(ok) == 1, f"{method} {path}: {ok}"
        for code, response in responses.items():
            content = response.get("content")
            assert content, f"{method} {path} {code}: no content declared"
            for media, body in content.items():
                assert typed(body["schema"]), f"{method} {path} {code} {media}: {body['schema']}"
                if not code.startswith("2"):
                    assert media == "application/json", f"{method} {path} {code}"


def test_no_model_is_an_untyped_object(client: TestClient) -> None:
    schemas = contract(client).spec["components"]["schemas"]
    for name, schema in schemas.items():
        if schema.get("type") == "object":
            assert schema.get("properties"), name
            assert (schema.get("additionalProperties") is True) == (name in OPEN_MODELS), name
    # the command record says what its parameters and acknowledgement are
    record = schemas["CommandRecord"]["properties"]
    assert record["params"]["additionalProperties"] == {
        "anyOf": [{"type": "number"}, {"type": "string"}]
    }
    assert {"$ref": "#/components/schemas/Ack"} in record["ack"]["anyOf"]
    assert {"type": "null"} in record["ack"]["anyOf"]
    for field in ("copies", "copies_sent", "p_delivered", "ber", "two_way", "superseded_by"):
        assert field in schemas["CommandRecord"]["required"], field


def test_security_schemes_are_declared_and_operator_calls_require_them(
    client: TestClient,
) -> None:
    c = contract(client)
    schemes = c.spec["components"]["securitySchemes"]
    assert schemes["bearerAuth"]["type"] == "http"
    assert schemes["bearerAuth"]["scheme"] == "bearer"
    assert schemes["tokenHeader"] == {**schemes["tokenHeader"], "type": "apiKey", "in": "header"}
    assert schemes["tokenHeader"]["name"] == "X-Nemesys-Token"
    secured = set()
    for method, path, op in c.operations():
        if "security" in op:
            assert op["security"] == [{"bearerAuth": []}, {"tokenHeader": []}]
            secured.add((method, normal(path)))
    assert secured == OPERATOR_OPS


def test_operator_calls_answer_401_and_403_and_the_rest_no_token_error(
    client: TestClient,
) -> None:
    """Every operation, called without the token: the operator's answer 401 (and 403 with a
    wrong one, in either header); no other answers 401 or 403."""
    c = contract(client)
    for method, path, op in list(c.operations()):
        url = path.format(**PATH_VALUES)
        body: dict[str, Any] | None = {} if "requestBody" in op else None
        if "security" in op:
            assert c.call(method, url, json=body).status_code == 401
            assert c.call(method, url, json=body, headers=WRONG_AUTH).status_code == 403
            wrong = {"X-Nemesys-Token": WRONG_TOKEN}
            assert c.call(method, url, json=body, headers=wrong).status_code == 403
        else:
            r = c.call(method, url, json=body)
            assert r.status_code not in (401, 403), f"{method} {path}"
    # the token in its own header is as good as the bearer one
    r = c.call("POST", "/api/scripts/run/stop", headers={"X-Nemesys-Token": TOKEN})
    assert r.status_code == 200


# --- the answers, checked against the document ----------------------------------------------


def test_a_tour_of_every_operation_validates(make_client: MakeClient, tmp_path: Path) -> None:
    """A successful call of every operation, each response checked against its schema."""
    client = make_client(tiles=tile_dir(tmp_path))
    c = contract(client)
    first_pose(client)
    c.call("GET", "/api/session")
    c.call("GET", "/api/chart")
    c.call("GET", "/api/tiles/3/2/5")
    c.call("PUT", "/api/datum", json={"lat_deg": 29.53, "lon_deg": -82.30}, headers=AUTH)
    assert c.call("GET", "/api/session", headers=AUTH).json()["authenticated"] is True
    c.call("GET", "/api/dictionary")
    body = {"pattern": "circle", "params": CIRCLE}
    c.call("POST", "/api/preview", json=body)
    c.call("POST", "/api/predict?horizon_s=30", json=body)
    c.call("POST", "/api/survey/preview", json=SURVEY)
    frame = c.call("POST", "/api/encode", json=body).json()["hex"]
    c.call("POST", "/api/decode", json={"frame": frame})
    # a fleet's addressed frame: with its address (no vehicle of this console has it)
    addressed = encode_frame("circle", CIRCLE, address=2).frame.hex
    assert c.call("POST", "/api/decode", json={"frame": addressed}).json()["address"] == 2
    sent = c.call("POST", "/api/commands", json=body, headers=AUTH).json()
    wait_state(client, sent["id"], ("acknowledged",))
    # a preview against the active pattern: with its diff
    square = {"pattern": "square", "params": SQUARE}
    wait_until(lambda: c.call("POST", "/api/preview", json=square).json()["diff"])
    c.call("GET", f"/api/commands/{sent['id']}")
    c.call("GET", "/api/commands")
    c.call("GET", "/api/log.json")
    c.call("GET", "/api/log.csv")
    c.call("GET", "/api/vehicle")
    # the fleet's views, here of the single vehicle (a fleet of one: "nemesys")
    assert [v["name"] for v in c.call("GET", "/api/vehicles").json()] == ["nemesys"]
    c.call("GET", "/api/vehicles/nemesys")
    c.call("GET", "/api/transmitter")
    c.call("POST", f"/api/commands/{interrupted_record(client)}/retry", json={}, headers=AUTH)
    surface = c.call("POST", "/api/surface", headers=AUTH).json()
    wait_state(client, surface["id"])
    c.call("GET", "/api/dives")
    c.call("GET", "/api/dives/1")
    c.call("GET", "/api/series")
    c.call("GET", "/api/dives/1/timeline")
    c.call("GET", "/api/dives/1/export.mcap")
    view = {"X-Nemesys-View": "tour-view-0001"}  # a page's own 3D view (none in this app)
    c.call("POST", "/api/dives/1/replay", headers={**AUTH, **view})
    c.call("PUT", "/api/replay/at", json={"dive": 1, "t_s": 0.0}, headers=view)
    c.call("DELETE", "/api/replay", headers=view)
    c.call("PUT", "/api/link", json={"delivery_target": 0.99}, headers=AUTH)
    c.call("POST", "/api/link/test", headers=AUTH)
    c.call("GET", "/api/training")
    c.call("PUT", "/api/training/channel", json={"range_m": None}, headers=AUTH)
    c.call("PUT", "/api/training/current", json={"north_mps": 0.1}, headers=AUTH)
    c.call("PUT", "/api/training/time_scale", json={"time_scale": 50}, headers=AUTH)
    c.call("GET", "/api/training")  # an unlimited range is null
    loaded = c.call("POST", "/api/training/scenario/pod", headers=AUTH).json()
    wait_state(client, loaded["sent"]["id"])
    c.call("POST", "/api/training/reset", headers=AUTH)
    first_pose(client)
    c.call("POST", "/api/scripts/preview", json=SCRIPT)
    c.call("POST", "/api/scripts/export", json=SCRIPT)
    c.call("POST", "/api/scripts/export?format=csv", json=SCRIPT)
    c.call("GET", "/api/scripts/run")
    c.call("POST", "/api/scripts/run", json={"script": SCRIPT, "mode": "step"}, headers=AUTH)
    c.call("POST", "/api/scripts/run/next", headers=AUTH)
    wait_until(lambda: c.call("GET", "/api/scripts/run").json()["next"], what="step 2 proposed")
    c.call("POST", "/api/scripts/run/stop", headers=AUTH)
    c.call("GET", "/api/scripts/run")
    c.call("POST", "/api/control", json={"action": "request"}, headers=AUTH)
    c.call("GET", "/api/control")
    ok = {(m, p) for m, p, status in c.seen if status < 300}
    assert ok == {(m, normal(p)) for m, p, _ in c.operations()}


@pytest.mark.training
def test_a_fleets_answers_validate(make_client: MakeClient) -> None:
    """Training with a fleet of three: the answers that are then each vehicle's validate,
    and the reads of one vehicle name it."""
    client = make_client(vehicles="3")
    c = contract(client)
    wait_until(lambda: all(v["pose"] for v in c.call("GET", "/api/vehicles").json()))
    training = c.call("GET", "/api/training").json()
    assert [v["vehicle"] for v in training["vehicle_channel_stats"]] == ["auv1", "auv2", "auv3"]
    c.call("GET", "/api/vehicles/auv2")
    c.call("GET", "/api/vehicle")
    series = c.call("GET", "/api/series?vehicle=auv2").json()
    assert series["vehicle"] == "auv2" and series["dive"] == 1
    missing = c.call("GET", "/api/series")
    assert missing.status_code == 422
    assert missing.json()["detail"][0]["loc"] == ["query", "vehicle"]
    c.call("GET", "/api/dives/1?vehicle=auv3")
    # the replay of one vehicle's: its timeline, its slider, its track in a view
    timeline = c.call("GET", "/api/dives/1/timeline?vehicle=auv2").json()
    assert timeline["vehicle"] == "auv2"
    assert c.call("GET", "/api/dives/1/timeline").status_code == 422
    view = {"X-Nemesys-View": "fleet-view-1"}
    at = c.call(
        "PUT", "/api/replay/at", json={"dive": 1, "t_s": 0.0, "vehicle": "auv2"}, headers=view
    )
    assert at.json()["vehicle"] == "auv2"
    replay = c.call("POST", "/api/dives/1/replay?vehicle=auv2", headers={**AUTH, **view})
    assert replay.json()["vehicle"] == "auv2"
    c.call("GET", "/api/transmitter")


def test_a_real_vehicles_answers_validate(make_client: MakeClient) -> None:
    """A vehicle console (no simulator): nothing known of the vehicle yet, no training."""
    c = contract(make_client(target="loop://"))
    assert c.call("GET", "/api/training").json() == {"enabled": False, "scenarios": []}
    vehicle = c.call("GET", "/api/vehicle").json()
    assert vehicle["pose"] is None and vehicle["status"] is None
    assert c.call("GET", "/api/session").json()["mode"] == "vehicle"
    c.call("PUT", "/api/link", json={"link_ber": 0.01}, headers=AUTH)
    c.call("POST", "/api/preview", json={"pattern": "circle", "params": CIRCLE})


@pytest.mark.training
def test_404s(client: TestClient) -> None:
    c = contract(client)
    for method, url, auth in (
        ("GET", "/api/commands/999", None),
        ("POST", "/api/commands/999/retry", AUTH),
        ("GET", "/api/dives/999", None),
        ("POST", "/api/dives/999/replay", AUTH),
        ("POST", "/api/training/scenario/atlantis", AUTH),
    ):
        assert c.call(method, url, headers=auth).status_code == 404, url


def test_409s(make_client: MakeClient) -> None:
    client = make_client()
    c = contract(client)
    first_pose(client)
    too_fast = {"pattern": "circle", "params": {**CIRCLE, "speed": 1.5}}
    r = c.call("POST", "/api/commands", json=too_fast, headers=AUTH)
    assert r.status_code == 409 and r.json()["detail"]["violations"]
    sent = c.call(
        "POST", "/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH
    )
    wait_state(client, sent.json()["id"], ("acknowledged",))
    assert (
        c.call("POST", f"/api/commands/{sent.json()['id']}/retry", headers=AUTH).status_code == 409
    )
    assert c.call("PUT", "/api/link", json={"link_ber": 0.01}, headers=AUTH).status_code == 409
    assert c.call("POST", "/api/scripts/run/next", headers=AUTH).status_code == 409
    run = {"script": SCRIPT, "mode": "step"}
    assert c.call("POST", "/api/scripts/run", json=run, headers=AUTH).status_code == 200
    assert c.call("POST", "/api/scripts/run", json=run, headers=AUTH).status_code == 409
    c.call("POST", "/api/scripts/run/stop", headers=AUTH)
    # a real vehicle has no training controls
    v = contract(make_client(target="loop://"))
    for method, url, body in (
        ("PUT", "/api/training/channel", {"ber": 0.01}),
        ("PUT", "/api/training/current", {"north_mps": 0.1}),
        ("PUT", "/api/training/time_scale", {"time_scale": 2}),
        ("POST", "/api/training/reset", None),
        ("POST", "/api/training/scenario/wreck", None),
    ):
        assert v.call(method, url, json=body, headers=AUTH).status_code == 409, url


#: Paths whose parameter is a name, any text of its length: an unknown one is 404, not 422.
NAMED_BY_TEXT = ("/api/training/scenario/{name}", "/api/vehicles/{name}")


def test_422s(client: TestClient) -> None:
    """Every operation that takes input refuses bad input with a documented 422 (its
    structured forms included: limits beyond the rating, a rejected frame, the codec's and
    the planner's refusals)."""
    c = contract(client)
    bad_body = {"nonsense": True}
    for method, path, op in list(c.operations()):
        if "422" not in op["responses"] or path in NAMED_BY_TEXT:
            continue  # a scenario's or a vehicle's name is any text: 404 when unknown
        if "requestBody" in op:
            url = path.format(**PATH_VALUES)
            r = c.call(method, url, json=bad_body, headers=AUTH)
        elif "{" in path:
            r = c.call(method, re.sub(r"\{[^}]*\}", "x", path), headers=AUTH)
        else:
            # a bad query, or a bad view id (DELETE /api/replay takes only that)
            bad_view = {"X-Nemesys-View": "not a view id"}
            r = c.call(method, path, params={"limit": 0}, headers={**AUTH, **bad_view})
        assert r.status_code == 422, f"{method} {path}: {r.status_code}"
    beyond = {"pattern": "circle", "params": {**CIRCLE, "depth": 105}, "override": True}
    r = c.call("POST", "/api/commands", json=beyond, headers=AUTH)
    assert r.status_code == 422 and r.json()["detail"]["violations"]
    r = c.call("POST", "/api/decode", json={"frame": "0" * 25})
    assert r.status_code == 422 and r.json()["detail"]["reason"]
    r = c.call("POST", "/api/preview", json={"pattern": "circle", "params": {"radius": 1e9}})
    assert r.status_code == 422
    r = c.call("POST", "/api/commands", json={**beyond, "copies": 0}, headers=AUTH)
    assert r.status_code == 422
    broken = {**SCRIPT, "steps": [{**SCRIPT["steps"][0], "params": {"depth": 500}}]}
    assert c.call("POST", "/api/scripts/preview", json=broken).status_code == 422
    # far over any body cap: refused either way (413 by the cap, or 422), as documented
    r = c.call("POST", "/api/preview", json={"pattern": "x" * 2_000_000})
    assert r.status_code in (413, 422)


def test_429s(make_client: MakeClient) -> None:
    client = make_client(max_sends_per_minute=1)
    c = contract(client)
    body = {"pattern": "circle", "params": CIRCLE}
    assert c.call("POST", "/api/commands", json=body, headers=AUTH).status_code == 202
    assert c.call("POST", "/api/commands", json=body, headers=AUTH).status_code == 429
    retry = f"/api/commands/{interrupted_record(client)}/retry"
    assert c.call("POST", retry, headers=AUTH).status_code == 429
    assert c.call("POST", "/api/training/scenario/wreck", headers=AUTH).status_code == 429
    # a Surface is never rate limited
    assert c.call("POST", "/api/surface", headers=AUTH).status_code == 202


# --- found by schemathesis (tests/backend/test_schemathesis.py) ------------------------------

#: Constraint names of pydantic's: in a JSON Schema they bound nothing.
PYDANTIC_ONLY = {"ge", "gt", "le", "lt", "min_length", "max_length", "multiple_of", "strict"}


def test_a_body_that_is_not_json_is_a_documented_422(client: TestClient) -> None:
    """A body sent as text/plain (FastAPI hands the model its bytes: the excerpt of them in
    the 422 was a 500), and one the JSON parser cannot read at all, not Unicode text or nested
    deeper than it goes (FastAPI's undocumented 400): each a 422 on every operation with a
    body, quoting the text."""
    c = contract(client)
    text = {**AUTH, "Content-Type": "text/plain"}
    as_json = {**AUTH, "Content-Type": "application/json"}
    for method, path, op in list(c.operations()):
        if "requestBody" not in op:
            continue
        url = path.format(**PATH_VALUES)
        r = c.call(method, url, content=b'{"frame": "0"}', headers=text)
        assert r.status_code == 422, f"{method} {path}: {r.status_code}"
        assert r.json()["detail"][0]["input"] == '{"frame": "0"}', r.text
        for body in (b"\xa1\xc2 is not UTF-8", b"[" * 5000):
            r = c.call(method, url, content=body, headers=as_json)
            assert r.status_code == 422, f"{method} {path}: {r.status_code} {r.text[:200]}"
            assert r.json()["detail"][0]["type"] == "json_invalid", r.text
    r = c.call("POST", "/api/decode", content=b"\xa1\xc2", headers=as_json)
    assert r.json()["detail"][0]["loc"] == ["body", 0]


def test_copies_null_is_no_copies_given(client: TestClient) -> None:
    """``copies: null`` (the documented default) was a 500: the bounds of the integer were
    applied to null."""
    c = contract(client)
    body = {"pattern": "circle", "params": CIRCLE, "copies": None}
    r = c.call("POST", "/api/commands", json=body, headers=AUTH)
    assert r.status_code == 202 and r.json()["copies"] == 1, r.text  # two-way: one copy
    retry = f"/api/commands/{interrupted_record(client)}/retry"
    assert c.call("POST", retry, json={"copies": None}, headers=AUTH).status_code == 202


def test_the_document_bounds_only_with_json_schema_keywords(client: TestClient) -> None:
    """pydantic writes a bound it checks after a validator under its own name (``ge``,
    ``lt``), which bounds nothing in a JSON Schema: PUT /api/link's fields were unbounded
    (schemathesis sent ``delivery_target`` 0 and 2e16 as valid)."""
    spec = contract(client).spec
    found: list[str] = []

    def walk(node: Any, where: str, names: bool = False) -> None:
        if isinstance(node, dict):
            for key, value in node.items():
                if key in PYDANTIC_ONLY and not names:
                    found.append(f"{where}/{key}")
                walk(value, f"{where}/{key}", names=key == "properties" and not names)
        elif isinstance(node, list):
            for i, item in enumerate(node):
                walk(item, f"{where}/{i}")

    walk(spec, "")
    assert not found
    link = spec["components"]["schemas"]["LinkIn"]["properties"]
    assert {"type": "number", "minimum": 0, "exclusiveMaximum": 0.5} in link["link_ber"]["anyOf"]
    bounded = {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 1}
    assert bounded in link["delivery_target"]["anyOf"]


def test_503_while_the_console_cannot_take_commands(client: TestClient) -> None:
    c = contract(client)
    console = console_of(client)
    retry = f"/api/commands/{interrupted_record(client)}/retry"
    service, console.service = console.service, None
    try:
        body = {"pattern": "circle", "params": CIRCLE}
        assert c.call("POST", "/api/commands", json=body, headers=AUTH).status_code == 503
        assert c.call("POST", "/api/surface", headers=AUTH).status_code == 503
        assert c.call("POST", retry, headers=AUTH).status_code == 503
    finally:
        console.service = service


@pytest.mark.training
def test_503_when_a_new_dive_cannot_be_logged(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    c = contract(client)
    log = console_of(client).log

    def full(_target: str) -> int:
        raise LogWriteError("database or disk is full")

    monkeypatch.setattr(log, "new_dive", full)
    assert c.call("POST", "/api/training/reset", headers=AUTH).status_code == 503
    assert c.call("POST", "/api/training/scenario/wreck", headers=AUTH).status_code == 503


# --- no field dropped -----------------------------------------------------------------------


def dumped(model: Any) -> Any:
    """A handler's model (or list of them) as the API serialises it."""
    if isinstance(model, list):
        return [dumped(m) for m in model]
    assert isinstance(model, BaseModel), model
    return model.model_dump(mode="json", by_alias=True, exclude_unset=True)


@pytest.mark.training
def test_the_models_drop_nothing_the_handlers_return(client: TestClient) -> None:
    """The responses hold every key of the handlers' own models (called directly), at every
    depth; and of the documents the handlers build them from (the log's rows, the runner's
    state, the simulator's settings, the telemetry, the profile, the station): a model that
    dropped a field of its source would fail here. The dictionary and a record are their
    sources exactly."""
    c = contract(client)
    console = console_of(client)
    first_pose(client)
    sent = c.call(
        "POST", "/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH
    )
    cid = sent.json()["id"]
    wait_state(client, cid, ("acknowledged",))
    c.call("PUT", "/api/training/time_scale", json={"time_scale": 0}, headers=AUTH)  # pause
    c.call("POST", "/api/scripts/run", json={"script": SCRIPT, "mode": "step"}, headers=AUTH)
    assert console.log is not None

    assert c.call("GET", "/api/dictionary").json() == describe_dictionary()
    record = c.call("GET", f"/api/commands/{cid}").json()
    assert record == console.log.command(cid)
    assert record["ack"]["from"] and record["ack"]["channel_flipped_bits"] == 0
    request = Request({"type": "http", "headers": [], "app": client.app, "server": None})
    for url, raw in (
        ("/api/session", lambda: authoring.session(request, console)),
        ("/api/commands", lambda: commands.commands(console, LogFilter(), 200)),
        ("/api/dives", lambda: commands.dives(console)),
        ("/api/dives/1", lambda: commands.dive(1, console)),
        ("/api/vehicle", lambda: commands.vehicle(console)),
        ("/api/training", lambda: training.training(console)),
        ("/api/scripts/run", lambda: scripts.run_state(console)),
    ):
        same_keys(c.call("GET", url).json(), dumped(raw()), url)
    assert c.call("GET", "/api/dives/1").json()["commands"] == console.log.commands(
        dive=1, limit=10, oldest_first=True
    )
    run = c.call("GET", "/api/scripts/run").json()
    assert console.runner is not None
    same_keys({k: v for k, v in run.items() if k != "commands"}, console.runner.state(), "run")
    sim = console.sim
    assert sim is not None
    on = c.call("GET", "/api/training").json()
    same_keys(on["channel"], asdict(sim.channel.config), "channel")
    same_keys(on["current"], asdict(sim.current.config), "current")
    same_keys(on["channel_stats"], asdict(sim.channel.stats), "channel_stats")
    assert "vehicle_channel_stats" not in on  # a fleet's only
    vehicle = c.call("GET", "/api/vehicle").json()
    same_keys(vehicle["pose"], console.hub.pose, "pose")
    same_keys(vehicle["status"], console.hub.status, "status")
    same_keys(c.call("GET", "/api/session").json()["profile"], asdict(console.profile))
    same_keys(c.call("GET", "/api/chart").json()["station"], console.station().as_dict())
    preview = c.call("POST", "/api/preview", json={"pattern": "square", "params": SQUARE})
    same_keys(preview.json(), console.preview("square", SQUARE, show=False))


# --- docs/api.md ----------------------------------------------------------------------------


def documented_endpoints() -> dict[tuple[str, str], dict[str, Any]]:
    """docs/api.md's endpoint table: (METHOD, normalised path) -> lock, ok status, errors."""
    text = DOCS.read_text()
    section = text.split("## Endpoints", 1)[1].split("\n#", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("| ")]
    header = [cell.strip() for cell in rows[0].strip("|").split("|")]
    assert header[:4] == ["method", "path", "ok", "errors"], header
    table: dict[tuple[str, str], dict[str, Any]] = {}
    for row in rows[1:]:
        cells = [cell.strip() for cell in re.split(r"(?<!\\)\|", row.strip().strip("|"))]
        method, paths, ok, errs = cells[:4]
        locked = "🔒" in method
        for path in re.findall(r"`(/api[^`]*)`", paths):
            key = (method.replace("🔒", "").strip(), normal(path))
            assert key not in table, f"{key} twice in docs/api.md"
            table[key] = {
                "locked": locked,
                "ok": int(ok),
                "errors": {int(e) for e in re.findall(r"\d{3}", errs)},
            }
    return table


def test_docs_api_md_lists_every_operation_as_the_openapi_does(client: TestClient) -> None:
    c = contract(client)
    docs = documented_endpoints()
    spec = {(m, normal(p)): op for m, p, op in c.operations()}
    assert set(docs) - set(spec) == set(), "documented but not in the OpenAPI"
    assert set(spec) - set(docs) == set(), "in the OpenAPI but not in docs/api.md"
    for key, op in spec.items():
        codes = {int(code) for code in op["responses"]}
        row = docs[key]
        assert row["locked"] == ("security" in op), f"{key}: the lock marker"
        assert {row["ok"]} == {code for code in codes if code < 300}, f"{key}: ok status"
        assert row["errors"] == {code for code in codes if code >= 400}, f"{key}: errors"


#: The survey preview's models, all named in its one section.
SURVEY_MODELS = (
    "SurveyPreviewDoc",
    "SurveyVehicleDoc",
    "SurveyPosition",
    "SurveyBlock",
    "SurveyEntry",
    "SurveyFootprint",
    "SurveyPath",
    "SurveyCoverage",
)


@pytest.mark.parametrize(
    "shape", ["Command record", "Preview response", "Link health", "Survey preview"]
)
def test_docs_api_md_names_every_field_of_its_shapes(client: TestClient, shape: str) -> None:
    """The documented shapes name every property of their models."""
    schemas = contract(client).spec["components"]["schemas"]
    models = {
        "Command record": ("CommandRecord",),
        "Preview response": ("PreviewDoc",),
        "Link health": ("LinkHealth",),
        "Survey preview": SURVEY_MODELS,
    }[shape]
    text = DOCS.read_text()
    section = text.split(f"### {shape}", 1)[1].split("\n### ", 1)[0]
    missing = [
        p
        for model in models
        for p in schemas[model]["properties"]
        if not re.search(rf"\b{p}\b", section)
    ]
    assert not missing, f"docs/api.md '{shape}' does not mention {missing}"
