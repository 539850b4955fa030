"""The console's edges against a real server: the Host rule (DNS rebinding), the /ws Origin
rule, and no token in the logs at debug level."""

from __future__ import annotations

import json
import socket
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from backend.api.schemas.live import message_types
from backend.messages import News
from bench._server import ConsoleProcess, start_console
from tests.backend.conftest import TOKEN, clear_nemesys_env, wait_until

#: A `nemesys console` subprocess per test: make test, not make test-fast.
pytestmark = pytest.mark.slow

CIRCLE = {"speed": 0.18, "depth": 3, "radius": 5, "direction": "cw"}


@pytest.fixture
def server(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[ConsoleProcess]:
    """``nemesys console`` at debug log level: every log line goes to its output file."""
    clear_nemesys_env(monkeypatch)
    proc = start_console(
        tmp_path / "console.log",
        TOKEN,
        "--db",
        str(tmp_path / "m.sqlite3"),
        env={
            "NEMESYS_LOG_LEVEL": "debug",
            "NEMESYS_ALLOWED_ORIGINS": '["http://chart.ship:3000"]',
            "NO_PROXY": "127.0.0.1,localhost",
        },
    )
    try:
        yield proc
    finally:
        proc.stop()


def test_a_request_naming_another_host_is_refused(server: ConsoleProcess) -> None:
    base = server.base_url
    with httpx.Client(timeout=10) as http:
        assert http.get(f"{base}/api/session").status_code == 200
        for host in ("evil.example", "evil.example:80", f"attacker.test:{server.port}"):
            r = http.get(f"{base}/api/session", headers={"Host": host})
            assert r.status_code == 400, (host, r.status_code)
            assert "localhost" in r.json()["detail"] and "allowed_hosts" in r.json()["detail"]
        for host in (f"localhost:{server.port}", f"LOCALHOST:{server.port}", "127.0.0.1"):
            assert http.get(f"{base}/api/session", headers={"Host": host}).status_code == 200
    # a websocket handshake naming another host is refused too (raw: clients set Host)
    with socket.create_connection(("127.0.0.1", server.port), timeout=10) as sock:
        sock.sendall(
            b"GET /ws HTTP/1.1\r\nHost: evil.example\r\nUpgrade: websocket\r\n"
            b"Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
            b"Sec-WebSocket-Version: 13\r\n\r\n"
        )
        assert sock.recv(4096).startswith(b"HTTP/1.1 403")


def test_ws_origin_must_be_the_page_or_configured(server: ConsoleProcess) -> None:
    url = f"ws://127.0.0.1:{server.port}/ws"
    own = f"http://127.0.0.1:{server.port}"
    for origin in (own, "http://chart.ship:3000", None):
        extra = {} if origin is None else {"Origin": origin}
        with connect(url, additional_headers=extra, proxy=None, open_timeout=10) as ws:
            ws.send(json.dumps({"type": "ping"}))
            # accepted: the connection speaks (news every page gets, or the answer to the ping)
            assert json.loads(ws.recv(timeout=10))["type"] in {"error", *message_types(News)}
    for origin in ("http://evil.example", f"http://127.0.0.1:{server.port + 1}", "null"):
        with pytest.raises(InvalidStatus) as refused:
            connect(url, additional_headers={"Origin": origin}, proxy=None, open_timeout=10)
        assert refused.value.response.status_code == 403, origin


def test_the_token_reaches_no_log_at_debug_level(server: ConsoleProcess) -> None:
    base = server.base_url
    bearer = {"Authorization": f"Bearer {TOKEN}"}
    with httpx.Client(timeout=10) as http:
        assert http.get(f"{base}/?token={TOKEN}").status_code == 200
        assert http.get(f"{base}/api/session?token={TOKEN}", headers=bearer).status_code == 200
        r = http.post(
            f"{base}/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=bearer
        )
        assert r.status_code == 202, r.text
        r = http.get(f"{base}/api/session", headers={"X-Nemesys-Token": TOKEN})
        assert r.status_code == 200
    with connect(f"ws://127.0.0.1:{server.port}/ws", proxy=None, open_timeout=10) as ws:
        ws.send(json.dumps({"type": "auth", "token": TOKEN}))
        wait_until(lambda: json.loads(ws.recv(timeout=10))["type"] == "auth_ok", 10)
    # the access log has seen the requests (so the check below is not vacuous)
    wait_until(lambda: "/api/commands" in server.log_path.read_text(), 10, what="access log")
    lines = server.log_path.read_text().splitlines()
    printed = [line for line in lines if "?token=" in line and line.strip().startswith("http")]
    leaked = [line for line in lines if TOKEN in line and line not in printed]
    assert len(printed) == 1, "the URL with the token is printed once, for the operator"
    assert not leaked, leaked
    assert any("token=***" in line for line in lines), "the query string was redacted"
