"""End to end: the real ``nemesys console`` (uvicorn, viser, the simulated vehicle behind its
rosbridge) as a subprocess, driven over HTTP with httpx on 127.0.0.1 only; and the mission
log surviving a killed server (SIGKILL), row by row, on SQLite and on PostgreSQL."""

from __future__ import annotations

import json
import re
import sqlite3
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from backend.mission_log.store import STATES
from backend.settings import Settings
from bench._server import ConsoleProcess, start_console
from tests.backend.conftest import CIRCLE, FINAL, SQUARE, TOKEN, clear_nemesys_env, wait_until
from tests.backend.log_backend import LogBackend

#: `nemesys console` subprocesses: make test, not make test-fast.
pytestmark = pytest.mark.slow

AUTH = {"Authorization": f"Bearer {TOKEN}"}
EAST = {"speed": 0.18, "depth": 2, "duration": 600, "heading": 90}
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


@pytest.fixture
def start_server(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> Iterator[Callable[..., ConsoleProcess]]:
    """Start ``nemesys console`` on a free port with ``db`` (and ``env``: the log on
    PostgreSQL); every server is stopped at the end of the test (killed if it does not
    stop)."""
    clear_nemesys_env(monkeypatch)
    servers: list[ConsoleProcess] = []

    def start(db: Path, env: dict[str, str] | None = None) -> ConsoleProcess:
        server = start_console(
            tmp_path / f"console-{len(servers)}.log",
            TOKEN,
            *("--db", str(db), "--time-scale", "10"),
            env={"NO_PROXY": "127.0.0.1,localhost", **(env or {})},
        )
        servers.append(server)
        assert server.base_url == f"http://{server.host}:{server.port}", server.base_url
        return server

    yield start
    for server in servers:
        server.stop(timeout_s=10)


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
    tmp_path: Path, start_server: Callable[[Path], ConsoleProcess]
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
        rec = wait_command(c, cmd["id"], FINAL)
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
    start_server: Callable[..., ConsoleProcess], log_backend: LogBackend
) -> None:
    db, env = log_backend.path, log_backend.console_env()
    first = start_server(db, env)
    with first.client() as c:
        wait_until(lambda: c.get("/api/vehicle").json()["pose"], what="a pose")
        cmd = post_command(c, "circle", CIRCLE)
        acked = wait_command(c, cmd["id"], FINAL)
    first.kill()  # right after the acknowledgement was reported
    assert acked["state"] == "acknowledged"

    # the log is readable as it was left (no shutdown ran)
    log = log_backend.open()
    try:
        got = log.command(cmd["id"])
        assert got is not None and got["state"] == "acknowledged"
        assert got["ack"]["outcome"] == "accepted"
    finally:
        log.close()

    second = start_server(db, env)
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

    if log_backend.kind == "sqlite":
        with sqlite3.connect(db) as raw:
            assert raw.execute("PRAGMA integrity_check").fetchone() == ("ok",)

    third = start_server(db, env)
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
