"""The link of a console without a transmitter (``NEMESYS_TARGET=relay``): "relay via <the
console that holds it>".

It transmits nothing (the command service hands this console's commands to the outbox:
:mod:`backend.relay.shore`) and hears nothing of the vehicle itself; what it knows is what the
transmitting consoles write into the ``transmitters`` table every second (their target and
their link's health: :mod:`backend.relay.ship`), read from the shared log at most every
:data:`READ_EVERY_S`. It is ``connected`` while such a console said so within
:data:`FRESH_S`, and its capability is that console's (acknowledgements come back to this
console as the states of the records the other console writes).

With a fleet (``NEMESYS_VEHICLES``, the same as the transmitting console's) the link is a
:class:`station.link_fleet.FleetLink` of the one :class:`RelayLink` and a
:class:`RelayVehicleLink` per vehicle (:func:`relay_fleet_link`): each reports "relay via" that
console, and a vehicle it does not say it has is not connected, its problem naming the
vehicles it has (a command to it would be refused there, naming them too). With several
transmitting consoles (two ships, each with its own vehicles), each vehicle's link is the one
that says it has that vehicle.
"""

from __future__ import annotations

import logging
import time
from typing import Final, NoReturn

from backend.mission_log import outbox
from backend.mission_log.store import LogWriteError, MissionLog
from backend.relay.model import RelayView
from backend.settings import RELAY_TARGET
from codec import Frame
from station.link import Capability, Link
from station.link_fleet import FleetLink, SharedTransmitter
from station.transmit import LinkCheck
from vehicle_contract.fleet import FleetVehicle

logger = logging.getLogger("backend.relay")

#: A transmitting console is taken as there while it said so this recently (s); it says so
#: every :data:`backend.relay.ship.BEAT_S`.
FRESH_S: Final = 5.0
#: The table is read at most this often (s): the link's properties are asked many times for
#: one health report.
READ_EVERY_S: Final = 0.5
#: What :meth:`RelayLink.transmit` answers (it is never asked: the service relays).
NO_TRANSMITTER: Final = (
    "this console has no transmitter (target relay): its commands go through the console that "
    "holds it"
)


class RelayLink(Link):
    """See the module's doc. :meth:`attach` gives it the log once the console opened it.
    ``fleet``: this console's vehicles' names, with a fleet (checked against the transmitting
    console's in :meth:`test`)."""

    def __init__(self, fleet: tuple[str, ...] = ()) -> None:
        super().__init__(RELAY_TARGET)
        self.fleet = fleet
        self._log: MissionLog | None = None
        #: Every transmitting console as last read (newest first), each as shown.
        self._views: list[RelayView] = []
        self._read_at: float | None = None
        self._problem: str | None = None

    def attach(self, log: MissionLog) -> None:
        self._log = log

    def _read(self) -> list[RelayView]:
        """The transmitting consoles as last read (read again when older than
        :data:`READ_EVERY_S`; a log out of reach: the last ones, no longer fresh)."""
        now = time.monotonic()
        if self._log is not None and (self._read_at is None or now - self._read_at > READ_EVERY_S):
            self._read_at = now
            try:
                found, now_s = outbox.transmitters(self._log)
                self._views = [view_of([t], now_s) for t in found]
                self._problem = None
            except LogWriteError as err:
                self._views = [v.model_copy(update={"fresh": False}) for v in self._views]
                self._problem = f"the transmitting consoles cannot be read: {err.reason}"
        return self._views

    def view(self, vehicle: str | None = None) -> RelayView:
        """The transmitting console this console's commands go through: to ``vehicle``, the
        one that says it has it (the freshest of them), else, and for the link as a whole,
        the one seen most recently. Several ships on one log each take their own vehicles'."""
        views = self._read()
        if vehicle is not None:
            having = [v for v in views if v.vehicles is not None and vehicle in v.vehicles]
            if having:
                return next((v for v in having if v.fresh), having[0])
        return views[0] if views else RelayView()

    @property
    def connected(self) -> bool:
        return self.problem_of() is None

    @property
    def connection_problem(self) -> str | None:
        return self.problem_of()

    @connection_problem.setter
    def connection_problem(self, value: str | None) -> None:
        """The base class sets it at construction; this link's is read from the log."""

    @property
    def capability(self) -> Capability:
        return self.capability_of()

    @capability.setter
    def capability(self, value: Capability) -> None:
        """The base class sets it at construction; this link's is the transmitting
        console's."""

    def capability_of(self, vehicle: str | None = None) -> Capability:
        """What the console taking commands (to ``vehicle``: :meth:`view`) hears back."""
        v = self.view(vehicle)
        return v.capability if v.fresh and v.capability is not None else Capability.UNKNOWN

    async def transmit(self, frame: Frame) -> str | None:
        return NO_TRANSMITTER

    def lacks(self, vehicle: str) -> str | None:
        """Why the transmitting console will refuse commands to ``vehicle`` (it said which
        vehicles it has, and this is not one; several: none of them has it); None: one has
        it, or has not said."""
        v = self.view(vehicle)
        if v.vehicles is None or vehicle in v.vehicles:
            return None
        return (
            f"console {v.via!r}, holding the transmitter, has no vehicle {vehicle!r} (its "
            f"vehicles: {', '.join(v.vehicles)}): commands to it are refused there; give this "
            "console the same fleet (NEMESYS_VEHICLES)"
        )

    def problem_of(self, vehicle: str | None = None) -> str | None:
        """Why the console taking commands (to ``vehicle``: :meth:`view`) does not now; None:
        it does."""
        v = self.view(vehicle)
        if v.fresh:
            return None if vehicle is None else self.lacks(vehicle)
        if self._problem is not None:
            return self._problem
        if v.via is None:
            return "no console holding the transmitter is on the mission log"
        age = v.seen_age_s or 0.0
        return f"console {v.via!r}, holding the transmitter, last seen {age:.0f} s ago"

    async def test(self) -> list[LinkCheck]:
        self._read_at = None  # read now
        v = self.view()
        problem = self.connection_problem
        detail = (
            f"relay via console {v.via!r} (its target {v.target}, its link "
            f"{'connected' if v.connected else 'NOT connected'}, {v.level or 'unknown'})"
            if v.via is not None
            else "no console holding the transmitter has said so on the mission log"
        )
        checks = [LinkCheck("relay", RELAY_TARGET, problem is None, problem, problem or detail)]
        if self.fleet:
            lacking = [why for name in self.fleet if (why := self.lacks(name)) is not None]
            said = f"console {v.via!r} has {', '.join(self.fleet)}"
            fleet_problem = "; ".join(lacking) or None
            checks.append(
                LinkCheck(
                    "relay fleet", RELAY_TARGET, not lacking, fleet_problem, fleet_problem or said
                )
            )
        return checks


class RelayVehicleLink(SharedTransmitter):
    """A fleet's vehicle on a console without a transmitter: what the :class:`RelayLink`
    (``relay``) is, unless the transmitting console says it has no such vehicle (then not
    connected, the problem naming the vehicles it has). Nothing of its own comes back: its
    telemetry is the shared log's (:class:`backend.relay.telemetry.RelayedTelemetry`)."""

    def __init__(self, relay: RelayLink, name: str) -> None:
        super().__init__(relay, name)
        self.relay = relay

    @property
    def connected(self) -> bool:
        return self.relay.problem_of(self.name) is None

    @property
    def connection_problem(self) -> str | None:
        return self.relay.problem_of(self.name)

    @connection_problem.setter
    def connection_problem(self, value: str | None) -> None:
        """Set by the base class's constructor only: the relay's are the ones read."""

    @property
    def capability(self) -> Capability:
        return self.relay.capability_of(self.name)

    @capability.setter
    def capability(self, value: Capability) -> NoReturn:
        raise AttributeError("a relayed vehicle has its transmitting console's capability")


def relay_fleet_link(vehicles: tuple[FleetVehicle, ...]) -> FleetLink:
    """The link of a console without a transmitter with a fleet: one :class:`RelayLink` (its
    "frames", which it never sends) and a :class:`RelayVehicleLink` per vehicle."""
    relay = RelayLink(tuple(v.name for v in vehicles))
    return FleetLink(relay, {v.name: RelayVehicleLink(relay, v.name) for v in vehicles})


def view_of(found: list[outbox.Transmitter], now_s: float) -> RelayView:
    """The most recently seen transmitting console as shown (``found``: newest first)."""
    if not found:
        return RelayView()
    t = found[0]
    age = max(0.0, now_s - t.seen_s)
    h = t.health
    level, problems, connected = h.get("level"), h.get("problems"), h.get("connected")
    try:
        capability = Capability(str(h.get("capability")))
    except ValueError:
        capability = None
    datum = datum_of(h.get("datum"))
    vehicles = h.get("vehicles")
    return RelayView(
        via=t.console,
        target=t.target,
        seen_age_s=round(age, 3),
        fresh=age <= FRESH_S,
        connected=connected if isinstance(connected, bool) else None,
        capability=capability,
        level=level if level in ("green", "amber", "red") else None,
        problems=[str(p) for p in problems] if isinstance(problems, list) else [],
        datum_lat_deg=None if datum is None else datum[0],
        datum_lon_deg=None if datum is None else datum[1],
        vehicles=[str(n) for n in vehicles] if isinstance(vehicles, list) else None,
    )


def datum_of(doc: object) -> tuple[float, float] | None:
    """(lat, lon) of the datum a transmitting console's health carries (None: none said)."""
    if not isinstance(doc, dict):
        return None
    lat, lon = doc.get("lat_deg"), doc.get("lon_deg")
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in (lat, lon)):
        return None
    return float(lat or 0.0), float(lon or 0.0)
