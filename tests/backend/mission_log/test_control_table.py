"""The control table (backend/mission_log/control.py) on both back-ends: the rules of request,
grant, refuse, release and takeover, each change with its event in one transaction, the epoch
that only grows, the heartbeat and the timeout judged on the database's clock; and, on
PostgreSQL, the notification of a committed write (never of a rolled-back one), naming the
writing console, to a listener on its own connection (backend/mission_log/listen.py)."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Iterator

import pytest

from backend.mission_log import control
from backend.mission_log.control import Actor, ControlRefused
from backend.mission_log.listen import Listener, Notice, parse_notice
from backend.mission_log.store import MissionLog
from tests.backend.conftest import command_fields
from tests.backend.log_backend import LogBackend

SHIP = Actor("ship", "alice")
SHORE = Actor("shore", "bob")
V = "nemesys"
TIMEOUT_S = 15.0


@pytest.fixture
def log(log_backend: LogBackend) -> Iterator[MissionLog]:
    opened = log_backend.open()
    yield opened
    opened.close()


def act(log: MissionLog, action: control.Action, by: Actor, **kw: bool) -> control.ControlChange:
    dive = log.dives()[0]["id"] if log.dives() else log.new_dive("sim")
    return control.act(log, dive, V, action, by, TIMEOUT_S, **kw)[-1]


def test_request_grant_refuse_release_takeover(log: MissionLog) -> None:
    first = act(log, "request", SHIP)
    assert first.outcome == "granted" and first.after.console == "ship"
    assert first.after.operator == "alice" and first.after.epoch == 1
    assert act(log, "request", SHIP).outcome == "unchanged"
    pending = act(log, "request", SHORE)
    assert pending.outcome == "pending" and pending.after.console == "ship"
    assert pending.after.request_console == "shore" and pending.after.epoch == 1
    with pytest.raises(ControlRefused, match="only the console in control can grant"):
        act(log, "grant", SHORE)
    refused = act(log, "refuse", SHIP)
    assert refused.outcome == "refused" and refused.after.request_console is None
    with pytest.raises(ControlRefused, match="no request for control of nemesys"):
        act(log, "grant", SHIP)
    act(log, "request", SHORE)
    granted = act(log, "grant", SHIP)
    assert granted.after.console == "shore" and granted.after.operator == "bob"
    assert granted.after.epoch == 2 and not granted.after.takeover_allowed
    with pytest.raises(ControlRefused, match="does not allow a takeover"):
        act(log, "takeover", SHIP)
    assert act(log, "request", SHORE, takeover_allowed=True).after.takeover_allowed
    taken = act(log, "takeover", SHIP)
    assert taken.outcome == "taken_over" and taken.after.console == "ship"
    assert taken.after.epoch == 3
    with pytest.raises(ControlRefused, match="only the console in control can release"):
        act(log, "release", SHORE)
    released = act(log, "release", SHIP)
    assert released.after.console is None and released.after.epoch == 4
    assert act(log, "takeover", SHORE).outcome == "granted"  # nobody had it
    kinds = [(e["kind"], e["data"]["outcome"]) for e in log.events()]
    assert kinds == [
        ("control", outcome)
        for outcome in (
            "granted",
            "unchanged",
            "pending",
            "refused",
            "pending",
            "granted",
            "unchanged",
            "taken_over",
            "released",
            "granted",
        )
    ]
    assert "'bob'" in log.events()[5]["detail"] and "granted" in log.events()[5]["detail"]


def test_the_heartbeat_keeps_control_and_the_timeout_releases_it(
    log: MissionLog, log_backend: LogBackend
) -> None:
    act(log, "request", SHIP)
    assert control.heartbeat(log, "ship", TIMEOUT_S) == [V]
    assert control.heartbeat(log, "shore", TIMEOUT_S) == []
    found, now = control.rows(log)
    assert found[V].owner(now, TIMEOUT_S) == "ship"
    assert found[V].owner(now + TIMEOUT_S + 1, TIMEOUT_S) is None  # on the database's clock
    assert control.expired(log, TIMEOUT_S) == []
    # the last beat older than the timeout: not refreshed, released by whoever looks
    aged = "UPDATE control SET heartbeat_s = heartbeat_s - ? RETURNING vehicle"
    assert log_backend.query(aged, (TIMEOUT_S + 1,)) == [(V,)]
    assert control.heartbeat(log, "ship", TIMEOUT_S) == []
    dive = log.dives()[0]["id"]
    assert control.expired(log, TIMEOUT_S) == [V]
    change = control.release_expired(log, dive, V, TIMEOUT_S)
    assert change is not None and change.outcome == "timed_out"
    assert change.after.console is None and change.after.epoch == 2
    assert control.release_expired(log, dive, V, TIMEOUT_S) is None  # done once
    assert "over the 15 s timeout" in log.events()[-1]["detail"]


def test_an_action_on_an_expired_control_times_it_out_first(
    log: MissionLog, log_backend: LogBackend
) -> None:
    act(log, "request", SHIP)
    aged = "UPDATE control SET heartbeat_s = heartbeat_s - ? RETURNING vehicle"
    assert log_backend.query(aged, (TIMEOUT_S + 1,)) == [(V,)]
    dive = log.dives()[0]["id"]
    changes = control.act(log, dive, V, "request", SHORE, TIMEOUT_S)
    assert [c.outcome for c in changes] == ["timed_out", "granted"]
    assert changes[-1].after.console == "shore" and changes[-1].after.epoch == 3


def test_a_refused_action_writes_nothing(log: MissionLog, log_backend: LogBackend) -> None:
    act(log, "request", SHIP)
    events = len(log.events())
    with pytest.raises(ControlRefused):
        act(log, "release", SHORE)
    assert len(log.events()) == events
    assert log_backend.scalar("SELECT epoch FROM control WHERE vehicle = ?", (V,)) == 1


def test_a_named_console_is_written_into_its_commands(log: MissionLog) -> None:
    dive = log.new_dive("sim")
    assert log.insert_command(dive, command_fields())["console"] is None
    log.name_console("ship")
    assert log.insert_command(dive, command_fields())["console"] == "ship"


def test_notices_parse_only_our_payloads() -> None:
    assert parse_notice('{"table": "commands", "id": 3, "console": "a"}') == Notice(
        "commands", 3, "a"
    )
    assert parse_notice('{"table": "control", "id": "nemesys", "console": null}') == Notice(
        "control", "nemesys", None
    )
    for bad in ("", "[]", "{}", '{"table": 1, "id": 2}', '{"table": "c", "id": true}'):
        assert parse_notice(bad) is None


@pytest.mark.slow  # a listener connecting, and waiting out what must not come
def test_postgres_notifies_other_consoles_of_committed_writes(pg_log: LogBackend) -> None:
    """Another console's commit is told with its row's key; a rolled-back write and the
    listener's own console's writes are not; a heartbeat alone is not."""
    ship, shore = pg_log.open(), pg_log.open()
    ship.name_console("ship")
    shore.name_console("shore")
    got: list[Notice] = []
    backs: list[float] = []

    async def scenario() -> None:
        listener = Listener(
            pg_log.url,
            "shore",
            on_notice=got.append,
            on_lost=lambda reason: None,
            on_back=lambda: backs.append(time.monotonic()),
        )
        task = asyncio.create_task(listener.run())
        try:
            while not backs:
                await asyncio.sleep(0.01)
            dive = ship.new_dive("sim")
            shore.insert_command(dive, command_fields())  # its own: not told
            with pytest.raises(RuntimeError), ship.transaction():
                ship.insert_command(dive, command_fields())
                raise RuntimeError("rolled back")
            rec = ship.insert_command(dive, command_fields())
            ship.update_command(rec["id"], state="transmitted")
            event = ship.add_event(dive, "datum", "a datum")
            control.act(ship, dive, V, "request", SHIP, TIMEOUT_S)
            control.heartbeat(ship, "ship", TIMEOUT_S)
            deadline = time.monotonic() + 10
            while len(got) < 5 and time.monotonic() < deadline:
                await asyncio.sleep(0.01)
            await asyncio.sleep(0.3)  # anything further would be a notice too many
            assert got == [
                Notice("commands", rec["id"], "ship"),
                Notice("commands", rec["id"], "ship"),
                Notice("events", event["id"], "ship"),
                Notice("events", event["id"] + 1, "ship"),  # the control event
                Notice("control", V, "ship"),
            ] or sorted(map(repr, got)) == sorted(
                map(
                    repr,
                    [
                        Notice("commands", rec["id"], "ship"),
                        Notice("commands", rec["id"], "ship"),
                        Notice("events", event["id"], "ship"),
                        Notice("control", V, "ship"),
                        Notice("events", event["id"] + 1, "ship"),
                    ],
                )
            )
        finally:
            task.cancel()
            with pytest.raises(asyncio.CancelledError):
                await task

    try:
        asyncio.run(scenario())
    finally:
        ship.close()
        shore.close()
