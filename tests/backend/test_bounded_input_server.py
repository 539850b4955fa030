"""Bounded input on the real ``nemesys console`` (uvicorn, the simulated vehicle): a 50 MB
body is refused without being read, while another client's ``GET /api/session`` keeps its
latency and the server's memory does not grow; /ws answers over-size and over-deep control
messages through uvicorn's websocket and stays usable."""

from __future__ import annotations

import json
import socket
import statistics
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect
from websockets.sync.connection import Connection

from backend.api.live import MAX_CONTROL_BYTES, MAX_CONTROL_DEPTH
from backend.api.schemas.live import message_types
from backend.messages import News
from bench._server import ConsoleProcess, start_console
from tests.backend.conftest import TOKEN, clear_nemesys_env

#: A `nemesys console` subprocess per test (uvicorn's own limits): make test, not make test-fast.
pytestmark = pytest.mark.slow

CAP = 65536
BIG = 50 * 1024 * 1024
CHUNK = 65536
JSON = {"content-type": "application/json"}
#: Worst latency allowed for a GET /api/session during the uploads (generous: shared CI).
WORST_S = 1.0
#: Growth of the server's peak memory (VmHWM) allowed over the uploads: far below one 50 MB
#: body.
PEAK_GROWTH_KIB = 20 * 1024


@pytest.fixture
def server(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[ConsoleProcess]:
    clear_nemesys_env(monkeypatch)
    with start_console(
        tmp_path / "console.log",
        TOKEN,
        *("--db", str(tmp_path / "missions.sqlite3")),
        env={"NO_PROXY": "127.0.0.1,localhost"},
    ) as console:
        yield console


def memory_kib(pid: int) -> dict[str, int]:
    """The process's resident set now (VmRSS) and at its peak so far (VmHWM), KiB."""
    out: dict[str, int] = {}
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        name, _, value = line.partition(":")
        if name in ("VmRSS", "VmHWM"):
            out[name] = int(value.split()[0])
    return out


def test_content_length_over_the_cap_is_answered_before_the_body_is_sent(
    server: ConsoleProcess,
) -> None:
    host = server.host or "127.0.0.1"
    with socket.create_connection((host, server.port), timeout=5) as sock:
        sock.sendall(
            b"POST /api/commands HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
            b"Content-Length: %d\r\n\r\n" % BIG
        )
        answer = b""
        while chunk := sock.recv(65536):  # the server closes after its 413
            answer += chunk
    head, _, body = answer.partition(b"\r\n\r\n")
    assert head.startswith(b"HTTP/1.1 413"), answer[:200]
    assert b"connection: close" in head.lower()
    assert json.loads(body) == {"detail": f"request body over {CAP} bytes"}


#: The uploader, a process of its own (building 50 MB in this one would hold its GIL and
#: slow the polling client, not the server): two bodies with Content-Length, two chunked.
UPLOADER = f"""
import json, sys, httpx
def chunks():
    for _ in range({BIG // CHUNK}):
        yield b" " * {CHUNK}
out = []
with httpx.Client(base_url=sys.argv[1], timeout=30, trust_env=False) as http:
    for content in (b" " * {BIG}, chunks(), b" " * {BIG}, chunks()):
        try:
            r = http.post("/api/preview", content=content, headers={JSON!r})
            out.append(str(r.status_code))
        except httpx.TransportError as err:  # the server closed while we wrote
            out.append(type(err).__name__)
print(json.dumps(out))
"""


def test_50_mb_bodies_cost_the_server_nothing(server: ConsoleProcess) -> None:
    """Four 50 MB uploads while another client polls the session: its latency stays small
    and the server's peak memory flat."""
    before = memory_kib(server.pid)
    latencies: list[float] = []
    with server.client() as http:
        for _ in range(20):  # warm: the first calls pay for imports and connections
            assert http.get("/api/session").status_code == 200
        uploader = subprocess.Popen(
            [sys.executable, "-c", UPLOADER, server.base_url], stdout=subprocess.PIPE, text=True
        )
        try:
            while uploader.poll() is None or len(latencies) < 50:
                start = time.perf_counter()
                assert http.get("/api/session").status_code == 200
                latencies.append(time.perf_counter() - start)
            out, _ = uploader.communicate(timeout=60)
        finally:
            if uploader.poll() is None:
                uploader.kill()
                uploader.wait()
    after = memory_kib(server.pid)
    outcomes = json.loads(out)
    median, worst = statistics.median(latencies), max(latencies)
    report = (
        f"{len(latencies)} GETs: median {median * 1e3:.1f} ms, worst {worst * 1e3:.1f} ms; "
        f"uploads {outcomes}; RSS {before['VmRSS']} -> {after['VmRSS']} KiB, "
        f"peak {before['VmHWM']} -> {after['VmHWM']} KiB"
    )
    print(report)
    assert len(outcomes) == 4 and all(o in ("413", "WriteError") for o in outcomes), report
    assert worst < WORST_S, report
    assert after["VmHWM"] - before["VmHWM"] < PEAK_GROWTH_KIB, report


NEWS = message_types(News)


def test_ws_limits_through_uvicorn(server: ConsoleProcess) -> None:
    deep = MAX_CONTROL_DEPTH + 1

    def reply(ws: Connection, text: str) -> dict[str, object]:
        ws.send(text)
        while True:
            msg: dict[str, object] = json.loads(ws.recv(timeout=5))
            if msg["type"] not in NEWS:  # the news every page gets (a belief, the link, ...)
                return msg

    with connect(server.ws_url, open_timeout=5) as ws:
        over = reply(ws, " " * (MAX_CONTROL_BYTES * 4))
        assert over == {"type": "error", "detail": f"message over {MAX_CONTROL_BYTES} bytes"}
        nested = reply(ws, "[" * deep + "]" * deep)
        assert nested == {
            "type": "error",
            "detail": f"message nested deeper than {MAX_CONTROL_DEPTH}",
        }
        assert reply(ws, json.dumps({"type": "auth", "token": TOKEN})) == {"type": "auth_ok"}
        # over uvicorn's own limit (ws_max_size): our reply, or a 1009 close; never silence
        try:
            assert reply(ws, " " * (CAP + 10))["detail"] == over["detail"]
        except ConnectionClosed as closed:
            assert closed.rcvd is not None and closed.rcvd.code == 1009


def test_ws_pages_get_uncompressed_messages(server: ConsoleProcess) -> None:
    """A page that offers permessage-deflate (as browsers and the websockets client do) is
    answered without it: compression is per connection, so each message would be encoded
    again for every page; sent as it is, one serialisation's bytes go to all of them."""
    with connect(server.ws_url, open_timeout=5) as ws:  # offers permessage-deflate
        assert ws.request is not None and ws.response is not None
        assert "permessage-deflate" in ws.request.headers.get("Sec-WebSocket-Extensions", "")
        assert "Sec-WebSocket-Extensions" not in ws.response.headers
        assert json.loads(ws.recv(timeout=30))["type"]  # and the news still comes
