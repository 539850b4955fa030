"""Each vehicle as the console knows it, its link's health, and the one transmitter's queue:
what ``/api/vehicle``, ``/api/vehicles``, ``/api/vehicles/{name}`` and ``/api/transmitter``
answer, and the ``link`` news of ``/ws``."""

from __future__ import annotations

import contextlib
from typing import TYPE_CHECKING

from backend.commands.airtime import copies_out_s
from backend.commands.health import LinkHealth, link_health_of
from backend.commands.link_settings import ber_now
from backend.fleet.models import FleetVehicleView, QueuedDelivery, TransmitterView
from backend.fleet.state import VehicleRuntime
from backend.messages import LinkMessage, VehicleView, for_vehicle

if TYPE_CHECKING:
    from backend.console import Console

__all__ = [
    "fleet_vehicle",
    "link_health",
    "link_news",
    "transmitter",
    "vehicle_list",
    "vehicle_view",
]


def _key(console: Console, vehicle: VehicleRuntime) -> str | None:
    """The name the command manager knows ``vehicle`` by (None: the single vehicle)."""
    return vehicle.name if console.fleet.configured else None


def link_health(console: Console, name: str | None = None) -> LinkHealth:
    """What the station knows of its link to vehicle ``name`` (None: the single vehicle, or a
    fleet's first): on a one-way modem, the shared transmitter's; with telemetry, its own.

    Raises:
        UnknownVehicle: naming the known ones.
    """
    v = console.fleet.get(name)
    cm = console.commands
    assert v.link is not None and cm is not None, "the console has not started"
    key = _key(console, v)
    return link_health_of(
        v.link,
        cm,
        v.hub,
        console.settings.target,
        ber_now(console, key),
        console.ber_choice.copies_from,
        datum_problem=console.datum_watch.problem(console.datum),
        mission_log=console.control.mission_log() if console.control else None,
        relay=console.relay.view(key) if console.relay else None,
        vehicle=key,
    )


def link_news(console: Console) -> list[LinkMessage]:
    """The ``link`` news: the single vehicle's health, or one per fleet vehicle, named."""
    return [
        for_vehicle(LinkMessage(link=link_health(console, v.name)), console.fleet.news_name(v))
        for v in console.fleet.vehicles.values()
    ]


def vehicle_view(console: Console, name: str | None = None) -> VehicleView:
    """Pose, status, the vehicle's echoed active command vs the last sent, link health and
    belief, of vehicle ``name`` (None: the single vehicle, or a fleet's first).

    Raises:
        UnknownVehicle: naming the known ones.
    """
    return VehicleView.model_validate(_view(console, console.fleet.get(name)))


def _view(console: Console, v: VehicleRuntime) -> dict[str, object]:
    cm = console.commands
    a = cm.addressee(_key(console, v)) if cm is not None else None
    last_sent = a.last_sent if a else None
    if console.settings.relay and console.log is not None:  # sent by the transmitting console
        with contextlib.suppress(*console.log.read_errors):  # out of reach: as known before
            last_sent = console.log.last_sent(vehicle=_key(console, v)) or last_sent
    return {
        "pose": v.hub.pose,
        "status": v.hub.status,
        "active": a.mirror.active if a else None,
        "last_sent": last_sent,
        "active_path": v.active_path,
        "echo_mismatch": a.mirror.echo_mismatch if a else False,
        "age_s": v.hub.age_s(),
        "link": link_health(console, v.name),
        "belief": console.beliefs[v.name].current() if console.beliefs else None,
    }


def fleet_vehicle(console: Console, name: str) -> FleetVehicleView:
    """Vehicle ``name`` as ``/api/vehicles/{name}`` shows it.

    Raises:
        UnknownVehicle: naming the known ones.
    """
    v = console.fleet.get(name)
    budget, repeating = _airtime(console).get(v.name, (0.0, False))
    return FleetVehicleView.model_validate(
        {
            **_view(console, v),
            "name": v.name,
            "address": v.address,
            "airtime_budget_s": budget,
            "repeating": repeating,
        }
    )


def vehicle_list(console: Console) -> list[FleetVehicleView]:
    """Every vehicle of the console, in the order configured."""
    return [fleet_vehicle(console, name) for name in console.fleet.names]


def _airtime(console: Console) -> dict[str, tuple[float, bool]]:
    """Each vehicle with queued copies: (seconds until its last bounded copy is out, whether
    a Surface repeats to it until acknowledged)."""
    cm = console.commands
    if cm is None:
        return {}
    ways = cm.on_the_way()
    ends = copies_out_s([w.queued for w in ways])
    out: dict[str, tuple[float, bool]] = {}
    for way, end in zip(ways, ends, strict=True):
        for name in way.vehicles:
            budget, repeating = out.get(name, (0.0, False))
            out[name] = (max(budget, end), repeating or way.queued.copies_left is None)
    return out


def transmitter(console: Console) -> TransmitterView:
    """The one transmitter: every delivery still going out, and the airtime budget."""
    cm, link = console.commands, console.link
    assert cm is not None and link is not None, "the console has not started"
    ways = cm.on_the_way()
    ends = copies_out_s([w.queued for w in ways])
    problem = None if link.connected else link.connection_problem or "not connected"
    return TransmitterView(
        target=console.settings.target,
        connected=link.connected,
        problems=[] if problem is None else [problem],
        addressed=console.fleet.configured,
        airtime_budget_s=max(ends, default=0.0),
        repeating_until_acknowledged=sorted(
            {n for w in ways if w.queued.copies_left is None for n in w.vehicles}
        ),
        queued=[
            QueuedDelivery(
                commands=list(w.records),
                vehicles=list(w.vehicles),
                pattern=w.pattern,
                copies_left=w.queued.copies_left,
                next_copy_in_s=w.queued.due_in_s,
                surface=w.queued.surface,
                frame_airtime_s=w.queued.airtime_s,
            )
            for w in ways
        ],
    )
