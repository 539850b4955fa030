"""The hybrid link end to end (issue 21, item 6): commands over an ME modem, telemetry and
acknowledgements over the vehicle's rosbridge, at once.

The vehicle is the training twin behind its rosbridge server (rosbridge/server.py + sim), with
no frame subscriber of its own in the console's path: its frames come by its ME receiver, the
reference node's ``frame_input: serial``. That receiver is a loopback test modem, a TCP gateway
double (tests/station/gateways.py) that hands every 13-byte frame it reads to the simulated
vehicle (``Simulation.submit_frame``: the emulated channel, then the onboard agent decoding the
raw bits), on the bridge's event loop. The console runs with ``NEMESYS_TARGET=tcp://...`` and
``NEMESYS_TELEMETRY=ws://...``: a command ends ``acknowledged`` by the acknowledgement that comes
back over rosbridge; with the rosbridge stopped the next command goes out as one-way copies and
ends ``sent``, and the link's health says it is one-way and why.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from rosbridge.server import BridgeServer
from sim.simulation import SimConfig, Simulation
from tests.backend.conftest import (
    CIRCLE,
    TIME_SCALE,
    MakeClient,
    send,
    wait_state,
    wait_until,
)
from tests.rosbridge.helpers import LoopThread
from tests.station.gateways import Gateway


class Vehicle:
    """The training twin behind its rosbridge, on an event loop of its own, with a loopback
    test modem (a TCP gateway) feeding its ME receiver."""

    def __init__(self) -> None:
        self.thread = LoopThread()
        self.thread.start()
        self.sim = Simulation(SimConfig(seed=21))
        self.bridge = BridgeServer(self.sim, "127.0.0.1", 0, time_scale=TIME_SCALE)
        self.thread.run(self.bridge.start())
        self.url = f"ws://127.0.0.1:{self.bridge.port}"
        self.modem = Gateway("read", on_frame=self._receive)
        self.bridge_up = True

    def _receive(self, frame: bytes) -> None:
        # the vehicle's ME receiver: on the bridge's loop, as its endpoint calls must be
        self.thread.loop.call_soon_threadsafe(self.sim.submit_frame, frame)

    def frames_in(self) -> int:
        return self.thread.run(self._frames_in())

    async def _frames_in(self) -> int:
        return self.sim.frames_in

    def stop_telemetry(self) -> None:
        self.thread.run(self.bridge.stop(), timeout_s=10.0)
        self.bridge_up = False

    def close(self) -> None:
        self.modem.close()
        if self.bridge_up:
            self.stop_telemetry()
        self.thread.stop()


@pytest.fixture
def vehicle() -> Iterator[Vehicle]:
    v = Vehicle()
    try:
        yield v
    finally:
        v.close()


def link_of(client: Any) -> dict[str, Any]:
    link: dict[str, Any] = client.get("/api/vehicle").json()["link"]
    return link


def test_commands_over_the_modem_acknowledged_over_rosbridge_then_one_way(
    make_client: MakeClient, vehicle: Vehicle
) -> None:
    client = make_client(
        target=vehicle.modem.target,
        telemetry=vehicle.url,
        link_ber=1e-2,
        copy_interval_s=0.05,
        surface_repeat_s=0.05,
    )
    two_way = wait_until(
        lambda: (lk := link_of(client))["capability"] == "acks_and_telemetry" and lk,
        what="the capability from the vehicle's rosbridge",
    )
    assert two_way["connected"] is True and two_way["acknowledges"] is True
    assert two_way["target"] == vehicle.modem.target
    wait_until(lambda: client.get("/api/vehicle").json()["pose"], what="a pose over rosbridge")

    cmd = send(client, "circle", CIRCLE)
    assert cmd["two_way"] is True and cmd["copies"] == 1
    rec = wait_state(client, cmd["id"])
    assert rec["state"] == "acknowledged", rec
    assert rec["ack"]["frame_hex"] == rec["hex"] and rec["copies_sent"] == 1
    # the frame went over the modem only, into the vehicle's receiver
    assert vehicle.modem.frames() == 1 == vehicle.frames_in()
    # and the vehicle runs it, as its status over rosbridge says
    wait_until(
        lambda: (client.get("/api/vehicle").json()["status"] or {}).get("mode") == "running",
        what="the vehicle running the circle",
    )

    vehicle.stop_telemetry()
    one_way = wait_until(
        lambda: (lk := link_of(client))["capability"] == "none" and lk,
        what="the link one-way",
    )
    assert one_way["acknowledges"] is False and one_way["connected"] is True  # the modem is up
    (why,) = [p for p in one_way["problems"] if p.startswith("no telemetry: ")]
    assert vehicle.url in why and "one-way copies" in why
    assert one_way["copies"] == 3  # chosen from link_ber 1e-2 for 0.999, as on any one-way link

    square = {"speed": 0.18, "depth": 2, "side_span": 6, "direction": "cw"}
    cmd = send(client, "square", square)
    assert cmd["two_way"] is False and cmd["copies"] == 3
    rec = wait_state(client, cmd["id"])
    assert rec["state"] == "sent" and rec["copies_sent"] == 3, rec
    vehicle.modem.wait_for("the square's copies", lambda: vehicle.modem.frames() == 4)
    assert vehicle.frames_in() == 4
