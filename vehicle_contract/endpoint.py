"""The contract between a vehicle (simulated or real) and the bridges that expose it.

The rosbridge server (:mod:`rosbridge.server`) drives any :class:`VehicleEndpoint`: it hands
received frames in, advances simulated time, and publishes what comes out (acknowledgements,
poses, status). :class:`sim.simulation.Simulation` is the simulated NemeSys that implements it.

All positions are NED metres (x north, y east, z down = depth), angles degrees, times seconds.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

from codec import FRAME_BYTES  # one packed frame: 100 bits MSB first plus 4 zero bits

__all__ = ["FRAME_BYTES", "FleetEndpoint", "Pose", "VehicleEndpoint"]


@dataclass(frozen=True, slots=True)
class Pose:
    """The vehicle's pose at simulated time ``t_s`` (NED metres, degrees)."""

    t_s: float
    x_m: float
    y_m: float
    z_m: float
    roll_deg: float
    heading_deg: float


class VehicleEndpoint(Protocol):
    """What a bridge needs from a vehicle."""

    @property
    def t_s(self) -> float:
        """Simulated (or vehicle) time in seconds."""
        ...

    def submit_frame(self, data: bytes) -> None:
        """Hand one received frame to the vehicle: ``FRAME_BYTES`` bytes, bits MSB first.

        The emulated ME channel and the onboard agent take it from there; every frame that
        reaches the agent produces one acknowledgement from :meth:`take_missions` (a wrong
        length is acknowledged as rejected, reason ``malformed``). A frame the channel loses
        produces none. Never raises for the frame's content.
        """
        ...

    def advance(self, dt_s: float) -> None:
        """Advance simulated time by ``dt_s`` seconds (physics, channel, agent, guidance)."""
        ...

    def take_missions(self) -> list[dict[str, Any]]:
        """Acknowledgements produced since the last call, oldest first, JSON-ready dicts."""
        ...

    def pose(self) -> Pose:
        """The current pose."""
        ...

    def status(self) -> dict[str, Any]:
        """JSON-ready status: depth, heading, speed, battery, mode, link state."""
        ...


@runtime_checkable
class FleetEndpoint(Protocol):
    """What a bridge needs from a fleet: several vehicles on one shared ME link, each under
    its own namespace (:func:`vehicle_contract.names.topic_names`), on one clock.

    The bridge advances and feeds the fleet as a whole (one :meth:`submit_frame` is one
    transmission, which every vehicle hears) and reads each vehicle in :attr:`members`
    (its pose, status and acknowledgements) under that vehicle's namespace;
    :class:`sim.fleet.FleetSimulation` is the simulated fleet.
    """

    @property
    def t_s(self) -> float:
        """The fleet's simulated time in seconds (every vehicle's)."""
        ...

    @property
    def members(self) -> Mapping[str, VehicleEndpoint]:
        """Each vehicle by its namespace (``"/auv1"``), in the fleet's order. The bridge calls
        only their ``pose``, ``status`` and ``take_missions``."""
        ...

    def submit_frame(self, data: bytes) -> None:
        """One frame on the shared link, now: every vehicle receives it through its own
        channel (its own errors, its own range), and each acknowledges what reaches it."""
        ...

    def advance(self, dt_s: float) -> None:
        """Advance every vehicle by ``dt_s`` simulated seconds."""
        ...
