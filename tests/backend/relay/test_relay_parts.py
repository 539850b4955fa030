"""The relay's parts without a console: the settings (``target relay`` needs the shared
PostgreSQL log, said at start in one line), the shore's view of the transmitting console, a
refusal's words and violations carried back from the outbox row, and an outbox row as the
ship's send request."""

from __future__ import annotations

import asyncio
import contextlib
import io
from collections.abc import Iterator
from pathlib import Path

import pytest
from pydantic import ValidationError

from backend.mission_log import outbox
from backend.mission_log.outbox import OutboxRow, Transmitter
from backend.mission_log.store import LogWriteError, MissionLog
from backend.relay.link import FRESH_S, NO_TRANSMITTER, RelayLink, view_of
from backend.relay.ship import request_of
from backend.relay.shore import refusal_of
from backend.settings import Settings
from cli.main import main
from codec import encode_frame
from station.link import Capability
from tests.backend.conftest import CIRCLE, clear_nemesys_env

URL = "postgresql://nemesys:secret@127.0.0.1:5432/nemesys"


def test_a_relay_needs_the_shared_postgresql_log(monkeypatch: pytest.MonkeyPatch) -> None:
    clear_nemesys_env(monkeypatch)
    with pytest.raises(ValidationError, match=r"target 'relay' .* needs the mission log"):
        Settings(target="relay")
    relay = Settings(target="relay", database_url=URL)
    assert relay.relay and not relay.training
    with pytest.raises(ValidationError, match="target 'relay' has no link of its own"):
        Settings(target="relay", database_url=URL, telemetry="ws://127.0.0.1:9090")
    with pytest.raises(ValidationError, match="relay_wait_s"):
        Settings(target="relay", database_url=URL, relay_wait_s=0)


def test_nemesys_console_says_so_in_one_line_before_anything_starts(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    clear_nemesys_env(monkeypatch)
    db = tmp_path / "missions.sqlite3"
    status = main(["console", "--target", "relay", "--db", str(db)], io.StringIO())
    assert status == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith("nemesys console: settings: ")
    assert "NEMESYS_DATABASE_URL=postgresql://" in line
    assert not db.exists()  # nothing opened


def test_the_shore_shows_the_transmitter_seen_last() -> None:
    assert view_of([], 100.0).via is None
    found = [
        Transmitter(
            "ship",
            "serial:///dev/ttyUSB0",
            {"connected": True, "capability": "none", "level": "amber", "problems": ["one-way"]},
            99.0,
        ),
        Transmitter("old-ship", "sim", {}, 10.0),
    ]
    v = view_of(found, 100.0)
    assert v.via == "ship" and v.target == "serial:///dev/ttyUSB0" and v.fresh
    assert v.connected is True and v.capability is Capability.NONE and v.level == "amber"
    assert v.problems == ["one-way"] and v.seen_age_s == 1.0
    stale = view_of(found, 99.0 + FRESH_S + 0.1)
    assert not stale.fresh and stale.via == "ship"
    odd = view_of([Transmitter("ship", "sim", {"capability": "x", "level": 3}, 1.0)], 1.0)
    assert odd.capability is None and odd.level is None and odd.problems == []


def test_a_refusal_comes_back_with_its_violations() -> None:
    violation = {
        "check": "depth_limit",
        "param": "depth",
        "kind": "hard",
        "message": "depth 3 m is beyond the limit 2 m",
        "value": 3.0,
        "limit": 2.0,
        "unit": "m",
        "allowed": "0 to 2 m",
        "overridable": False,
        "step": None,
    }
    message, violations = refusal_of(
        {"message": "limit violation", "violations": [violation]}, "fallback"
    )
    assert message == "limit violation"
    assert [v.as_json() for v in violations] == [violation]
    assert refusal_of(None, "console 'shore' is not in control") == (
        "console 'shore' is not in control",
        (),
    )


def test_an_outbox_row_is_the_ships_request_with_who_asked() -> None:
    row = OutboxRow(
        id=7,
        created_at="2026-01-01T00:00:00.000+00:00",
        created_s=1.0,
        console="shore",
        operator="bob",
        vehicle="nemesys",
        origin="script",
        kind="script",
        pattern="circle",
        params=CIRCLE,
        override=True,
        accepted=frozenset({("depth", "depth")}),
        copies=2,
        retry_of=3,
        state="waiting",
    )
    request = request_of(row)
    assert request.accepted == frozenset({("depth", "depth")})
    assert (request.pattern, dict(request.params), request.origin) == ("circle", CIRCLE, "script")
    assert request.override and request.copies == 2 and request.retry_of == 3
    assert request.kind == "script"
    assert request.relayed is not None and request.relayed.origin == "relay:shore"
    assert (request.relayed.operator, request.relayed.outbox_id) == ("bob", 7)
    odd = request_of(OutboxRow(**{**row.__dict__, "origin": "elsewhere", "kind": "x"}))
    assert odd.origin == "api" and odd.kind == "command"


class _Gone:
    """A log whose database is out of reach."""

    @contextlib.contextmanager
    def connection(self) -> Iterator[None]:
        raise LogWriteError("server closed the connection unexpectedly")
        yield


def test_the_relay_link_follows_the_transmitters_table(tmp_path: Path) -> None:
    log = MissionLog(tmp_path / "missions.sqlite3")
    try:
        link = RelayLink()
        assert link.target == "relay" and not link.connected  # no log yet: nothing known
        link.attach(log)
        assert not link.connected and link.capability is Capability.UNKNOWN
        assert link.connection_problem == "no console holding the transmitter is on the mission log"
        health = {"connected": True, "capability": "acks_and_telemetry", "level": "green"}
        outbox.beat_transmitter(log, "ship", "sim", health)
        (check,) = asyncio.run(link.test())  # read now
        assert check.ok and "relay via console 'ship'" in check.detail
        assert link.connected and link.connection_problem is None
        assert link.capability is Capability.ACKS_AND_TELEMETRY and link.acknowledges
        assert asyncio.run(link.transmit(encode_frame("surface", {}).frame)) == NO_TRANSMITTER
        link.attach(_Gone())
        (check,) = asyncio.run(link.test())
        assert not check.ok and not link.connected
        assert check.reason is not None and "cannot be read" in check.reason
        assert link.view().via == "ship"  # the last one read, no longer fresh
    finally:
        log.close()
