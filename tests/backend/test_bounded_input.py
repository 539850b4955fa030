"""Bounded input (issue 13): request bodies capped before they are read, /ws control messages
capped in size and nesting, 422 bodies quoting only an excerpt of the input, integers held to
SQLite's signed 64 bits, booleans, NaN and infinity refused as numbers. In-process (TestClient);
the real server under a 50 MB upload is in ``test_bounded_input_server.py``."""

from __future__ import annotations

import json
import re
from typing import Any

import anyio
import pytest
from fastapi.testclient import TestClient
from starlette.requests import ClientDisconnect, Request
from starlette.responses import PlainTextResponse
from starlette.types import Message, Receive, Scope, Send

from backend.api.live import MAX_CONTROL_BYTES, MAX_CONTROL_DEPTH, nesting_over
from backend.api.schemas.live import message_types
from backend.bounded_input import EXCERPT_CHARS, BodyLimit, excerpt
from backend.messages import News
from backend.settings import Settings
from cli.main import main as cli_main
from tests.backend.conftest import AUTH, CIRCLE, TOKEN, MakeClient, clear_nemesys_env, loc_of, send

CAP = 65536
OVER = {"detail": f"request body over {CAP} bytes"}
JSON = {"content-type": "application/json"}
#: Integers SQLite cannot hold (signed 64-bit), and a float's worth of digits.
OVERFLOW = [2**63, -(2**63) - 1, 10**30]
SCRIPT: dict[str, Any] = {
    "format": "nemesys-mission-script",
    "version": 1,
    "name": "one step",
    "steps": [{"pattern": "circle", "params": CIRCLE, "trigger": {"kind": "at", "t_s": 0}}],
}


def script(**step: Any) -> dict[str, Any]:
    doc: dict[str, Any] = json.loads(json.dumps(SCRIPT))
    doc["steps"][0].update(step)
    return doc


def raw(client: TestClient, url: str, text: str, method: str = "POST") -> Any:
    """A body as written (Python's json.loads reads NaN and Infinity; httpx never writes
    them)."""
    return client.request(method, url, content=text.encode(), headers={**JSON, **AUTH})


# --- the body cap -------------------------------------------------------------------------


@pytest.mark.parametrize("url", ["/api/commands", "/api/preview", "/api/scripts/run"])
@pytest.mark.parametrize("headers", [{}, AUTH])
def test_over_size_body_is_413_before_auth_or_parsing(
    client: TestClient, url: str, headers: dict[str, str]
) -> None:
    r = client.post(url, content=b"{" * (CAP + 1), headers={**JSON, **headers})
    assert r.status_code == 413 and r.json() == OVER
    assert r.headers["connection"] == "close"


def test_chunked_body_without_length_is_413(client: TestClient) -> None:
    chunks = (b" " * 65536 for _ in range(20))
    r = client.post("/api/preview", content=chunks, headers=JSON)
    assert "content-length" not in r.request.headers
    assert r.status_code == 413 and r.json() == OVER


def asgi_request(app: Any, chunks: int, chunk: bytes = b" " * 1000) -> tuple[int, list[Message]]:
    """Run one chunked POST through ``app``: how many chunks it pulled, and what it sent."""
    pulled = 0
    sent: list[Message] = []

    async def receive() -> Message:
        nonlocal pulled
        pulled += 1
        return {"type": "http.request", "body": chunk, "more_body": pulled < chunks}

    async def send(message: Message) -> None:
        sent.append(message)

    scope = {"type": "http", "method": "POST", "path": "/", "headers": [], "query_string": b""}
    anyio.run(app, scope, receive, send)
    return pulled, sent


def test_chunked_reading_stops_at_the_cap_and_the_app_answer_is_dropped() -> None:
    seen: list[str] = []

    async def app(scope: Scope, receive: Receive, send: Send) -> None:
        try:
            await Request(scope, receive).body()
        except ClientDisconnect:
            seen.append("disconnect")
        await PlainTextResponse("late", status_code=400)(scope, receive, send)

    pulled, sent = asgi_request(BodyLimit(app, max_bytes=10_000), chunks=50_000)  # 50 MB
    assert pulled == 11 and seen == ["disconnect"]
    assert [m.get("status") for m in sent] == [413, None]
    assert json.loads(sent[1]["body"]) == {"detail": "request body over 10000 bytes"}
    pulled, sent = asgi_request(BodyLimit(app, max_bytes=10_000), chunks=10)
    assert pulled == 10 and [m.get("status") for m in sent] == [400, None]


def test_a_response_already_started_is_not_replaced() -> None:
    async def streaming(scope: Scope, receive: Receive, send: Send) -> None:
        await send({"type": "http.response.start", "status": 200, "headers": []})
        while (await receive())["type"] == "http.request":
            pass  # ends at the disconnect the limit hands over
        await send({"type": "http.response.body", "body": b""})

    pulled, sent = asgi_request(BodyLimit(streaming, max_bytes=10_000), chunks=50_000)
    assert pulled == 11 and [m.get("status") for m in sent] == [200, None]


def test_bodies_up_to_the_cap_pass(client: TestClient) -> None:
    body = json.dumps({"pattern": "circle", "params": CIRCLE}).encode()
    padded = body + b" " * (CAP - len(body))
    assert client.post("/api/encode", content=padded, headers=JSON).status_code == 200
    chunked = iter([body[:10], body[10:], b" " * (CAP - len(body))])
    assert client.post("/api/encode", content=chunked, headers=JSON).status_code == 200
    assert client.post("/api/encode", content=padded + b" ", headers=JSON).status_code == 413


def test_the_cap_is_a_setting(make_client: MakeClient, monkeypatch: pytest.MonkeyPatch) -> None:
    client = make_client(max_body_bytes=10_000)
    r = client.post("/api/encode", content=b" " * 10_001, headers=JSON)
    assert r.status_code == 413 and r.json() == {"detail": "request body over 10000 bytes"}
    clear_nemesys_env(monkeypatch)
    assert Settings().max_body_bytes == CAP
    monkeypatch.setenv("NEMESYS_MAX_BODY_BYTES", "131072")
    assert Settings.load().max_body_bytes == 131072
    monkeypatch.setenv("NEMESYS_MAX_BODY_BYTES", "100")  # below the /ws control cap
    with pytest.raises(ValueError, match="max_body_bytes"):
        Settings.load()


# --- 422 bodies quote an excerpt ----------------------------------------------------------

BIG = "x" * 10_000


def assert_short(response: Any, limit: int = 1000) -> None:
    assert response.status_code == 422, response.text
    assert len(response.content) < limit, response.text[:2000]
    run = max((len(m) for m in re.findall("x+", response.text)), default=0)
    assert run <= EXCERPT_CHARS, run
    for error in response.json()["detail"]:
        assert set(error) <= {"loc", "msg", "type", "input"}


@pytest.mark.parametrize(
    "body",
    [
        {"pattern": BIG, "params": CIRCLE},
        {"pattern": "circle", "params": {**CIRCLE, "direction": BIG}},
        {"pattern": "circle", "params": {**CIRCLE, BIG: 1}},
        {"pattern": "circle", "params": CIRCLE, BIG: 1},
        {"params": {"speed": BIG}},  # "missing pattern": its input is the whole body
        {"pattern": "circle", "params": [BIG]},
    ],
)
def test_422_quotes_only_an_excerpt_of_the_input(client: TestClient, body: Any) -> None:
    assert_short(client.post("/api/preview", json=body))


def test_422_excerpts_keep_loc_msg_type_and_short_inputs(client: TestClient) -> None:
    r = client.post("/api/preview", json={"pattern": "circle", "params": {**CIRCLE, "x": [1]}})
    (error,) = r.json()["detail"]
    assert error["loc"] == ["body", "params", "x"] and error["input"] == [1]
    assert error["type"] == "value_error" and "number or a text" in error["msg"]
    r = client.post("/api/preview", content=b'{"pattern": ', headers=JSON)
    (error,) = r.json()["detail"]
    assert error["type"] == "json_invalid" and error["msg"].startswith("JSON decode error: ")


def test_script_422_quotes_only_an_excerpt(client: TestClient) -> None:
    assert_short(client.post("/api/scripts/preview", json=script(pattern=BIG)))
    assert_short(client.post("/api/scripts/preview", json={**SCRIPT, "name": BIG}))
    # the codec's own message quotes the value: at most the 300-character msg excerpt
    r = client.post("/api/scripts/preview", json=script(params={**CIRCLE, "direction": BIG}))
    assert r.status_code == 422 and len(r.content) < 1500


def test_excerpt() -> None:
    assert excerpt("abc") == "abc" and excerpt([1, 2]) == [1, 2] and excerpt(None) is None
    assert excerpt(float("nan")) == "nan" and excerpt(float("-inf")) == "-inf"
    assert len(excerpt("x" * 1000)) == EXCERPT_CHARS and excerpt("x" * 1000).endswith("…")
    assert len(excerpt({"a": "x" * 1000})) == EXCERPT_CHARS
    assert excerpt(10**30) == 10**30 and excerpt(10**100) == "<an integer of 333 bits>"
    assert excerpt([float("nan")]) == "[NaN]"  # text: JSON has no NaN


# --- integers SQLite can hold -------------------------------------------------------------


@pytest.mark.parametrize("value", OVERFLOW)
def test_overflowing_integers_in_bodies_are_422(client: TestClient, value: int) -> None:
    r = client.post(
        "/api/preview", json={"pattern": "circle", "params": {**CIRCLE, "radius": value}}
    )
    assert r.status_code == 422 and loc_of(r.json()) == ["body", "params", "radius"]
    r = client.post(
        "/api/commands", json={"pattern": "circle", "params": CIRCLE, "copies": value}, headers=AUTH
    )
    assert r.status_code == 422 and loc_of(r.json()) == ["body", "copies"]
    rec = send(client)
    r = client.post(f"/api/commands/{rec['id']}/retry", json={"copies": value}, headers=AUTH)
    assert r.status_code == 422 and loc_of(r.json()) == ["body", "copies"]
    r = client.put("/api/training/channel", json={"burst_length_bits": value}, headers=AUTH)
    assert r.status_code == 422 and loc_of(r.json()) == ["body", "burst_length_bits"]
    r = client.put("/api/training/time_scale", json={"time_scale": value}, headers=AUTH)
    assert r.status_code == 422 and loc_of(r.json()) == ["body", "time_scale"]
    r = client.post("/api/scripts/preview", json=script(params={**CIRCLE, "radius": value}))
    assert r.status_code == 422 and loc_of(r.json())[:4] == ["body", "steps", 0, "params"]


@pytest.mark.parametrize("value", OVERFLOW)
@pytest.mark.parametrize(
    ("method", "url"),
    [
        ("GET", "/api/commands/{}"),
        ("POST", "/api/commands/{}/retry"),
        ("GET", "/api/dives/{}"),
        ("POST", "/api/dives/{}/replay"),
        ("GET", "/api/commands?dive={}"),
        ("GET", "/api/log.json?dive={}"),
        ("GET", "/api/log.csv?dive={}"),
        ("GET", "/api/commands?limit={}"),
        ("GET", "/api/log.json?limit={}"),
    ],
)
def test_overflowing_ids_in_paths_and_queries_are_422(
    client: TestClient, method: str, url: str, value: int
) -> None:
    r = client.request(method, url.format(value), headers=AUTH)
    assert r.status_code == 422, r.text
    assert len(r.content) < 1000


def test_integers_too_long_to_parse_are_not_500(client: TestClient) -> None:
    text = '{"pattern": "circle", "params": {"radius": %s}}' % ("9" * 5000)
    assert raw(client, "/api/preview", text).status_code in (400, 422)
    text = '{"pattern": "circle", "params": {"radius": %s}}' % ("[" * 5000 + "]" * 5000)
    assert raw(client, "/api/preview", text).status_code in (400, 422)


# --- booleans, NaN and infinity are not numbers -------------------------------------------

#: JSON that is not a number: a boolean, the NaN and infinities Python's parser accepts, and
#: a numeric text (which only a command parameter may be: the codec reads it).
NOT_NUMBERS = ["true", "NaN", "Infinity", "-Infinity"]
CIRCLE_WITH = '{"pattern": "circle", "params": {"speed": 0.2, "depth": 3, "radius": 5, '
NUMBER_FIELDS = [
    ("POST", "/api/preview", CIRCLE_WITH.replace("0.2", "%s") + '"direction": "cw"}}', "params"),
    ("POST", "/api/commands", CIRCLE_WITH + '"direction": "cw"}, "copies": %s}', "copies"),
    ("PUT", "/api/training/channel", '{"ber": %s}', "ber"),
    ("PUT", "/api/training/channel", '{"range_m": %s}', "range_m"),
    ("PUT", "/api/training/channel", '{"burst_length_bits": %s}', "burst_length_bits"),
    ("PUT", "/api/training/current", '{"north_mps": %s}', "north_mps"),
    ("PUT", "/api/training/time_scale", '{"time_scale": %s}', "time_scale"),
    ("PUT", "/api/link", '{"delivery_target": %s}', "delivery_target"),
]


@pytest.mark.parametrize(
    ("method", "url", "template", "field", "value"),
    [
        (*case, value)
        for case in NUMBER_FIELDS
        for value in NOT_NUMBERS + (['"1"'] if case[3] != "params" else [])
    ],
)
def test_booleans_nan_and_infinity_are_refused_naming_the_field(
    client: TestClient, method: str, url: str, template: str, field: str, value: str
) -> None:
    r = raw(client, url, template % value, method)
    loc = ["body", "params", "speed"] if field == "params" else ["body", field]
    assert r.status_code == 422, r.text
    assert loc_of(r.json()) == loc
    json.loads(r.text)  # valid JSON: no NaN echoed back


@pytest.mark.parametrize("value", ["true", "NaN", "Infinity"])
def test_script_numbers_refuse_nan_and_infinity(client: TestClient, value: str) -> None:
    doc = json.dumps(script(trigger={"kind": "at", "t_s": "T"}))
    r = raw(client, "/api/scripts/preview", doc.replace('"T"', value))
    assert r.status_code == 422 and loc_of(r.json())[:3] == ["body", "steps", 0]
    doc = json.dumps(script(params={**CIRCLE, "radius": "R"}))
    r = raw(client, "/api/scripts/preview", doc.replace('"R"', value))
    assert r.status_code == 422 and loc_of(r.json())[:5] == ["body", "steps", 0, "params", "radius"]


# --- /ws control messages -----------------------------------------------------------------


#: The server's own messages, which may come between a control message and its answer.
NEWS = message_types(News)


def ws_reply(ws: Any, text: str) -> dict[str, Any]:
    ws.send_text(text)
    while True:
        msg: dict[str, Any] = ws.receive_json()
        if msg["type"] not in NEWS:  # the news every page gets (a belief, the link, ...)
            return msg


def test_ws_over_size_and_over_deep_messages_get_error_replies(client: TestClient) -> None:
    deep = MAX_CONTROL_DEPTH + 1
    with client.websocket_connect("/ws") as ws:
        assert ws_reply(ws, " " * (MAX_CONTROL_BYTES + 1)) == {
            "type": "error",
            "detail": f"message over {MAX_CONTROL_BYTES} bytes",
        }
        assert ws_reply(ws, "é" * (MAX_CONTROL_BYTES // 2 + 1))["detail"].startswith("message over")
        nested = {"type": "error", "detail": f"message nested deeper than {MAX_CONTROL_DEPTH}"}
        assert ws_reply(ws, "[" * deep + "]" * deep) == nested
        assert ws_reply(ws, "[" * MAX_CONTROL_BYTES) == nested  # never parsed: no recursion
        assert ws_reply(ws, '{"type": "send", "params": %s}' % ("{" * deep)) == nested
        assert ws_reply(ws, '{"type": "auth", "token": NaN}') == {
            "type": "error",
            "detail": "NaN is not a JSON number",
        }
        ok_depth = '{"type": "x", "a": %s}' % ("[" * (MAX_CONTROL_DEPTH - 1) + "]" * 31)
        assert ws_reply(ws, ok_depth)["detail"].startswith("unknown message type 'x'")
        brackets = json.dumps({"type": "auth", "token": "[{" * 100 + '\\"['})
        assert ws_reply(ws, brackets)["detail"] == "wrong operator token"
        assert ws_reply(ws, json.dumps({"type": "auth", "token": TOKEN})) == {
            "type": "auth_ok"
        }  # the connection stays usable


@pytest.mark.parametrize(
    ("text", "over"),
    [
        ("[]", False),
        ("[[[]]]", True),
        ("[[]][[]]", False),
        ('["[[[[", {"a": "]]]]{{{{"}]', False),
        ('["\\"[[[["]', False),
        ('["\\\\", [[[]]]]', True),
        ('{"a": {"b": {"c": 1}}}', True),
        ('"[[[["', False),
    ],
)
def test_nesting_scan(text: str, over: bool) -> None:
    assert nesting_over(text, 2) is over


# --- pattern names ------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["\u00b9", "\u0663", "x" * 10_000])
def test_cli_encode_unknown_pattern_text_is_usage_not_internal(
    name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert cli_main(["encode", name]) == 2
    err = capsys.readouterr().err
    assert err.startswith("nemesys encode: unknown pattern ") and "circle (3)" in err
    assert "internal error" not in err and len(err) < 300


@pytest.mark.parametrize(("name", "status"), [("\u0663", 422), ("\u00b9", 422), ("03", 200)])
def test_api_pattern_names_are_ascii(client: TestClient, name: str, status: int) -> None:
    r = client.post("/api/encode", json={"pattern": name, "params": CIRCLE})
    assert r.status_code == status, r.text
    if status == 422:
        assert loc_of(r.json()) == ["body", "pattern"] and "circle (3)" in r.text


def test_ws_error_replies_quote_an_excerpt(client: TestClient) -> None:
    with client.websocket_connect("/ws") as ws:
        answer = ws_reply(ws, json.dumps({"type": "x" * 3000}))
        assert (
            answer["detail"].startswith("unknown message type 'xxx") and len(answer["detail"]) < 100
        )
        ws_reply(ws, json.dumps({"type": "auth", "token": TOKEN}))
        params = {**CIRCLE, "direction": "x" * 3000}
        answer = ws_reply(ws, json.dumps({"type": "send", "pattern": "circle", "params": params}))
        assert answer["field"] == "direction" and len(answer["detail"]) <= 300
