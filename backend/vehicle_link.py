"""The link the console opens to its vehicle, from the settings.

Training: the simulated vehicle and its rosbridge server on loopback, reached through the same
rosbridge client a real vehicle gets (frames only from this console: a per-start secret for
the rosbridge auth op). Otherwise: the target the settings name (a rosbridge URL, an ME modem,
or a modem with telemetry over rosbridge: :func:`station.link_modem.open_link`), or no
transmitter at all (``relay``: :class:`backend.relay.link.RelayLink`). A fleet
(``NEMESYS_VEHICLES``) on one of those: :func:`station.link_fleet.open_fleet_link`, one
transmitter and each vehicle's own link for what it reports; with ``relay``,
:func:`backend.relay.link.relay_fleet_link`, a relay link per vehicle.
"""

from __future__ import annotations

import secrets
from typing import TYPE_CHECKING

from backend.settings import Settings
from planner import Limits
from station.link import Link, RosbridgeLink
from station.link_fleet import FleetLink, open_fleet_link
from station.link_modem import open_link

if TYPE_CHECKING:  # the heavy ones, imported when training starts
    from rosbridge.server import BridgeServer
    from sim.fleet import FleetSimulation
    from sim.simulation import Simulation


async def open_vehicle_link(
    s: Settings, limits: Limits
) -> tuple[Link, Simulation | None, BridgeServer | None]:
    """The link (not started), and in training the simulator and its started bridge.

    Raises:
        ValueError: a target or telemetry setting that names no link (the message says
            which forms are allowed).
    """
    if s.relay:
        from backend.relay.link import RelayLink, relay_fleet_link

        return (relay_fleet_link(s.fleet) if s.fleet else RelayLink()), None, None
    if s.fleet and not s.training:  # in training: open_training_fleet
        fleet = open_fleet_link(s.target, s.bitrate_bps, s.fleet, s.telemetry or None)
        return fleet, None, None
    if not s.training:
        link = open_link(
            s.target, s.bitrate_bps, s.telemetry or None, namespace=s.vehicle_namespace
        )
        return link, None, None
    from rosbridge.server import BridgeServer
    from sim.simulation import SimConfig, Simulation

    sim = Simulation(SimConfig(seed=s.sim_seed, limits=limits))
    secret = secrets.token_hex(16)
    bridge = BridgeServer(
        sim, "127.0.0.1", s.sim_port, time_scale=s.sim_time_scale, auth_secret=secret
    )
    await bridge.start()
    link = RosbridgeLink(f"ws://127.0.0.1:{bridge.port}", auth_secret=secret)
    return link, sim, bridge


async def open_training_fleet(
    s: Settings, limits: Limits
) -> tuple[FleetLink, FleetSimulation, BridgeServer]:
    """Training with a fleet (``NEMESYS_VEHICLES``): the simulated fleet on one shared ME link
    behind one rosbridge server on loopback (:class:`sim.fleet.FleetSimulation`), and the
    console's fleet link to it: frames published once on the un-namespaced frame topic (the
    station's transmitter: every vehicle hears it), each vehicle's telemetry and
    acknowledgements under its namespace. Frames only from this console, as for one vehicle.

    Raises:
        ValueError: a fleet that would start beyond the link's range (the simulator's words).
    """
    from rosbridge.server import BridgeServer
    from sim.fleet import FleetSimulation
    from sim.simulation import SimConfig

    fleet = FleetSimulation(s.fleet, SimConfig(seed=s.sim_seed, limits=limits))
    secret = secrets.token_hex(16)
    bridge = BridgeServer(
        fleet, "127.0.0.1", s.sim_port, time_scale=s.sim_time_scale, auth_secret=secret
    )
    await bridge.start()
    url = f"ws://127.0.0.1:{bridge.port}"
    own: dict[str, Link] = {
        v.name: RosbridgeLink(url, auth_secret=secret, namespace=v.name, frames=False)
        for v in s.fleet
    }
    return FleetLink(RosbridgeLink(url, auth_secret=secret), own), fleet, bridge


def link_delay_s(sim: Simulation | None, bridge: BridgeServer | None) -> float:
    """The emulated channel's delay on the wall clock (s), what an acknowledgement's timeout
    adds; 0 off training. The channel's delay is in simulated seconds."""
    if sim is None:
        return 0.0
    delay = sim.channel.config.delay_s
    scale = bridge.time_scale if bridge is not None else 1.0
    return delay / scale if scale > 0 else 3600.0
