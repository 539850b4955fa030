"""A fleet on one ME link: one transmitter for every vehicle's frames, and each vehicle's own
link for what it reports back (docs/protocol.md, "Addressing").

:class:`FleetLink` is the console's link when a fleet is configured (``NEMESYS_VEHICLES``).
Its :meth:`~FleetLink.transmit` is the one transmitter's: every frame of every vehicle, one at
a time (the frames carry their addresses; the command manager schedules them). ``vehicles``
holds, by name, the link each vehicle reports over, whose capability decides that vehicle's
delivery rules (one copy and an acknowledgement, or repeated copies):

* an ME modem alone: nothing comes back from any vehicle; each one's link is a
  :class:`SharedTransmitter`, a view of the modem (one-way, its health the modem's);
* an ME modem with ``telemetry`` (the hybrid link): each vehicle's own rosbridge link under
  its namespace (``/auv1/nemesys/...``), carrying no frames;
* a rosbridge target: the frames are published once each on the fleet's channel topic, the
  frame topic under no namespace (``/nemesys/frame``: the one emulated ME channel every
  vehicle hears, as the fleet simulator serves it), and each vehicle's telemetry and
  acknowledgements come under its namespace.

Every link here is one of :mod:`station.link` or :mod:`station.link_modem`; this module only
puts them together.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import NoReturn

from codec import Frame
from station.link import Capability, Link, RosbridgeLink
from station.link_modem import (
    BACKOFF_S,
    MAX_BACKOFF_S,
    PROBE_S,
    ModemLink,
    parse_telemetry,
)
from station.transmit import LinkCheck
from vehicle_contract.fleet import FleetVehicle

__all__ = ["FleetLink", "SharedTransmitter", "open_fleet_link"]


class _Follows(Link):
    """A link whose connection is another's (``frames``): read through, never set."""

    def __init__(self, frames: Link) -> None:
        self.frames = frames
        super().__init__(frames.target)

    @property
    def connected(self) -> bool:
        return self.frames.connected

    @property
    def connection_problem(self) -> str | None:
        return self.frames.connection_problem

    @connection_problem.setter
    def connection_problem(self, value: str | None) -> None:
        """Set by the base class's constructor only: the transmitter's is the one read."""


class SharedTransmitter(_Follows):
    """A fleet's vehicle on a one-way link: nothing of its own comes back, so it is what the
    shared transmitter is (its capability, problems and connection); its frames leave by the
    fleet's :class:`FleetLink`."""

    def __init__(self, frames: Link, name: str) -> None:
        super().__init__(frames)
        self.name = name

    @property
    def capability(self) -> Capability:
        return self.frames.capability

    @capability.setter
    def capability(self, value: Capability) -> NoReturn:
        raise AttributeError("a one-way fleet's vehicle has the shared transmitter's capability")

    @property
    def capability_problems(self) -> list[str]:
        return self.frames.capability_problems

    @capability_problems.setter
    def capability_problems(self, value: list[str]) -> None:
        """Set by the base class's constructor only: the transmitter's are the ones read."""

    async def transmit(self, frame: Frame) -> str | None:
        return f"{self.name}'s frames leave by the fleet's one transmitter ({self.target})"

    async def test(self) -> list[LinkCheck]:
        return []  # the transmitter's own test covers it


class FleetLink(_Follows):
    """One transmitter (``frames``) for a fleet, and each vehicle's link by name (see the
    module's doc). Its own capability and health are the transmitter's."""

    def __init__(self, frames: Link, vehicles: Mapping[str, Link]) -> None:
        super().__init__(frames)
        if not vehicles:
            raise ValueError("a fleet link needs at least one vehicle")
        self.vehicles: dict[str, Link] = dict(vehicles)

    @property
    def capability(self) -> Capability:
        return self.frames.capability

    @capability.setter
    def capability(self, value: Capability) -> NoReturn:
        raise AttributeError("a fleet link's capability is its transmitter's")

    @property
    def capability_problems(self) -> list[str]:
        return self.frames.capability_problems

    @capability_problems.setter
    def capability_problems(self, value: list[str]) -> None:
        """Set by the base class's constructor only: the transmitter's are the ones read."""

    def _own(self) -> list[Link]:
        """The vehicles' links that are links of their own (not views of the transmitter)."""
        return [v for v in self.vehicles.values() if not isinstance(v, SharedTransmitter)]

    async def start(self) -> None:
        await self.frames.start()
        for link in self._own():
            await link.start()

    async def stop(self) -> None:
        for link in self._own():
            await link.stop()
        await self.frames.stop()

    async def wait_connected(self, timeout_s: float) -> bool:
        """Wait for the transmitter and every vehicle's own rosbridge link to be ready (each
        within ``timeout_s``; a modem is ready once started); whether all are connected."""
        links = [self.frames, *self._own()]
        for link in links:
            if isinstance(link, RosbridgeLink):
                await link.wait_connected(timeout_s)
        return all(link.connected for link in links)

    async def transmit(self, frame: Frame) -> str | None:
        return await self.frames.transmit(frame)

    async def test(self) -> list[LinkCheck]:
        """The transmitter's checks, then each vehicle's own link's (named by the vehicle)."""
        checks = await self.frames.test()
        for name, link in self.vehicles.items():
            if isinstance(link, SharedTransmitter):
                continue
            checks += [
                LinkCheck(f"{c.what} ({name})", c.target, c.ok, c.reason, c.detail)
                for c in await link.test()
            ]
        return checks


def open_fleet_link(
    target: str,
    bitrate_bps: float,
    vehicles: Sequence[FleetVehicle],
    telemetry: str | None = None,
    *,
    probe_s: float = PROBE_S,
    backoff_s: float = BACKOFF_S,
    max_backoff_s: float = MAX_BACKOFF_S,
) -> FleetLink:
    """The fleet's link for a target (see the module's doc): ``ws://`` -> frames on the
    fleet's channel topic and each vehicle's telemetry under its namespace; anything else ->
    the ME modem, with each vehicle's telemetry over ``telemetry`` (a rosbridge) when given.
    ``probe_s``, ``backoff_s``, ``max_backoff_s``: the modem's watch
    (:class:`station.link_modem.ModemLink`).

    Raises:
        ValueError: ``telemetry`` with a rosbridge target, or a malformed target or
            ``telemetry``.
    """
    if target.startswith(("ws://", "wss://")):
        if telemetry:
            raise ValueError(
                "telemetry is for an ME modem target (serial://, tcp://, loop://): a rosbridge "
                f"target ({target}) carries telemetry and acknowledgements itself"
            )
        channel = RosbridgeLink(target)
        own: dict[str, Link] = {
            v.name: RosbridgeLink(target, namespace=v.name, frames=False) for v in vehicles
        }
        return FleetLink(channel, own)
    frames = ModemLink(
        target, bitrate_bps, probe_s=probe_s, backoff_s=backoff_s, max_backoff_s=max_backoff_s
    )
    if telemetry:
        url = parse_telemetry(telemetry)
        own = {v.name: RosbridgeLink(url, namespace=v.name, frames=False) for v in vehicles}
        return FleetLink(frames, own)
    return FleetLink(frames, {v.name: SharedTransmitter(frames, v.name) for v in vehicles})
