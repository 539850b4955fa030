"""The console on an honest modem (issue 21, item 7), through the command manager and the API:
a TCP gateway that closes after each frame, one that closes and stops listening (copies counted
equal frames received), one that goes away and comes back (the link's health follows without a
command), and ``POST /api/link/test`` (token required, no frame sent). The gateways are the
loopback doubles of tests/station/gateways.py; copies move on a manual clock, and every wait is
on a condition."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from pydantic import ValidationError

from backend.settings import Settings
from station.link_modem import ModemLink
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    WRONG_AUTH,
    MakeLightClient,
    advance,
    clear_nemesys_env,
    record,
    wait_state,
    wait_until,
)
from tests.manual_clock import ManualClock
from tests.station.gateways import Behaviour, Gateway

QUICK = {"probe_s": 0.05, "backoff_s": 0.02, "max_backoff_s": 0.1}


@pytest.fixture
def gateways() -> Iterator[list[Gateway]]:
    made: list[Gateway] = []
    yield made
    for g in made:
        g.close()


def console_on(
    make: MakeLightClient, g: Gateway, clock: ManualClock | None = None
) -> tuple[TestClient, ModemLink]:
    link = ModemLink(g.target, 36_000, **QUICK)
    extra: dict[str, Any] = {} if clock is None else {"clock": clock}
    return make(link, target=g.target, **extra), link  # type: ignore[arg-type]


def tried(client: TestClient, cid: int, n: int) -> Callable[[], bool]:
    return lambda: bool(record(client, cid)["attempts"] == n)


def closed(g: Gateway, n: int) -> Callable[[], bool]:
    return lambda: g.closed_by_gateway == n


def link_of(client: TestClient) -> dict[str, Any]:
    link: dict[str, Any] = client.get("/api/vehicle").json()["link"]
    return link


@pytest.mark.parametrize(
    ("behaviour", "listening", "reached"),
    [("close", True, 4), ("half_close", True, 4), ("close", False, 1), ("half_close", False, 1)],
)
def test_copies_counted_equal_frames_the_gateway_received(
    make_light_client: MakeLightClient,
    gateways: list[Gateway],
    behaviour: Behaviour,
    listening: bool,
    reached: int,
) -> None:
    """Today's "4 copies counted sent, 1 received": now a copy counts only on a connection the
    gateway had not closed (a new one when it listens again, none when it does not)."""
    g = Gateway(behaviour, one_connection=not listening)
    gateways.append(g)
    clock = ManualClock()
    client, _link = console_on(make_light_client, g, clock)
    r = client.post(
        "/api/commands", json={"pattern": "circle", "params": CIRCLE, "copies": 4}, headers=AUTH
    )
    assert r.status_code == 202, r.text
    cid = r.json()["id"]
    for n in range(1, 5):
        wait_until(tried(client, cid, n), what=f"copy {n} tried")
        if n == 1 or listening:  # it closes after the first frame of each connection
            g.wait_for(f"close {n}", closed(g, n))
        if n < 4:
            advance(client, clock, 1.0)
    rec = wait_state(client, cid)
    assert rec["state"] == "sent" and rec["attempts"] == 4
    assert rec["copies_sent"] == g.frames() == reached, rec
    if not listening:
        assert "did not leave: connection refused" in (rec["reason"] or ""), rec
        link = link_of(client)
        assert any("the last frame did not reach the modem" in p for p in link["problems"])


def test_the_health_clears_when_the_gateway_is_back_without_a_command(
    make_light_client: MakeLightClient, gateways: list[Gateway]
) -> None:
    g = Gateway("read")
    gateways.append(g)
    client, _link = console_on(make_light_client, g)
    link = link_of(client)
    assert link["connected"] is True and link["level"] == "amber"  # one-way, but there
    g.wait_for("the link's connection", lambda: g.connections == 1)
    g.stop()
    gone = wait_until(
        lambda: (lk := link_of(client))["level"] == "red" and lk, what="the health red"
    )
    assert gone["connected"] is False
    assert any(g.target in p and "connection refused" in p for p in gone["problems"]), gone
    g.restart()
    back = wait_until(lambda: (lk := link_of(client))["connected"] and lk, what="connected")
    assert back["level"] == "amber" and not any("refused" in p for p in back["problems"])
    assert back["frames"]["dive"]["frames"] == 0
    assert g.total() == 0  # no command, no frame: the watch found the gateway back


def test_test_link_checks_the_gateway_and_sends_no_frame(
    make_light_client: MakeLightClient, gateways: list[Gateway]
) -> None:
    g = Gateway("read")
    gateways.append(g)
    client, _link = console_on(make_light_client, g)
    g.wait_for("the link's connection", lambda: g.connections == 1)
    assert client.post("/api/link/test").status_code == 401
    assert client.post("/api/link/test", headers=WRONG_AUTH).status_code == 403
    r = client.post("/api/link/test", headers=AUTH)
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["ok"] is True
    (check,) = body["checks"]
    assert (check["what"], check["target"], check["ok"], check["reason"]) == (
        "modem",
        g.target,
        True,
        None,
    )
    assert "writable" in check["detail"]
    assert body["link"]["connected"] is True and body["link"]["target"] == g.target
    g.stop()
    r = client.post("/api/link/test", headers=AUTH)
    body = r.json()
    assert r.status_code == 200 and body["ok"] is False
    assert body["checks"][0]["reason"] in ("connection refused", "connection closed")
    assert body["link"]["connected"] is False and body["link"]["level"] == "red"
    assert g.total() == 0 and g.connections == 1


def test_test_link_on_a_rosbridge_link_says_whether_it_is_connected(
    make_light_client: MakeLightClient,
) -> None:
    client = make_light_client()
    body = client.post("/api/link/test", headers=AUTH).json()
    assert body["ok"] is True and [c["what"] for c in body["checks"]] == ["rosbridge"]
    assert "acks_and_telemetry" in body["checks"][0]["detail"]


@pytest.mark.parametrize(
    ("overrides", "words"),
    [
        ({"target": "loop://", "telemetry": "vehicle:9090"}, "no scheme"),
        ({"target": "loop://", "telemetry": "tcp://vehicle:9090"}, "must be ws:// or wss://"),
        ({"telemetry": "ws://vehicle:9090"}, "is the embedded simulator"),
        ({"target": "ws://vehicle:9090", "telemetry": "ws://vehicle:9090"}, "is a rosbridge"),
    ],
)
def test_telemetry_settings_are_checked_naming_the_forms(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, overrides: dict[str, str], words: str
) -> None:
    clear_nemesys_env(monkeypatch)
    with pytest.raises(ValidationError) as err:
        Settings(token="x" * 20, db_path=tmp_path / "m.sqlite3", **overrides)  # type: ignore[arg-type]
    assert words in str(err.value) and "telemetry" in str(err.value)
    assert "ws://host:port[/path]" in str(err.value) or "ME modem target" in str(err.value)


def test_telemetry_with_a_modem_target_is_taken(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    clear_nemesys_env(monkeypatch)
    monkeypatch.setenv("NEMESYS_TARGET", "tcp://127.0.0.1:4001")
    monkeypatch.setenv("NEMESYS_TELEMETRY", " ws://127.0.0.1:9090 ")
    s = Settings(token="x" * 20, db_path=tmp_path / "m.sqlite3")
    assert s.telemetry == "ws://127.0.0.1:9090"
    assert Settings(token="x" * 20, db_path=tmp_path / "m.sqlite3", telemetry="").telemetry == ""
