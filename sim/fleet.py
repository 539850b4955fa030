"""A simulated fleet on one ME link: N vehicles, each its own twin, on one clock.

Each vehicle of a :class:`FleetSimulation` is a whole :class:`sim.simulation.Simulation` (the
model, its environment, its battery, its onboard agent with the vehicle's address, its
guidance) under the vehicle's namespace (``/auv1``). They share one emulated ME link, a
broadcast medium: :meth:`FleetSimulation.submit_frame` is one transmission, and every vehicle
receives it through its own receiver's channel (:class:`sim.channel.MEChannel`, seeded per
vehicle), so each copy has its own bit errors and its own range from the transmitter (a vehicle
beyond ``range_m`` hears nothing). Each vehicle's agent then decides as a fleet's vehicle does
(docs/protocol.md, "Addressing"): a frame addressed to another is acknowledged rejected
``other_vehicle`` and changes nothing; a Surface to all (address 0) surfaces every vehicle.

The vehicles start apart, :data:`DEFAULT_SPACING_M` from each other on a grid of rows of
:data:`ROW_LENGTH` (:func:`start_positions`), the first where a single vehicle would start;
each must start within the link's range of the transmitter. Everything random is seeded from
``SimConfig.seed`` and the vehicle's address (:func:`vehicle_seed`), so a run is repeatable.

The fleet is a :class:`vehicle_contract.endpoint.FleetEndpoint`:
``BridgeServer(fleet, ...)`` serves every vehicle on one rosbridge server, each under its
namespace, and hands each frame published on any frame topic to :meth:`submit_frame` once.

Speed: the vehicles are stepped one after another over the same interval
(:meth:`FleetSimulation.run_until`). Nothing couples them inside an interval (a frame reaches
them only at a submission, between intervals, when all are at the same time), so this is the
lock-step loop, without its per-step overhead; ``nemesys bench sim`` measures it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from types import MappingProxyType
from typing import Final

from sim.channel import ChannelConfig
from sim.environment import CurrentConfig
from sim.simulation import SimConfig, Simulation
from vehicle_contract.fleet import FleetVehicle, check_fleet

__all__ = [
    "DEFAULT_SPACING_M",
    "ROW_LENGTH",
    "FleetSimulation",
    "start_positions",
    "vehicle_seed",
]

#: Metres between neighbouring vehicles at the start: apart, and all within a few tens of
#: metres of the start so every one is well inside the link's range.
DEFAULT_SPACING_M: Final = 30.0
#: Vehicles per row of the starting grid (rows run east, successive rows north).
ROW_LENGTH: Final = 5
#: Seeds per vehicle: a simulation draws from ``seed``, ``seed + 1`` and ``seed + 2``.
_SEED_STRIDE: Final = 4
#: Seeds per fleet seed: every address's streams stay apart from another run's.
_RUN_STRIDE: Final = 100


def vehicle_seed(seed: int, address: int) -> int:
    """The seed of the vehicle with ``address`` in a fleet run with ``seed``: its own streams
    (channel, current, depth sensor), the same whatever the other vehicles are."""
    return seed * _RUN_STRIDE + _SEED_STRIDE * address


def start_positions(
    count: int, x_m: float = 0.0, y_m: float = 0.0, spacing_m: float = DEFAULT_SPACING_M
) -> list[tuple[float, float]]:
    """Where ``count`` vehicles start (NED metres): the first at (``x_m``, ``y_m``), the others
    ``spacing_m`` apart on a grid of rows of :data:`ROW_LENGTH`, each row east of its first
    vehicle, the next row ``spacing_m`` north.

    Raises:
        ValueError: ``spacing_m`` not a positive finite number of metres.
    """
    if not (math.isfinite(spacing_m) and spacing_m > 0):
        raise ValueError(f"spacing_m must be a positive number of metres, got {spacing_m!r}")
    return [
        (x_m + spacing_m * (i // ROW_LENGTH), y_m + spacing_m * (i % ROW_LENGTH))
        for i in range(count)
    ]


class FleetSimulation:
    """N simulated vehicles on one shared ME link (see the module doc).

    ``vehicles``: the fleet (:func:`vehicle_contract.fleet.parse_vehicles`), at least one.
    ``config``: what every vehicle shares (seed, channel, current, limits, the transmitter's
    position, the first vehicle's start); each vehicle gets its own start
    (:func:`start_positions`), seed (:func:`vehicle_seed`) and address.

    Raises:
        ValueError: no vehicle, a fleet :func:`vehicle_contract.fleet.check_fleet` refuses
            (a :class:`vehicle_contract.fleet.FleetError`), a bad ``spacing_m``, or a vehicle
            that would start beyond the link's range of the transmitter (named, with both
            distances).
    """

    def __init__(
        self,
        vehicles: Sequence[FleetVehicle],
        config: SimConfig | None = None,
        *,
        spacing_m: float = DEFAULT_SPACING_M,
    ) -> None:
        if not vehicles:
            raise ValueError("a fleet simulation needs at least one vehicle")
        self.vehicles: tuple[FleetVehicle, ...] = check_fleet(list(vehicles))
        self.spacing_m = spacing_m
        self._sims: dict[str, Simulation] = {}
        #: What every vehicle shares (each gets its own start, seed and address from it).
        self.config: SimConfig = config or SimConfig()
        self.reset()

    # --- the fleet -----------------------------------------------------------------------

    def reset(self, config: SimConfig | None = None) -> None:
        """Every vehicle starts again from its start pose (optionally with a new shared
        config); the link's frames in flight are forgotten."""
        cfg = self.config = config or self.config
        starts = start_positions(len(self.vehicles), cfg.start_x_m, cfg.start_y_m, self.spacing_m)
        range_m = cfg.channel.range_m
        sims: dict[str, Simulation] = {}
        for v, (x_m, y_m) in zip(self.vehicles, starts, strict=True):
            own = replace(
                cfg,
                seed=vehicle_seed(cfg.seed, v.address),
                start_x_m=x_m,
                start_y_m=y_m,
                address=v.address,
            )
            distance_m = math.dist((x_m, y_m, cfg.start_z_m), (cfg.station_x_m, cfg.station_y_m, 0))
            if distance_m > range_m:
                raise ValueError(
                    f"vehicle {v.name} would start {distance_m:.0f} m from the transmitter, "
                    f"beyond the link's range of {range_m:g} m: start them closer (spacing "
                    f"{self.spacing_m:g} m now) or use fewer vehicles"
                )
            sims[v.namespace] = Simulation(own)
        self._sims = sims
        self._clock_s = 0.0
        #: Frames put on the link (each heard by every vehicle).
        self.transmissions = 0

    @property
    def members(self) -> Mapping[str, Simulation]:
        """Each vehicle's simulation by its namespace (``"/auv1"``), in the fleet's order."""
        return MappingProxyType(self._sims)

    def sim(self, name: str) -> Simulation:
        """The simulation of the vehicle called ``name`` (``"auv1"``).

        Raises:
            KeyError: no vehicle of the fleet has that name (the message lists them).
        """
        sim = self._sims.get(f"/{name}")
        if sim is None:
            names = ", ".join(v.name for v in self.vehicles)
            raise KeyError(f"no vehicle {name!r} in the fleet (vehicles: {names})")
        return sim

    # --- the link and the clock (the FleetEndpoint) --------------------------------------

    @property
    def t_s(self) -> float:
        """Simulated time (s), every vehicle's."""
        return next(iter(self._sims.values())).t_s

    def submit_frame(self, data: bytes) -> None:
        """One frame goes on the air now: every vehicle's receiver gets it through its own
        channel (its own errors and range; :meth:`sim.simulation.Simulation.submit_frame`),
        and every agent it reaches acknowledges it. A message of no frame's length is
        acknowledged ``malformed`` by each vehicle, as by a single one."""
        self.transmissions += 1
        for sim in self._sims.values():
            sim.submit_frame(data)

    def advance(self, dt_s: float) -> None:
        """Advance every vehicle by ``dt_s`` simulated seconds (whole physics steps; the rest
        carries over, as :meth:`sim.simulation.Simulation.advance`)."""
        if not dt_s >= 0.0:
            raise ValueError(f"dt_s must be >= 0 seconds, got {dt_s!r}")
        self.run_until(self._clock_s + dt_s)

    def run_until(self, t_s: float) -> None:
        """Step every vehicle until simulated time reaches ``t_s`` (see the module doc)."""
        self._clock_s = max(self._clock_s, t_s)
        for sim in self._sims.values():
            sim.run_until(self._clock_s)

    # --- what every vehicle shares -------------------------------------------------------

    @property
    def channel_config(self) -> ChannelConfig:
        """The shared link's settings (every vehicle's receiver has them)."""
        return self.config.channel

    def set_channel_config(self, channel: ChannelConfig) -> None:
        """Change the shared link from the next frame on, for every vehicle (each channel's
        random stream continues)."""
        for sim in self._sims.values():
            sim.channel.set_config(channel)
        self.config = replace(self.config, channel=channel)

    def set_current_config(self, current: CurrentConfig) -> None:
        """Change the water current every vehicle is in."""
        for sim in self._sims.values():
            sim.current.set_config(current)
        self.config = replace(self.config, current=current)
