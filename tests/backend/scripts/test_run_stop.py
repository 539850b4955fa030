"""A running script gives way to the operator (the developers' guide: "a newer command or
Surface is never undone by an older one"): a Surface, a manual command (REST or ``/ws``), a
retry or a training scenario sent while a script runs ends the run at once, before its first
copy leaves; no later step is sent; the run says why in the operator's words, and the stop is
an event of the mission log. A step already on its way when the Surface came never goes out
after it.

The light app (the onboard agent of an in-memory vehicle) on a manual clock: "no later step
is sent" is proved by moving the clock past every later step's time and reading the frames
the vehicle received and the commands the mission log holds."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.commands.service import SendOutcome, SendRequest
from backend.console import Console
from backend.scripts.guard import STOPPED_EVENT
from codec import Frame, encode_frame
from station.link import Capability
from tests.agent_link import AgentLink
from tests.backend.conftest import AUTH, MakeLightClient, advance, console_of
from tests.backend.scripts.test_run_completion import run, state, until
from tests.backend.scripts.test_scripts import CIRCLE, HOVER, STRAIGHT, doc, step
from tests.backend.test_api_live import receive_until
from tests.manual_clock import ManualClock

#: The third step: a hover of its own heading (a frame of its own).
HOVER_3: dict[str, Any] = {**HOVER, "heading": 180}
#: Three timed steps: a hover at once, a straight at 60 s, a hover at 120 s.
THREE = doc(
    step("hover", HOVER, "at", 0),
    step("straight", STRAIGHT, "at", 60),
    step("hover", HOVER_3, "at", 120),
)
#: Past every later step's time (s on the console's clock; the run's clock on a real link).
PAST_THE_SCRIPT_S = 200.0
LATER = (encode_frame("straight", STRAIGHT).frame.hex, encode_frame("hover", HOVER_3).frame.hex)
SURFACE_HEX = encode_frame("surface", {}).frame.hex
STRAIGHT_HEX = LATER[0]


def first_step_out(client: TestClient, clock: ManualClock) -> None:
    """Start the three-step run; return once step 1 is acknowledged and step 2 waits."""
    assert run(client, THREE)["running"]
    until(client, clock, lambda s: s["waiting_for"] == "time", 10.0)
    assert state(client)["steps"][0]["state"] == "acknowledged"


def commands_of_the_dive(client: TestClient) -> list[dict[str, Any]]:
    console = console_of(client)
    assert console.log is not None
    log = console.log
    rows: list[dict[str, Any]] = client.portal.call(  # type: ignore[union-attr]
        lambda: log.commands(dive=console.dive, oldest_first=True)
    )
    return rows


def stop_events(client: TestClient) -> list[dict[str, Any]]:
    console = console_of(client)
    assert console.log is not None
    log = console.log
    events: list[dict[str, Any]] = client.portal.call(  # type: ignore[union-attr]
        lambda: log.events(console.dive)
    )
    return [e for e in events if e["kind"] == STOPPED_EVENT]


def assert_stopped_for_good(
    client: TestClient, clock: ManualClock, link: AgentLink, reason: str, command_id: int
) -> dict[str, Any]:
    """The run is stopped with ``reason``, said in its summary, logged as an event; moving
    the clock past every later step's time sends none of them. Returns the run's state."""
    stopped = state(client)
    assert not stopped["running"] and stopped["outcome"] == "stopped"
    assert stopped["reason"] == reason
    assert stopped["summary"] == f"stopped: {reason}"
    advance(client, clock, PAST_THE_SCRIPT_S)
    assert not any(frame in link.frames for frame in LATER)
    steps_logged = [c["pattern"] for c in commands_of_the_dive(client) if c["kind"] == "script"]
    assert steps_logged == ["hover"]  # the first step's record only
    done = state(client)
    assert [s["state"] for s in done["steps"]] == ["acknowledged", "pending", "pending"]
    assert done["steps"][1]["state_text"] == "not sent yet"
    assert done["outcome"] == "stopped" and done["reason"] == reason
    (event,) = stop_events(client)
    assert event["detail"] == f"mission script 'pod patrol' stopped: {reason}"
    assert event["data"]["command"] == command_id and event["data"]["steps_sent"] == [1]
    return done


class WireAtStop:
    """A watcher after the run's own: what the wire and the run were when a command was
    written (its first copy not out yet)."""

    def __init__(self, console: Console, link: AgentLink) -> None:
        self.console, self.link = console, link
        self.seen: list[tuple[str, bool, int]] = []

    def admit(self, request: SendRequest) -> None:
        pass

    def sent(self, request: SendRequest, outcome: SendOutcome) -> None:
        runner = self.console.runner
        running = runner is not None and runner.running
        self.seen.append((outcome.record.pattern, running, self.link.frames.count(SURFACE_HEX)))


def test_surface_stops_the_run_before_its_first_copy_and_no_later_step_goes(
    make_light_client: MakeLightClient,
) -> None:
    clock, link = ManualClock(), AgentLink()
    client = make_light_client(link, clock=clock)
    console = console_of(client)
    wire = WireAtStop(console, link)
    assert console.service is not None
    client.portal.call(console.service.watch, wire)  # type: ignore[union-attr]
    first_step_out(client, clock)
    r = client.post("/api/surface", headers=AUTH)
    assert r.status_code == 202, r.text
    surface = r.json()
    # stopped before the Surface's first copy left (the run's watcher comes first)
    assert wire.seen[-1] == ("surface", False, 0)
    reason = f"the operator sent Surface (command {surface['id']})"
    assert_stopped_for_good(client, clock, link, reason, surface["id"])
    assert link.agent.active is not None and link.agent.active.pattern == "surface"
    assert [c["pattern"] for c in commands_of_the_dive(client)] == ["hover", "surface"]
    # the operator's Stop on a run already stopped changes nothing
    again = client.post("/api/scripts/run/stop", headers=AUTH).json()
    assert again["reason"] == reason


def test_a_manual_command_stops_the_run(make_light_client: MakeLightClient) -> None:
    clock, link = ManualClock(), AgentLink()
    client = make_light_client(link, clock=clock)
    first_step_out(client, clock)
    r = client.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
    assert r.status_code == 202, r.text
    circle = r.json()
    reason = f"the operator sent a circle (command {circle['id']})"
    assert_stopped_for_good(client, clock, link, reason, circle["id"])
    assert link.agent.active is not None and link.agent.active.pattern == "circle"


def test_a_command_sent_on_ws_stops_the_run_and_the_page_hears_of_it(
    make_light_client: MakeLightClient,
) -> None:
    clock, link = ManualClock(), AgentLink()
    client = make_light_client(link, clock=clock)
    first_step_out(client, clock)
    with client.websocket_connect("/ws") as ws:
        ws.send_json({"type": "auth", "token": AUTH["Authorization"].removeprefix("Bearer ")})
        ws.send_json({"type": "send", "pattern": "circle", "params": CIRCLE})
        got = receive_until(ws, lambda m: m["type"] == "event")
    queued = next(m for m in got if m.get("type") == "queued")
    event = next(m for m in got if m.get("type") == "event")["event"]
    cid = queued["command"]["id"]
    reason = f"the operator sent a circle (command {cid})"
    assert event["kind"] == STOPPED_EVENT and event["detail"].endswith(reason)
    assert_stopped_for_good(client, clock, link, reason, cid)


def test_a_retry_stops_the_run(make_light_client: MakeLightClient) -> None:
    clock, link = ManualClock(), AgentLink()
    client = make_light_client(link, clock=clock)
    console = console_of(client)
    assert console.log is not None
    log = console.log
    link.answer = False  # the vehicle out of range: the circle times out
    r = client.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
    old = r.json()["id"]

    def timed_out() -> bool:
        record = log.command(old)
        return record is not None and record["state"] == "timed_out"

    client.portal.call(clock.advance_until, timed_out, 60.0)  # type: ignore[union-attr]
    link.answer = True
    first_step_out(client, clock)
    r = client.post(f"/api/commands/{old}/retry", headers=AUTH)
    assert r.status_code == 202, r.text
    new = r.json()["id"]
    reason = f"the operator retried command {old}: a circle (command {new})"
    assert_stopped_for_good(client, clock, link, reason, new)


def test_a_training_scenarios_command_stops_the_run(make_light_client: MakeLightClient) -> None:
    """A scenario's first command goes through the service as ``scenario`` (the training
    route, ``backend/api/training.py``, needs the simulator; the path is the same)."""
    clock, link = ManualClock(), AgentLink()
    client = make_light_client(link, clock=clock)
    console = console_of(client)
    service = console.service
    assert service is not None
    first_step_out(client, clock)
    request = SendRequest("circle", CIRCLE, "scenario")
    sent = client.portal.call(service.send, request)  # type: ignore[union-attr]
    cid = sent.record.id
    reason = f"the operator loaded a training scenario, which sent a circle (command {cid})"
    assert_stopped_for_good(client, clock, link, reason, cid)


def test_a_step_on_its_way_to_the_service_when_surface_comes_is_never_sent(
    make_light_client: MakeLightClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Step 2 falls due and is handed to the service, whose send is still awaiting (held
    here) when the operator presses Surface: when it reaches the service it is refused,
    nothing of it is written or sent, and it reads "not sent yet"."""
    clock, link = ManualClock(), AgentLink()
    client = make_light_client(link, clock=clock)
    console = console_of(client)
    service = console.service
    assert service is not None
    send = service.send
    gate = asyncio.Event()
    held: list[SendRequest] = []

    async def held_send(request: SendRequest) -> SendOutcome:
        if request.origin == "script" and request.pattern == "straight":
            held.append(request)
            await gate.wait()
        return await send(request)

    monkeypatch.setattr(service, "send", held_send)
    first_step_out(client, clock)
    until(client, clock, lambda s: s["steps"][1]["state"] == "sent", 70.0)
    assert len(held) == 1 and state(client)["running"]
    surface = client.post("/api/surface", headers=AUTH).json()
    client.portal.call(gate.set)  # type: ignore[union-attr]
    advance(client, clock, 1.0)
    reason = f"the operator sent Surface (command {surface['id']})"
    assert_stopped_for_good(client, clock, link, reason, surface["id"])
    assert STRAIGHT_HEX not in link.frames
    assert [c["pattern"] for c in commands_of_the_dive(client)] == ["hover", "surface"]


class HeldLink(AgentLink):
    """A one-way link whose modem holds the first frame ``hold`` until released: a step's
    copy on its way out when the operator presses Surface."""

    def __init__(self, hold: str) -> None:
        super().__init__(Capability.NONE)
        self.hold = hold
        self.holding = asyncio.Event()
        self.release = asyncio.Event()

    async def transmit(self, frame: Frame) -> str | None:
        if frame.hex == self.hold and not self.release.is_set():
            self.holding.set()
            await self.release.wait()
        return await super().transmit(frame)


def test_a_step_whose_copies_are_going_out_sends_none_after_the_surface(
    make_light_client: MakeLightClient,
) -> None:
    """On a one-way link step 2 goes as three copies; its first is in the modem when the
    operator presses Surface: the Surface supersedes it, no copy of it leaves after the
    Surface's first, and the run is stopped."""
    clock, link = ManualClock(), HeldLink(STRAIGHT_HEX)
    client = make_light_client(link, clock=clock, link_ber=0.01)
    console = console_of(client)
    assert console.log is not None
    log = console.log
    assert run(client, THREE)["completion_by"] == "estimate"
    client.portal.call(clock.advance_until, link.holding.is_set, 90.0)  # type: ignore[union-attr]
    straight = client.portal.call(  # type: ignore[union-attr]
        lambda: log.commands(pattern="straight", dive=console.dive)
    )[0]
    assert straight["copies"] == 3 and straight["copies_sent"] == 0
    surface = client.post("/api/surface", headers=AUTH).json()
    client.portal.call(link.release.set)  # type: ignore[union-attr]
    advance(client, clock, PAST_THE_SCRIPT_S)
    first_surface = link.frames.index(SURFACE_HEX)
    assert link.frames.count(STRAIGHT_HEX) == 1  # the held copy, before the Surface
    assert link.frames.index(STRAIGHT_HEX) < first_surface
    assert LATER[1] not in link.frames
    record = client.get(f"/api/commands/{straight['id']}").json()
    assert record["state"] == "superseded" and record["superseded_by"] == surface["id"]
    done = state(client)
    assert done["outcome"] == "stopped"
    assert done["reason"] == f"the operator sent Surface (command {surface['id']})"
    assert done["steps"][2]["state"] == "pending"
    (event,) = stop_events(client)
    assert event["data"]["command"] == surface["id"]
