"""Each vehicle's runtime record, and the fleet of them the console holds.

Without a fleet the console holds one vehicle, ``nemesys``, with no address: its hub is the
console's own hub and its link the console's link, so every view of it is today's. With a fleet
each vehicle has its own hub (its pose and status; the console's hub serves them all to the
pages: :attr:`backend.telemetry.TelemetryHub.feeds`) and its own link (what it reports over;
:class:`station.link_fleet.FleetLink`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from backend.commands.manager import FleetMember
from backend.commands.vehicles import SINGLE_VEHICLE, UnknownVehicle
from backend.messages import ActivePath
from backend.telemetry import TelemetryHub
from station.link import Link
from station.link_fleet import FleetLink
from vehicle_contract.fleet import FleetVehicle

__all__ = ["Fleet", "VehicleRuntime", "members", "vehicle_links"]


@dataclass(eq=False)
class VehicleRuntime:
    """One vehicle as the running console holds it."""

    name: str
    #: Its frames' address (1-15); None: the single vehicle (unaddressed frames).
    address: int | None
    #: Its last pose and status (the single vehicle: the console's hub).
    hub: TelemetryHub
    #: What it reports back over (set when the console starts its link).
    link: Link | None = None
    #: The path it flies, as the station mirrors it (None: none known).
    active_path: ActivePath | None = None
    #: Poses it sent, for the 3D view's one vehicle (the single vehicle, or a fleet's first).
    drawn: bool = field(default=False)


class Fleet:
    """The console's vehicles, by name, in the order configured."""

    def __init__(self, vehicles: tuple[FleetVehicle, ...], hub: TelemetryHub) -> None:
        """``vehicles``: the fleet (empty: the single vehicle, on ``hub``). A fleet's vehicles
        get hubs of their own, served to the pages through ``hub``."""
        #: A fleet is configured: frames are addressed, requests name their vehicle.
        self.configured = bool(vehicles)
        if not vehicles:
            single = VehicleRuntime(SINGLE_VEHICLE, None, hub, drawn=True)
            self.vehicles = {SINGLE_VEHICLE: single}
            return
        self.vehicles = {
            v.name: VehicleRuntime(
                v.name, v.address, TelemetryHub(1.0 / hub.period_s, vehicle=v.name)
            )
            for v in vehicles
        }
        next(iter(self.vehicles.values())).drawn = True
        hub.feeds = [v.hub for v in self.vehicles.values()]

    @property
    def names(self) -> list[str]:
        return list(self.vehicles)

    @property
    def first(self) -> VehicleRuntime:
        """The single vehicle, or a fleet's first (what a single-vehicle view shows)."""
        return next(iter(self.vehicles.values()))

    def get(self, name: str | None) -> VehicleRuntime:
        """The vehicle ``name`` (None: the first).

        Raises:
            UnknownVehicle: naming the known ones.
        """
        if name is None:
            return self.first
        vehicle = self.vehicles.get(name)
        if vehicle is None:
            raise UnknownVehicle(name, self.names)
        return vehicle

    def news_name(self, vehicle: VehicleRuntime) -> str | None:
        """The name a piece of news about ``vehicle`` carries: a fleet's, else none."""
        return vehicle.name if self.configured else None


def vehicle_links(fleet: Fleet, link: Link) -> list[tuple[VehicleRuntime, Link]]:
    """Each vehicle with the link it reports over: the single vehicle's is ``link``; a
    fleet's, its own of the :class:`station.link_fleet.FleetLink`.

    Raises:
        ValueError: a fleet on a link that is not a fleet's, or not of these vehicles.
    """
    if not fleet.configured:
        return [(fleet.first, link)]
    if not isinstance(link, FleetLink) or set(link.vehicles) != set(fleet.vehicles):
        has = sorted(link.vehicles) if isinstance(link, FleetLink) else "one vehicle"
        raise ValueError(
            f"the fleet {fleet.names} needs a fleet link of the same vehicles, not {has}"
        )
    return [(v, link.vehicles[name]) for name, v in fleet.vehicles.items()]


def members(fleet: Fleet) -> list[FleetMember]:
    """A fleet's vehicles as the command manager takes them (none: the single vehicle)."""
    if not fleet.configured:
        return []
    out = []
    for v in fleet.vehicles.values():
        assert v.address is not None and v.link is not None, "a fleet's vehicle, listened to"
        out.append(FleetMember(v.name, v.address, v.link, v.hub))
    return out
