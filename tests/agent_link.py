"""An in-memory vehicle link for the light app (``tests/backend/conftest.py``'s ``client``).

:class:`AgentLink` is a :class:`station.link.Link` with no socket, no rosbridge and no
simulator behind it. What it keeps of the real links is their rules:

* a two-way link (:attr:`Capability.ACKS_AND_TELEMETRY`) hands every frame to the real onboard
  agent (:class:`onboard.agent.OnboardAgent`: sync, BCH, the vehicle's limits, the plan)
  of a vehicle holding still at ``state``, and its acknowledgement comes back on the event loop
  after ``transmit`` returned, through JSON as over rosbridge, like the simulated vehicle's;
* a two-way link reports the vehicle's pose and status once when it starts (and on
  :meth:`report`), as the contract's messages: the vehicle is known, it does not move;
* a one-way link (:attr:`Capability.NONE`, an ME modem) answers nothing;
* ``fail`` makes a frame not leave (``transmit`` returns the reason), as a modem or a closed
  socket does; ``answer = False`` loses every acknowledgement (the vehicle out of range).

Every frame that left is kept in :attr:`frames` (hex, in order), so a test reads what went out
on the wire without a modem or a bridge.

A fleet (issue 23): :func:`agent_fleet` makes N such vehicles, each with its address (its agent
takes addressed frames) and its own place, behind one :class:`AgentChannel`: the one
transmitter, whose every frame every vehicle hears (:meth:`AgentLink.hear`) and answers on its
own link, as a fleet on one ME link does (a vehicle a frame is not for answers
``other_vehicle``). On a one-way channel the vehicles still take the frames; nothing comes
back.
"""

from __future__ import annotations

import asyncio
import json
from typing import Any

from codec import Frame
from onboard.agent import OnboardAgent, command_json
from onboard.guidance import Guidance
from planner import Limits, VehicleState
from station.link import Capability, Link
from station.link_fleet import FleetLink
from vehicle_contract.endpoint import Pose
from vehicle_contract.fleet import FleetVehicle
from vehicle_contract.messages import pose_stamped_msg

#: The target the light app's settings name (never connected to: the link is given).
TARGET = "ws://127.0.0.1:9"
#: Where the vehicle holds still: 2 m deep at the origin, heading north.
HOLDING = VehicleState(0.0, 0.0, 2.0, heading_deg=0.0, speed_mps=0.0, t_s=100.0)


class AgentLink(Link):
    """A link to an in-memory vehicle running the onboard agent (see the module's doc)."""

    def __init__(
        self,
        capability: Capability = Capability.ACKS_AND_TELEMETRY,
        *,
        limits: Limits | None = None,
        state: VehicleState = HOLDING,
        target: str = TARGET,
        address: int | None = None,
    ) -> None:
        """``address``: a fleet's vehicle's (its agent takes addressed frames)."""
        super().__init__(target)
        self.capability = capability
        if not capability.acknowledges:
            self.capability_problems = ["an in-memory one-way link: nothing comes back"]
        self.agent = OnboardAgent(Guidance(), limits, address=address)
        self.state = state
        #: Hex of every frame that left, in order.
        self.frames: list[str] = []
        #: Every acknowledgement the vehicle sent back, in order.
        self.acks: list[dict[str, Any]] = []
        self.fail: str | None = None
        self.answer = True
        self._started = False

    @property
    def connected(self) -> bool:
        return self._started

    async def start(self) -> None:
        self._started = True
        if self.capability.telemetry:
            self.report()

    def report(self) -> None:
        """The vehicle's pose and status, as it publishes them (it holds still at ``state``)."""
        s = self.state
        self.on_pose(pose_stamped_msg(Pose(s.t_s, s.x_m, s.y_m, s.z_m, 0.0, s.heading_deg)))
        active = self.agent.active
        status = {
            "t_s": s.t_s,
            "x_m": s.x_m,
            "y_m": s.y_m,
            "depth_m": s.z_m,
            "heading_deg": s.heading_deg,
            "speed_mps": s.speed_mps,
            "battery_pct": 100.0,
            "mode": self.agent.guidance.mode.value,
            "pattern": None if active is None else active.pattern,
            "active": None if active is None else command_json(active.command),
        }
        self.on_status(json.loads(json.dumps(status)))

    async def stop(self) -> None:
        self._started = False

    async def transmit(self, frame: Frame) -> str | None:
        await asyncio.sleep(0)  # a real link yields to the loop while the frame goes out
        if self.fail is not None:
            return self.fail
        self.frames.append(frame.hex)
        if self.capability.acknowledges:
            self.hear(frame)
        return None

    def hear(self, frame: Frame) -> None:
        """The vehicle receives ``frame`` (of any length: a fleet's are addressed); its
        acknowledgement comes back on the event loop when the link carries one."""
        ack, _reference = self.agent.receive(frame.value, len(frame.bits), self.state)
        if self.capability.acknowledges and self.answer:
            wire = json.loads(json.dumps(ack))  # as the rosbridge string carries it
            self.acks.append(wire)
            asyncio.get_running_loop().call_soon(self.on_mission, wire)


class AgentChannel(Link):
    """The one transmitter of an in-memory fleet: every frame to every vehicle (see the
    module's doc). ``frames``: the hex of every frame that left, in order; ``fail`` makes a
    frame not leave."""

    def __init__(self, vehicles: dict[str, AgentLink], capability: Capability) -> None:
        super().__init__(TARGET)
        self.vehicles = vehicles
        self.capability = capability
        if not capability.acknowledges:
            self.capability_problems = ["an in-memory one-way channel: nothing comes back"]
        self.frames: list[str] = []
        self.fail: str | None = None
        self._started = False

    @property
    def connected(self) -> bool:
        return self._started

    async def start(self) -> None:
        self._started = True

    async def stop(self) -> None:
        self._started = False

    async def transmit(self, frame: Frame) -> str | None:
        await asyncio.sleep(0)
        if self.fail is not None:
            return self.fail
        self.frames.append(frame.hex)
        for vehicle in self.vehicles.values():
            vehicle.hear(frame)
        return None


def agent_fleet(
    vehicles: tuple[FleetVehicle, ...],
    capability: Capability = Capability.ACKS_AND_TELEMETRY,
    *,
    limits: Limits | None = None,
    spacing_m: float = 20.0,
) -> FleetLink:
    """A fleet link to in-memory vehicles (see the module's doc), each holding still 2 m deep
    at its own place: the first at the origin, each next ``spacing_m`` further east."""
    links = {
        v.name: AgentLink(
            capability,
            limits=limits,
            state=VehicleState(0.0, i * spacing_m, 2.0, 0.0, 0.0, 100.0),
            address=v.address,
        )
        for i, v in enumerate(vehicles)
    }
    return FleetLink(AgentChannel(links, capability), links)
