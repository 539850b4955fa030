"""Strict input on a real uvicorn server, for every JSON endpoint of the OpenAPI and for /ws:
a lone surrogate anywhere, a number in non-ASCII digits and a boolean where a number goes
are each a 422 naming the field, and the next request on the same keep-alive connection
succeeds. The endpoints and their fields are read from the OpenAPI: a new JSON endpoint is
covered once its model has a valid body in :data:`BASES` (the test says so until it has).
And with the operator token in a path segment, a query, a header and a body, no log line
of any logger at any level holds it, and no logging error is met."""

from __future__ import annotations

import copy
import json
import logging
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import pytest
from uvicorn.logging import AccessFormatter
from websockets.sync.client import connect

from backend.app import create_app
from codec import ASCII_DIGITS

from .conftest import CIRCLE, clear_nemesys_env, settings_for
from .live_server import client_port, serve

#: The operator token of this module's console: distinctive, so a log line holding it is
#: found by a plain search.
SECRET = "strict-input-operator-token-" + "k" * 12
AUTH = {"Authorization": f"Bearer {SECRET}"}
JSON = {"content-type": "application/json"}
LONE = "\ud800"  # written by json.dumps as the escape \ud800: valid JSON, not a character
DIGITS = ("\u0661\u0660", "\uff11\uff10")  # ten in Arabic-Indic and in fullwidth digits

SCRIPT: dict[str, Any] = {
    "format": "nemesys-mission-script",
    "version": 1,
    "name": "strict",
    "steps": [{"pattern": "circle", "params": CIRCLE, "trigger": {"kind": "at", "t_s": 0}}],
}
#: A valid body of every request model, by its OpenAPI schema name; a test changes one value.
#: A fleet survey of two lanes for one vehicle (POST /api/survey/preview).
SURVEY_AREA: dict[str, Any] = {
    "origin_x_m": 0.0,
    "origin_y_m": 0.0,
    "heading_deg": 0.0,
    "width_m": 20.0,
    "length_m": 50.0,
    "lane_spacing_m": 10.0,
    "depth_m": 5.0,
    "speed_mps": 0.18,
}
SURVEY_VEHICLE: dict[str, Any] = {"vehicle": "auv1", "x_m": 0.0, "y_m": 0.0, "heading_deg": 0.0}
BASES: dict[str, dict[str, Any]] = {
    "CommandIn": {"pattern": "circle", "params": CIRCLE},
    "SendIn": {"pattern": "circle", "params": CIRCLE, "override": False, "copies": 1},
    "RetryIn": {"copies": 1},
    "DecodeIn": {"frame": "0" * 100},
    "LinkIn": {"link_ber": 0.001, "delivery_target": 0.99},
    "ChannelIn": {},
    "CurrentIn": {},
    "TimeScaleIn": {"time_scale": 1.0},
    "MissionScript": SCRIPT,
    "RunIn": {"script": SCRIPT, "mode": "step"},
    "DatumIn": {"lat_deg": 1.0, "lon_deg": 2.0},
    "ReplayAtIn": {"dive": 1, "t_s": 0.0, "vehicle": "nemesys"},  # a fleet's names its vehicle
    "SurveyIn": {"area": SURVEY_AREA, "vehicles": [SURVEY_VEHICLE]},
    "ControlIn": {"action": "request", "vehicle": "nemesys", "takeover_allowed": False},
    "SurfaceIn": {"vehicle": "nemesys"},  # issue 23: a fleet's Surface names its vehicle
}
#: A value for every path parameter of the API.
PATH_VALUES = {"command_id": "1", "dive": "1", "z": "0", "x": "0", "y": "0", "name": "wreck"}

Loc = tuple[str | int, ...]


@dataclass(frozen=True)
class Slot:
    """One value of a body: where, whether the schema takes a number there, and whether it
    takes text too (a number written as text is then parsed: the ASCII rule applies)."""

    path: Loc
    number: bool
    text: bool


@dataclass(frozen=True)
class Endpoint:
    method: str
    url: str
    base: dict[str, Any]
    slots: tuple[Slot, ...]

    def __str__(self) -> str:
        return f"{self.method} {self.url}"


def _resolve(spec: dict[str, Any], schema: dict[str, Any]) -> dict[str, Any]:
    while "$ref" in schema:
        schema = spec["components"]["schemas"][schema["$ref"].rsplit("/", 1)[1]]
    return schema


def _model(schema: dict[str, Any]) -> str:
    for option in (schema, *schema.get("anyOf", ())):
        if "$ref" in option:
            return str(option["$ref"].rsplit("/", 1)[1])
    raise AssertionError(f"a JSON body that is no model: {schema}")


def _slots(spec: dict[str, Any], schema: dict[str, Any], base: Any, path: Loc) -> Iterator[Slot]:
    schema = _resolve(spec, schema)
    options = [_resolve(spec, s) for s in schema.get("anyOf", ())] or [schema]
    objects = [o for o in options if "properties" in o or o.get("type") == "object"]
    arrays = [o for o in options if o.get("type") == "array"]
    if objects:
        props, given = objects[0].get("properties", {}), base if isinstance(base, dict) else {}
        for name, sub in props.items():
            yield from _slots(spec, sub, given.get(name), (*path, name))
        extra = objects[0].get("additionalProperties")
        if isinstance(extra, dict):  # a map (a command's params): the base's keys
            for key, value in given.items():
                yield from _slots(spec, extra, value, (*path, key))
    elif arrays and isinstance(base, list) and base:
        yield from _slots(spec, arrays[0]["items"], base[0], (*path, 0))
    else:
        kinds = {o.get("type") for o in options}
        number = bool(kinds & {"number", "integer"}) and not isinstance(base, str)
        yield Slot(path, number, number and "string" in kinds)


def endpoints(spec: dict[str, Any]) -> list[Endpoint]:
    """Every operation of the OpenAPI that takes a JSON body."""
    out = []
    for path, operations in spec["paths"].items():
        for method, op in operations.items():
            content = op.get("requestBody", {}).get("content", {})
            if "application/json" not in content:
                continue
            name = _model(content["application/json"]["schema"])
            assert name in BASES, f"{method.upper()} {path} takes {name}: add a body to BASES"
            slots = _slots(spec, content["application/json"]["schema"], BASES[name], ())
            out.append(Endpoint(method.upper(), path.format(**PATH_VALUES), BASES[name], (*slots,)))
    return out


#: The OpenAPI of the app (as its server answers /openapi.json; built without starting it).
SPEC = create_app(settings_for(Path("unused.sqlite3"), token=SECRET), viewer=False).openapi()
ENDPOINTS = endpoints(SPEC)


def put(base: dict[str, Any], path: Loc, value: Any) -> dict[str, Any]:
    """``base`` with the value at ``path`` replaced (or added)."""
    doc = copy.deepcopy(base)
    node: Any = doc
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return doc


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """One training console for the module, at uvicorn's most verbose level (trace)."""
    with pytest.MonkeyPatch.context() as mp:
        clear_nemesys_env(mp)
        db = tmp_path_factory.mktemp("strict") / "missions.sqlite3"
        app = create_app(settings_for(db, token=SECRET), viewer=False)
        with serve(app, log_level="trace") as url:
            yield url


@pytest.fixture
def http(server: str) -> Iterator[httpx.Client]:
    with httpx.Client(base_url=server, headers=AUTH, timeout=30, trust_env=False) as client:
        yield client


def still_open(http: httpx.Client, answer: httpx.Response) -> None:
    """The connection that carried ``answer`` serves the next request."""
    assert "close" not in answer.headers.get("connection", "")
    ok = http.get("/api/session")
    assert ok.status_code == 200, ok.text
    assert client_port(ok) == client_port(answer), "the connection was not kept"


def refused(http: httpx.Client, ep: Endpoint, body: str, path: Loc) -> dict[str, Any]:
    """The 422 error naming ``path`` that ``body`` gets; the connection stays usable."""
    r = http.request(ep.method, ep.url, content=body.encode(), headers=JSON)
    assert r.status_code == 422, f"{ep} {body[:200]}: {r.status_code} {r.text[:300]}"
    at = ["body", *path]
    named = [e for e in r.json()["detail"] if e["loc"][: len(at)] == at]
    assert named, f"{ep}: no error at {at}: {r.text[:400]}"
    still_open(http, r)
    error: dict[str, Any] = named[0]
    return error


def test_the_openapi_has_the_json_endpoints_expected() -> None:
    """The walk finds every JSON endpoint and its fields (a smaller set would test less)."""
    urls = {str(ep) for ep in ENDPOINTS}
    assert len(urls) == 18 and {"PUT /api/datum", "POST /api/survey/preview"} <= urls
    assert "POST /api/surface" in urls  # issue 23: its body names the vehicle
    assert "POST /api/control" in urls
    assert sum(len(ep.slots) for ep in ENDPOINTS) > 60
    by_url = {str(ep): ep.slots for ep in ENDPOINTS}
    assert Slot(("steps", 0, "params", "radius"), True, True) in by_url["POST /api/scripts/preview"]
    assert Slot(("lat_deg",), True, False) in by_url["PUT /api/datum"]


@pytest.mark.parametrize("ep", ENDPOINTS, ids=str)
def test_a_lone_surrogate_anywhere_is_a_422_naming_the_field(
    http: httpx.Client, ep: Endpoint
) -> None:
    for slot in ep.slots:
        error = refused(http, ep, json.dumps(put(ep.base, slot.path, LONE)), slot.path)
        assert error["type"] == "string_unicode" and "lone surrogate" in error["msg"]
        assert error["input"] == "\\ud800"
    # as a key: named by its escape
    error = refused(http, ep, json.dumps({**ep.base, f"a{LONE}": 1}), ("a\\ud800",))
    assert error["type"] == "string_unicode"


@pytest.mark.parametrize("ep", [ep for ep in ENDPOINTS if any(s.number for s in ep.slots)], ids=str)
def test_non_ascii_digits_and_booleans_are_not_numbers(http: httpx.Client, ep: Endpoint) -> None:
    for slot in (s for s in ep.slots if s.number):
        for digits in DIGITS:
            error = refused(http, ep, json.dumps(put(ep.base, slot.path, digits)), slot.path)
            if slot.text:  # parsed as text: the rule is said
                assert ASCII_DIGITS in error["msg"], error
        for boolean in (True, False):
            refused(http, ep, json.dumps(put(ep.base, slot.path, boolean)), slot.path)


def _number_parameters() -> list[tuple[str, str, str, str]]:
    """(method, path, where, name) of every path or query parameter that is a number."""
    out = []
    for path, operations in SPEC["paths"].items():
        for method, op in operations.items():
            for p in op.get("parameters", ()):
                options = p["schema"].get("anyOf", [p["schema"]])
                if {o.get("type") for o in options} & {"number", "integer"}:
                    out.append((method.upper(), path, p["in"], p["name"]))
    return out


@pytest.mark.parametrize(("method", "path", "where", "name"), _number_parameters())
def test_number_parameters_take_ascii_digits_only(
    http: httpx.Client, method: str, path: str, where: str, name: str
) -> None:
    op = SPEC["paths"][path][method.lower()]
    content = op.get("requestBody", {}).get("content", {}).get("application/json")
    body = json.dumps(BASES[_model(content["schema"])]) if content else None
    for value in (*DIGITS, "true"):
        values = {**PATH_VALUES, name: value} if where == "path" else PATH_VALUES
        params = {name: value} if where == "query" else None
        r = http.request(method, path.format(**values), params=params, content=body, headers=JSON)
        assert r.status_code == 422, f"{method} {path} {name}={value}: {r.text[:300]}"
        (error,) = [e for e in r.json()["detail"] if e["loc"] == [where, name]]
        if value != "true":
            assert ASCII_DIGITS in error["msg"], error
        still_open(http, r)


def test_ws_control_refuses_bad_text_numbers_and_booleans_and_stays_open(server: str) -> None:
    replies = ("error", "auth_ok", "queued")

    def reply(ws: Any, text: str) -> dict[str, Any]:
        ws.send(text)
        while True:
            msg: dict[str, Any] = json.loads(ws.recv(timeout=10))
            if msg["type"] in replies:
                return msg

    send: dict[str, Any] = {"type": "send", "pattern": "circle", "params": CIRCLE}
    with connect(server.replace("http", "ws", 1) + "/ws", open_timeout=10) as ws:
        # before authentication: the token itself a lone surrogate (it raised, closing /ws)
        msg = reply(ws, json.dumps({"type": "auth", "token": LONE}))
        assert msg["type"] == "error" and msg["field"] == "token" and "surrogate" in msg["detail"]
        assert reply(ws, json.dumps({"type": "auth", "token": SECRET}))["type"] == "auth_ok"
        for path in (("pattern",), ("params", "radius"), ("params", "direction")):
            msg = reply(ws, json.dumps(put(send, path, LONE)))
            assert msg["type"] == "error" and msg["field"] == ".".join(path), msg
        for digits in DIGITS:
            msg = reply(ws, json.dumps(put(send, ("params", "radius"), digits)))
            assert msg["field"] == "radius" and ASCII_DIGITS in msg["detail"], msg
        for path in (("params", "depth"), ("copies",)):
            msg = reply(ws, json.dumps(put(send, path, True)))
            assert msg["type"] == "error" and msg["field"] == path[-1], msg
        # the same connection still answers
        assert reply(ws, json.dumps({"type": "auth", "token": SECRET}))["type"] == "auth_ok"


# --- the token in no log line ----------------------------------------------------------------


class Capture(logging.Handler):
    """Every record, formatted as a plain line and, for uvicorn's access records, by
    uvicorn's own access formatter (which unpacks the record's arguments)."""

    def __init__(self) -> None:
        super().__init__(logging.NOTSET)
        self.setFormatter(logging.Formatter("%(name)s %(levelname)s %(message)s"))
        self.access = AccessFormatter('%(client_addr)s - "%(request_line)s" %(status_code)s')
        self.lines: list[str] = []
        self.names: set[str] = set()

    def emit(self, record: logging.LogRecord) -> None:
        self.names.add(record.name)
        try:  # as logging's own handlers do: a failure is a logging error, not the caller's
            self.lines.append(self.format(record))
            if record.name == "uvicorn.access":
                self.lines.append(self.access.format(record))
        except Exception:
            self.handleError(record)


@pytest.fixture
def capture(monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[Capture, list[str]]]:
    """All records of all loggers at DEBUG and below (uvicorn at trace), and every logging
    error any handler meets (``Handler.handleError``, which prints a dump of the record)."""
    errors: list[str] = []

    def handle_error(handler: logging.Handler, record: logging.LogRecord) -> None:
        errors.append(f"{type(handler).__name__}: {sys.exc_info()[1]!r}")

    monkeypatch.setattr(logging, "raiseExceptions", True)
    monkeypatch.setattr(logging.Handler, "handleError", handle_error)
    handler = Capture()
    loggers = [logging.getLogger()]
    loggers += [
        x for x in logging.Logger.manager.loggerDict.values() if isinstance(x, logging.Logger)
    ]
    levels = {logger: logger.level for logger in loggers}
    for logger in loggers:
        if logger.level > logging.DEBUG or logger is loggers[0]:
            logger.setLevel(logging.DEBUG)
        if logger is loggers[0] or not logger.propagate:
            logger.addHandler(handler)
    try:
        yield handler, errors
    finally:
        for logger, level in levels.items():
            logger.setLevel(level)
            logger.removeHandler(handler)


def test_the_token_reaches_no_log_line_at_any_level(
    server: str, http: httpx.Client, capture: tuple[Capture, list[str]]
) -> None:
    handler, errors = capture
    plain = httpx.Client(base_url=server, timeout=30, trust_env=False)
    with plain:
        assert plain.get("/api/session", params={"token": SECRET}).status_code == 200
        assert plain.get(f"/api/session?v=1&token={SECRET}&x=2").status_code == 200
        answer = plain.get(f"/api/commands/{SECRET}")  # a path segment: 422, echoed input
        assert answer.status_code == 422 and SECRET not in answer.text
        assert plain.get(f"/static/{SECRET}.js").status_code == 404
        assert plain.get("/api/session", headers={"X-Nemesys-Token": SECRET}).json()[
            "authenticated"
        ]
    assert http.get("/api/session").json()["authenticated"]  # Authorization: Bearer
    for url, body in (("/api/preview", {"pattern": SECRET}), ("/api/decode", {"frame": SECRET})):
        assert http.post(url, json=body).status_code == 422
    with connect(server.replace("http", "ws", 1) + f"/ws?token={SECRET}") as ws:
        ws.send(json.dumps({"type": "auth", "token": SECRET}))
        while json.loads(ws.recv(timeout=10))["type"] != "auth_ok":
            pass
    # the console's own loggers, every way a call can carry it, and calls that are wrong
    log = logging.getLogger("backend.strict_input_test")
    log.debug("%s - %r", SECRET, SECRET.encode())
    log.debug("%(token)s", {"token": SECRET})
    log.debug("headers %s", [(b"x-nemesys-token", SECRET.encode())])
    log.debug("failed", exc_info=ValueError(f"input {SECRET!r}"))
    log.debug("%s %s", SECRET)  # noqa: PLE1206 (one argument short: unformattable)
    log.debug("%d", SECRET)  # the wrong type

    assert errors == [], errors
    lines = handler.lines
    assert not [line for line in lines if SECRET in line]
    # what was captured is what this test says: each place, redacted, at every level
    assert {"uvicorn.access", "uvicorn.error", "uvicorn.asgi"} <= handler.names
    assert any('"GET /api/session?token=*** HTTP/1.1" 200' in line for line in lines)
    assert any('"GET /api/commands/*** HTTP/1.1" 422' in line for line in lines)
    assert any("x-nemesys-token" in line and "***" in line for line in lines)
    assert any("ValueError: input '***'" in line for line in lines)
