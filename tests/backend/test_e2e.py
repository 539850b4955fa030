"""End to end: the real ``nemesys console`` (uvicorn, viser, the simulated vehicle behind its
rosbridge) as a subprocess, driven over HTTP with httpx on 127.0.0.1 only; and the mission
log surviving a killed server (SIGKILL), row by row."""

from __future__ import annotations

import json
import os
import queue
import re
import socket
import sqlite3
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
import pytest

from backend.settings import Settings
from backend.store import STATES, MissionLog

from .conftest import CIRCLE, SQUARE, TOKEN, clear_nemesys_env, wait_until

REPO = Path(__file__).resolve().parents[2]
AUTH = {"Authorization": f"Bearer {TOKEN}"}
URL_LINE = re.compile(r"(http://(127\.0\.0\.1):(\d+))/\?token=(\S+)")
EAST = {"speed": 1.0, "depth": 2, "duration": 600, "heading": 90}
#: Links to anything off this machine in the page's HTML, scripts or styles.
EXTERNAL = re.compile(
    r"""(?:src|href|action)\s*=\s*["']?\s*(?:https?:)?//"""
    r"""|\bimport\b[^;'"]*["'](?:https?:)?//"""
    r"""|\bimport\s*\(\s*["'](?:https?:)?//"""
    r"""|url\(\s*["']?(?:https?:)?//""",
    re.IGNORECASE,
)
LOCAL_REF = re.compile(r"""(?:src|href)\s*=\s*["'](/[^"']*)["']""")
JS_IMPORT = re.compile(r"""\bfrom\s*["'](\./[^"']+)["']|\bimport\s*\(\s*["'](\./[^"']+)["']""")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


@dataclass
class Server:
    proc: subprocess.Popen[str]
    base: str
    host: str
    port: int
    token: str
    output: list[str] = field(default_factory=list)

    def client(self) -> httpx.Client:
        return httpx.Client(base_url=self.base, timeout=5.0, trust_env=False)

    def kill(self) -> None:
        """SIGKILL: no shutdown, no flush, no lifespan exit."""
        self.proc.kill()
        self.proc.wait(timeout=10)


def _pump(stream: Any, lines: queue.Queue[str | None]) -> None:
    for line in stream:
        lines.put(line)
    lines.put(None)


@pytest.fixture
def start_server(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> Iterator[Callable[[Path], Server]]:
    """Start ``nemesys console`` on a free port with ``db``; every server is stopped at the
    end of the test (killed if it does not stop)."""
    clear_nemesys_env(monkeypatch)
    servers: list[Server] = []

    def start(db: Path) -> Server:
        port = free_port()
        env = {k: v for k, v in os.environ.items() if not k.startswith("NEMESYS_")}
        env["NEMESYS_TOKEN"] = TOKEN
        env["NO_PROXY"] = "127.0.0.1,localhost"
        stderr = (tmp_path / f"console-{len(servers)}.err").open("w")
        argv = [
            sys.executable,
            "-m",
            "backend.cli",
            "console",
            "--port",
            str(port),
            "--viewer-port",
            "0",
            "--db",
            str(db),
            "--time-scale",
            "10",
        ]
        proc = subprocess.Popen(
            argv, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=stderr, text=True
        )
        stderr.close()
        lines: queue.Queue[str | None] = queue.Queue()
        threading.Thread(target=_pump, args=(proc.stdout, lines), daemon=True).start()
        output: list[str] = []
        deadline = time.monotonic() + 20.0
        match: re.Match[str] | None = None
        while match is None:
            try:
                line = lines.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                line = None
            if line is None:
                proc.kill()
                err = (tmp_path / f"console-{len(servers)}.err").read_text()
                raise AssertionError(f"no URL printed: {output!r} {err}")
            output.append(line)
            match = URL_LINE.search(line)
        server = Server(proc, match[1], match[2], int(match[3]), match[4], output)
        servers.append(server)
        assert server.port == port

        def up() -> bool:
            assert proc.poll() is None, (tmp_path / f"console-{len(servers) - 1}.err").read_text()
            try:
                with server.client() as c:
                    return c.get("/api/session").status_code == 200
            except httpx.TransportError:
                return False

        wait_until(up, timeout_s=20.0, interval_s=0.05, what="the console to answer")
        return server

    yield start
    for server in servers:
        if server.proc.poll() is None:
            server.proc.terminate()
            try:
                server.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                server.kill()


def wait_command(
    c: httpx.Client, command_id: int, states: tuple[str, ...], timeout_s: float = 10.0
) -> dict[str, Any]:
    def probe() -> dict[str, Any] | None:
        rec: dict[str, Any] = c.get(f"/api/commands/{command_id}").json()
        return rec if rec["state"] in states else None

    return wait_until(probe, timeout_s, what=f"command {command_id} in {states}")


def post_command(c: httpx.Client, pattern: str, params: dict[str, Any]) -> dict[str, Any]:
    r = c.post("/api/commands", json={"pattern": pattern, "params": params}, headers=AUTH)
    assert r.status_code == 202, r.text
    rec: dict[str, Any] = r.json()
    return rec


def listening_sockets(port: int) -> list[str]:
    """Local addresses (hex, as in /proc/net/tcp{,6}) listening on ``port``."""
    found: list[str] = []
    for name in ("/proc/net/tcp", "/proc/net/tcp6"):
        path = Path(name)
        if not path.exists():
            continue
        for line in path.read_text().splitlines()[1:]:
            parts = line.split()
            address, _, port_hex = parts[1].rpartition(":")
            if parts[3] == "0A" and int(port_hex, 16) == port:  # 0A: LISTEN
                found.append(address)
    return found


def test_settings_bind_loopback_by_default(monkeypatch: pytest.MonkeyPatch) -> None:
    clear_nemesys_env(monkeypatch)
    settings = Settings()
    assert settings.host == "127.0.0.1"
    assert settings.viewer_host == "127.0.0.1"
    assert settings.training and settings.target == "sim"
    assert len(settings.token) >= 16 and settings.token != Settings().token  # fresh per start


def test_console_drives_the_simulated_vehicle_and_serves_the_page(
    tmp_path: Path, start_server: Callable[[Path], Server]
) -> None:
    server = start_server(tmp_path / "missions.sqlite3")
    assert server.host == "127.0.0.1"  # the default: loopback only
    assert server.token == TOKEN  # from NEMESYS_TOKEN
    if Path("/proc/net/tcp").exists():
        assert listening_sockets(server.port) == ["0100007F"]  # 127.0.0.1, nothing else
    with server.client() as c:
        session = c.get("/api/session", headers=AUTH).json()
        assert session["mode"] == "training" and session["authenticated"] is True
        assert session["viewer_url"] is not None
        assert c.get("/api/session").json()["authenticated"] is False
        assert c.get("/api/training").json()["time_scale"] == 10

        start = wait_until(lambda: c.get("/api/vehicle").json()["pose"], what="a pose")
        cmd = post_command(c, "straight", EAST)
        assert cmd["state"] == "queued"
        rec = wait_command(c, cmd["id"], ("acknowledged", "rejected", "timed_out", "failed"))
        assert rec["state"] == "acknowledged", rec
        assert rec["ack"]["outcome"] == "accepted"

        poses: list[dict[str, Any]] = []

        def moved_east() -> bool:
            poses.append(c.get("/api/vehicle").json()["pose"])
            return bool(poses[-1]["y_m"] > start["y_m"] + 2.0)

        wait_until(moved_east, timeout_s=10.0, interval_s=0.1, what="the vehicle moving east")
        assert poses[-1]["t_s"] > start["t_s"]
        vehicle = c.get("/api/vehicle").json()
        assert vehicle["active"]["pattern"] == "straight"
        assert vehicle["echo_mismatch"] is False

        (row,) = c.get("/api/commands", params={"state": "acknowledged"}).json()
        assert row["id"] == cmd["id"] and row["ack"]["command"]["pattern"] == "straight"
        csv_text = c.get("/api/log.csv").text
        assert f"\n{cmd['id']},1," in csv_text and ",acknowledged," in csv_text

        # the page and every asset it loads, all from this server
        page = c.get("/")
        assert page.status_code == 200
        html = page.text
        assert "http://" not in html and "https://" not in html
        assert not EXTERNAL.search(html)
        refs = [r for r in LOCAL_REF.findall(html) if not r.startswith("//")]
        assert "/static/app.js" in refs
        todo, fetched = list(refs), set()
        while todo:
            ref = todo.pop()
            if ref in fetched:
                continue
            fetched.add(ref)
            r = c.get(ref)
            assert r.status_code == 200, ref
            if ref.endswith((".js", ".css")):
                assert not EXTERNAL.search(r.text), ref
                base = ref.rsplit("/", 1)[0]
                for a, b in JS_IMPORT.findall(r.text):
                    todo.append(f"{base}/{(a or b)[2:]}")
        assert any(ref.endswith(".css") for ref in fetched)
        assert len(fetched) > 3  # the page, its modules and its style
        assert c.get("/docs").status_code == 200


def test_the_log_survives_a_killed_server(
    tmp_path: Path, start_server: Callable[[Path], Server]
) -> None:
    db = tmp_path / "missions.sqlite3"
    first = start_server(db)
    with first.client() as c:
        wait_until(lambda: c.get("/api/vehicle").json()["pose"], what="a pose")
        cmd = post_command(c, "circle", CIRCLE)
        acked = wait_command(c, cmd["id"], ("acknowledged", "rejected", "timed_out", "failed"))
    first.kill()  # right after the acknowledgement was reported
    assert acked["state"] == "acknowledged"

    # the file is readable as it was left (no shutdown ran)
    log = MissionLog(db)
    try:
        got = log.command(cmd["id"])
        assert got is not None and got["state"] == "acknowledged"
        assert got["ack"]["outcome"] == "accepted"
    finally:
        log.close()

    second = start_server(db)
    with second.client() as c:
        rec = c.get(f"/api/commands/{cmd['id']}").json()
        assert rec["state"] == "acknowledged"
        assert rec["ack"] == acked["ack"] and rec["acked_at"] == acked["acked_at"]
        assert rec["dive"] == 1
        assert c.get("/api/session").json()["dive"] == 2  # a new dive was started
        assert [d["id"] for d in c.get("/api/dives").json()] == [2, 1]
        # a row written (queued) just before a kill: no half-written record
        queued = post_command(c, "square", SQUARE)
    second.kill()
    assert queued["state"] == "queued" and queued["dive"] == 2

    with sqlite3.connect(db) as raw:
        assert raw.execute("PRAGMA integrity_check").fetchone() == ("ok",)

    third = start_server(db)
    with third.client() as c:
        rows = c.get("/api/commands").json()
        assert [r["id"] for r in rows] == [queued["id"], cmd["id"]]
        row = rows[0]
        assert row["state"] in STATES
        for key in ("created_at", "updated_at", "operator", "target", "kind", "params", "hex"):
            assert row[key] is not None, key
        assert row["params"] == queued["params"] and row["requested"] == queued["requested"]
        assert row["bits"] == queued["bits"] and len(row["bits"]) == 100
        assert row["hex"] == queued["hex"] and len(row["hex"]) == 25
        assert row["created_at"] == queued["created_at"]
        if row["state"] == "acknowledged":
            assert row["ack"]["frame_hex"] == row["hex"]
        assert c.get("/api/session").json()["dive"] == 3
        exported = c.get("/api/log.json").json()
        assert json.dumps(exported)  # the whole log reads back
