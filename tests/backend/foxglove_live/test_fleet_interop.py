"""The live Foxglove view of a fleet (issue 23), through Foxglove's own client: npm
``@foxglove/ws-protocol``'s FoxgloveClient in Node (``tests/node/foxglove_watch.mjs``),
decoding each message from the schema the server advertises, against the console with three
in-memory vehicles on one channel (``tests/agent_link.py``'s ``agent_fleet``).

Every vehicle is drawn, each on its own channels under ``/<name>`` (its pose where it is, its
status, belief and link), its own frame named by it on ``/tf``, and its own entities on the
shared scene channels (``auv2/active``, ``<name>/believed`` labelled with its name, address,
believed command and position); the single-vehicle channels are not advertised. (Without a
fleet the channels and ids are as they always were: ``test_live.py``, ``test_interop.py``.)
"""

from __future__ import annotations

import json
import queue
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import pytest

from backend.foxglove_live.channels import channel_specs
from backend.foxglove_live.frames import enu
from backend.foxglove_live.server import FoxgloveLive
from planner import VehicleState
from station.link_fleet import FleetLink
from tests.agent_link import AgentLink, agent_fleet
from tests.backend.conftest import AUTH, CIRCLE, MakeLightClient, console_of, wait_state, wait_until
from tests.backend.foxglove_live.test_interop import NODE_DIR, _node
from vehicle_contract.fleet import parse_vehicles

pytestmark = pytest.mark.interop

SCRIPT = NODE_DIR / "foxglove_watch.mjs"
FLEET = parse_vehicles("3")
NAMES = [v.name for v in FLEET]
OWN = ("/vehicle/pose", "/vehicle/status", "/belief", "/link")
SHARED = ("/tf", "/paths/active", "/belief/position", "/commands", "/log")
TOPICS = (*SHARED, *(f"/{name}{topic}" for name in NAMES for topic in OWN))
Event = dict[str, Any]


class Watch:
    """foxglove_watch.mjs's events as they come (``events``: every one so far)."""

    def __init__(self, proc: subprocess.Popen[str]) -> None:
        self.proc = proc
        self.events: list[Event] = []
        self._queue: queue.Queue[Event | None] = queue.Queue()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            if line.startswith("{"):
                self._queue.put(json.loads(line))
        self._queue.put(None)

    def until(self, done: Callable[[Watch], bool], what: str, timeout_s: float = 20.0) -> None:
        """Read events until ``done(self)``; fail at the deadline or if the script ends."""
        deadline = time.monotonic() + timeout_s
        while not done(self):
            try:
                event = self._queue.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                raise AssertionError(
                    f"no {what} from foxglove_watch.mjs in {timeout_s} s"
                ) from None
            if event is None:
                stderr = self.proc.stderr.read() if self.proc.stderr else ""
                raise AssertionError(f"foxglove_watch.mjs ended before {what}: {stderr}")
            assert event["event"] != "error", event
            self.events.append(event)

    def on(self, topic: str) -> list[dict[str, Any]]:
        """The decoded messages of ``topic``, in order."""
        return [
            e["message"] for e in self.events if e["event"] == "message" and e["topic"] == topic
        ]

    def ready(self) -> Event:
        return next(e for e in self.events if e["event"] == "ready")


@contextmanager
def watching(port: int) -> Iterator[Watch]:
    """Foxglove's client subscribed to :data:`TOPICS` on the view at ``port``; ended (its
    standard input closed) afterwards."""
    proc = subprocess.Popen(
        [_node(), str(SCRIPT), f"ws://127.0.0.1:{port}", *TOPICS],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=NODE_DIR,
    )
    try:
        yield Watch(proc)
        assert proc.stdin is not None
        proc.stdin.close()
        assert proc.wait(timeout=20) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def entities(messages: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Each scene entity by its id, as the latest scene update drew it."""
    return {e["id"]: e for m in messages for e in m["entities"]}


def test_every_vehicle_on_its_own_channels_entities_and_frame(
    make_light_client: MakeLightClient,
) -> None:
    link: FleetLink = agent_fleet(FLEET)
    client = make_light_client(link, vehicles="3", foxglove_port=0)  # type: ignore[arg-type]
    wait_until(lambda: all(v["pose"] for v in client.get("/api/vehicles").json()))
    live = console_of(client).foxglove
    assert isinstance(live, FoxgloveLive)
    places = {name: (5.0 * (i + 1), 20.0 * i, 2.0 + i) for i, name in enumerate(NAMES)}
    with watching(live.port) as w:
        w.until(lambda w: any(e["event"] == "ready" for e in w.events), "ready")
        advertised = {c["topic"]: c["schemaName"] for c in w.ready()["channels"]}
        assert advertised == {c.topic: c.schema for c in channel_specs(NAMES)}
        assert "/vehicle/pose" not in advertised and "/auv3/vehicle/track" in advertised
        channels = {**live.channels.typed, **live.channels.json}
        wait_until(lambda: all(channels[t].has_sinks() for t in TOPICS), what="subscriptions")
        # each vehicle heard a second later, where the test puts it
        for name, vehicle in link.vehicles.items():
            assert isinstance(vehicle, AgentLink)
            x, y, z = places[name]
            vehicle.state = VehicleState(x, y, z, heading_deg=90.0, speed_mps=0.0, t_s=101.0)
            client.portal.call(vehicle.report)  # type: ignore[union-attr]
        r = client.post(
            "/api/commands",
            json={"pattern": "circle", "params": CIRCLE, "vehicle": "auv2"},
            headers=AUTH,
        )
        assert r.status_code == 202, r.text
        sent = wait_state(client, r.json()["id"])
        assert sent["state"] == "acknowledged"
        done = f"command {sent['id']} circle to auv2: acknowledged"

        def seen(w: Watch) -> bool:
            moved = all(
                any(m["pose"]["position"]["x"] == places[n][1] for m in w.on(f"/{n}/vehicle/pose"))
                for n in NAMES
            )
            frames = {t["childFrameId"] for m in w.on("/tf") for t in m["transforms"]}
            believed = entities(w.on("/belief/position"))
            auv2 = believed.get("auv2/believed", {}).get("texts", [{}])[0].get("text", "")
            return (
                moved
                and frames == set(NAMES)
                and "auv2/active" in entities(w.on("/paths/active"))
                and "circle p 100 %" in auv2
                and all(f"{n}/believed" in believed for n in NAMES)
                and all(w.on(f"/{n}/belief") and w.on(f"/{n}/link") for n in NAMES)
                and any(m["message"] == done for m in w.on("/log"))
            )

        w.until(seen, "every vehicle's pose, frame, belief, link and auv2's path")

    for name in NAMES:
        (x, y, z), pose = places[name], w.on(f"/{name}/vehicle/pose")[-1]
        assert pose["frameId"] == "map"
        e, n, u = enu(x, y, z)
        assert pose["pose"]["position"] == {"x": e, "y": n, "z": u}
        frame = next(
            t for m in reversed(w.on("/tf")) for t in m["transforms"] if t["childFrameId"] == name
        )
        assert frame["parentFrameId"] == "map" and frame["translation"] == {"x": e, "y": n, "z": u}
        assert frame["rotation"] == pose["pose"]["orientation"]
        assert w.on(f"/{name}/vehicle/status")[-1]["y_m"] == y  # its own status
        assert {b["vehicle"] for b in w.on(f"/{name}/belief")} == {name}
        assert all("acknowledges" in h for h in w.on(f"/{name}/link"))
    # the shared scene channels: one entity per vehicle, named by it
    active = entities(w.on("/paths/active"))
    assert set(active) == {"auv2/active"}
    assert active["auv2/active"]["texts"][0]["text"] == "auv2 active: circle"
    gone = [d for m in w.on("/paths/active") for d in m["deletions"]]
    assert {d["id"] for d in gone} <= {f"{n}/active" for n in NAMES}  # never all of them
    believed = entities(w.on("/belief/position"))
    for i, name in enumerate(NAMES):
        text = believed[f"{name}/believed"]["texts"][0]["text"]
        assert text.startswith(f"{name} (address {i + 1})\n"), text
        assert "(fix)" in text
    assert "circle p 100 %" in believed["auv2/believed"]["texts"][0]["text"]
    assert "holding p 100 %" in believed["auv1/believed"]["texts"][0]["text"]
    # the commands and their lines name their vehicle
    assert {c["vehicle"] for c in w.on("/commands")} == {"auv2"}
    lines = [m["message"] for m in w.on("/log") if m["name"] == "commands"]
    assert lines and all(" circle to auv2: " in line for line in lines), lines
