"""The simulated NemeSys: vehicle, sensors, battery, current, channel, agent and guidance.

One :class:`Simulation` is one vehicle on a fixed physics step (50 Hz by default) with
guidance and the autopilot at 10 Hz. Everything random (channel, current drift, depth
noise) draws from generators seeded from ``SimConfig.seed``, so a run is repeatable; nothing
reads the wall clock except the agent's latency measurements. It implements
:class:`vehicle_contract.endpoint.VehicleEndpoint`, which the rosbridge server drives.

Frames travel: :meth:`Simulation.submit_frame` -> the emulated ME channel (errors, loss,
range, airtime and delay, in simulated time) -> at arrival, on the next guidance tick, the
onboard agent -> acknowledgement (:meth:`take_missions`) and, when accepted, the new
setpoint in that same tick.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field
from typing import Any

from codec import FRAME_BITS, FRAME_BYTES
from onboard.agent import OnboardAgent, command_json
from onboard.guidance import Guidance, GuidanceConfig, Reference
from planner import Limits, VehicleState
from sim.channel import ChannelConfig, Delivery, MEChannel
from sim.completion import Completion
from sim.control import Autopilot, AutopilotGains
from sim.environment import (
    Battery,
    BatteryConfig,
    Current,
    CurrentConfig,
    DepthSensor,
    DepthSensorConfig,
    thrust_power_w,
)
from sim.model import Vehicle, VehicleParams
from vehicle_contract.codes import Mode
from vehicle_contract.endpoint import Pose


@dataclass(frozen=True, slots=True)
class SimConfig:
    """Everything that defines a run. Positions NED metres, heading degrees."""

    seed: int = 0
    physics_hz: float = 50.0
    guidance_hz: float = 10.0
    start_x_m: float = 0.0
    start_y_m: float = 0.0
    start_z_m: float = 2.0
    start_heading_deg: float = 0.0
    #: Where the surface station's ME transmitter is (the range is measured from here).
    station_x_m: float = 0.0
    station_y_m: float = 0.0
    vehicle: VehicleParams = field(default_factory=VehicleParams)
    gains: AutopilotGains = field(default_factory=AutopilotGains)
    guidance: GuidanceConfig = field(default_factory=GuidanceConfig)
    channel: ChannelConfig = field(default_factory=ChannelConfig)
    current: CurrentConfig = field(default_factory=CurrentConfig)
    depth_sensor: DepthSensorConfig = field(default_factory=DepthSensorConfig)
    battery: BatteryConfig = field(default_factory=BatteryConfig)
    limits: Limits = field(default_factory=Limits)
    #: Hours the battery has already run at nominal load (0: full; ~7.4 h: empty).
    battery_start_h: float = 0.0
    #: Samples per second kept in :attr:`Simulation.track` (0: none).
    record_hz: float = 0.0
    #: The vehicle's frame address in a fleet on one ME link, 1-15 (docs/protocol.md,
    #: "Addressing"): its agent then takes 108-bit addressed frames to it or to all, and of
    #: 100-bit frames only surface. ``None`` (no fleet): today's frames only.
    address: int | None = None

    def __post_init__(self) -> None:
        for name in ("physics_hz", "guidance_hz"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number of Hz, got {value!r}")
        ratio = self.physics_hz / self.guidance_hz
        if abs(ratio - round(ratio)) > 1e-9 or ratio < 1:
            raise ValueError(
                f"physics_hz ({self.physics_hz}) must be a whole multiple of guidance_hz "
                f"({self.guidance_hz})"
            )
        if self.start_z_m < 0:
            raise ValueError(f"start_z_m is a depth and must be >= 0, got {self.start_z_m}")


@dataclass(slots=True, eq=False)
class Sample:
    """One recorded instant (for plots and metrics). Compared by identity: a track holds
    thousands, and ``in`` over a track stays a pointer comparison."""

    t_s: float
    x_m: float
    y_m: float
    z_m: float
    depth_ref_m: float
    cross_track_m: float
    mode: str
    #: The active plan's segment guidance tracks.
    segment: int


class Simulation:
    """A simulated NemeSys (see the module doc)."""

    def __init__(self, config: SimConfig | None = None) -> None:
        self.config = config or SimConfig()
        self.reset()

    def reset(self, config: SimConfig | None = None) -> None:
        """Start again from the configured start pose (optionally with a new config)."""
        cfg = self.config = config or self.config
        seed = cfg.seed
        self.vehicle = Vehicle(
            cfg.vehicle, cfg.start_x_m, cfg.start_y_m, cfg.start_z_m, cfg.start_heading_deg
        )
        self.autopilot = Autopilot(cfg.vehicle, cfg.gains)
        self.guidance = Guidance(cfg.guidance)
        self.guidance.hold_here(cfg.start_x_m, cfg.start_y_m, cfg.start_z_m, cfg.start_heading_deg)
        self.agent = OnboardAgent(self.guidance, cfg.limits, cfg.address)
        # A fleet's vehicle also takes the addressed frame's length (the codec's addressed
        # module is loaded only then, as the onboard agent loads it).
        self._addressed = (0, 0)  # (bytes, bits) of the addressed frame, if taken
        if cfg.address is not None:
            from codec import ADDRESSED_FRAME_BITS, ADDRESSED_FRAME_BYTES

            self._addressed = (ADDRESSED_FRAME_BYTES, ADDRESSED_FRAME_BITS)
        #: When the pattern guidance flies was done (:mod:`sim.completion`'s rule).
        self.completion = Completion()
        self.channel = MEChannel(cfg.channel, seed=seed)
        self.current = Current(cfg.current, seed=seed + 1)
        self.sensor = DepthSensor(cfg.depth_sensor, seed=seed + 2)
        self.battery = Battery(cfg.battery, cfg.battery_start_h)
        self.dt_s = 1.0 / cfg.physics_hz
        self._ticks_per_guidance = round(cfg.physics_hz / cfg.guidance_hz)
        self._record_every = round(cfg.physics_hz / cfg.record_hz) if cfg.record_hz > 0 else 0
        self.steps = 0
        self.t_s = 0.0
        self.depth_m = cfg.start_z_m  # the last depth sensor reading
        self.ref = Reference(math.radians(cfg.start_heading_deg), 0.0, cfg.start_z_m)
        # frames in flight, by arrival time then submission order: (arrive_t_s, n, delivery,
        # n_bits); a delivery of None is a message that was not a frame (wrong length)
        self._inbox: list[tuple[float, int, Delivery | None, int]] = []
        self._clock_s = 0.0
        self._heave_n = 0.0
        self._missions: list[dict[str, Any]] = []
        self.acks: list[dict[str, Any]] = []  # every acknowledgement of the run
        self.track: list[Sample] = []
        self.frames_in = 0
        self.frames_lost = 0
        self.last_frame_t_s: float | None = None

    # --- the endpoint contract -----------------------------------------------------------

    def submit_frame(self, data: bytes) -> None:
        """A frame leaves the surface station now; the channel decides what arrives, when.

        A vehicle with an address (``SimConfig.address``) takes the 14-byte addressed frame
        too (108 bits on the air)."""
        self.frames_in += 1
        if len(data) == FRAME_BYTES:
            n_bits = FRAME_BITS
        elif len(data) == self._addressed[0]:
            n_bits = self._addressed[1]
        else:
            # not a frame: acknowledged as malformed on the next tick, nothing transmitted
            heapq.heappush(self._inbox, (self.t_s, self.frames_in, None, 8 * len(data)))
            return
        delivery = self.channel.transmit_bytes(bytes(data), self.t_s, self.distance_m, n_bits)
        if delivery is None:
            self.frames_lost += 1
            return
        heapq.heappush(
            self._inbox, (delivery.arrive_t_s, self.frames_in, delivery, delivery.n_bits)
        )

    def advance(self, dt_s: float) -> None:
        """Run the physics forward by ``dt_s`` seconds: whole steps, the rest carries over to
        the next call (so many small advances add up to the right time)."""
        if not dt_s >= 0.0:
            raise ValueError(f"dt_s must be >= 0 seconds, got {dt_s!r}")
        self.run_until(self._clock_s + dt_s)

    def run_until(self, t_s: float) -> None:
        """Step until simulated time reaches ``t_s`` (to the nearest step)."""
        self._clock_s = max(self._clock_s, t_s)
        while self.t_s + self.dt_s / 2 <= t_s:
            self.step()
        if self._inbox:  # frames that arrived since the last step: no need to wait for one
            self._deliver(t_s)

    def take_missions(self) -> list[dict[str, Any]]:
        out, self._missions = self._missions, []
        return out

    def pose(self) -> Pose:
        v = self.vehicle
        return Pose(self.t_s, v.x, v.y, v.z, v.roll_deg, v.heading_deg)

    @property
    def mode(self) -> Mode:
        return Mode.BATTERY_EMPTY if self.battery.empty else self.guidance.mode

    @property
    def distance_m(self) -> float:
        """Slant range from the station's transmitter (at the surface) to the vehicle (m)."""
        v, c = self.vehicle, self.config
        return math.sqrt((v.x - c.station_x_m) ** 2 + (v.y - c.station_y_m) ** 2 + v.z * v.z)

    def status(self) -> dict[str, Any]:
        v = self.vehicle
        active = self.agent.active
        cfg = self.channel.config
        distance_m = self.distance_m
        status: dict[str, Any] = {
            "t_s": self.t_s,
            "x_m": v.x,
            "y_m": v.y,
            "depth_m": self.depth_m,
            "heading_deg": v.heading_deg,
            "speed_mps": v.speed_mps,
            "battery_pct": self.battery.soc_pct,
            "mode": self.mode.value,
            "pattern": active.pattern if active is not None else None,
            # the active command as the acknowledgements echo it (the contract's status schema)
            "active": command_json(active.command) if active is not None else None,
            "nav_valid": True,  # the simulator always knows where it is
            "frame_input": "topic",
            # what a console that reconnected missed (the contract: the last 30 s of acks)
            "recent_acks": self.agent.recent_acks(self.t_s),
            "link": {
                "frames_in": self.frames_in,
                "frames_lost": self.frames_lost,
                "accepted": self.agent.accepted,
                "rejected": self.agent.rejected,
                "last_frame_t_s": self.last_frame_t_s,
                "distance_m": distance_m,
                "range_m": cfg.range_m,
                "in_range": distance_m <= cfg.range_m,
                "ber": cfg.ber,
            },
        }
        if self.config.address is not None:  # a fleet's vehicle says which it is (contract 2.1)
            status["address"] = self.config.address
        return status

    # --- state for the planner -----------------------------------------------------------

    def state(self) -> VehicleState:
        """The vehicle as its own navigation sees it (depth from the sensor)."""
        v = self.vehicle
        g = self.guidance
        segment = g.segment if g.mode is Mode.RUNNING and g.plan is not None else None
        return VehicleState(v.x, v.y, self.depth_m, v.heading_deg, v.speed_mps, self.t_s, segment)

    # --- the loop ------------------------------------------------------------------------

    def step(self) -> None:
        """One physics step; guidance, the agent and the autopilot run every few steps."""
        v = self.vehicle
        dt = self.dt_s
        if self.steps % self._ticks_per_guidance == 0:
            self._control(dt * self._ticks_per_guidance)
        elif self._inbox:
            self._deliver(self.t_s)
        v.current_n, v.current_e = self.current.step(dt)
        v.step(dt)
        self.battery.step(dt, thrust_power_w(v.thrusts))
        self.steps += 1
        self.t_s = self.steps * dt
        if self._record_every and self.steps % self._record_every == 0:
            self.track.append(
                Sample(
                    self.t_s,
                    v.x,
                    v.y,
                    v.z,
                    self.ref.depth_m,
                    self.guidance.cross_track_m,
                    self.mode.value,
                    self.guidance.segment,
                )
            )

    def _deliver(self, t_s: float) -> Reference | None:
        """Hand the agent every frame that has arrived by ``t_s``; the last accepted frame's
        first setpoint goes to the thrusters at once (the depth loop keeps its last force until
        its next tick)."""
        ref: Reference | None = None
        while self._inbox and self._inbox[0][0] <= t_s + 1e-9:
            arrive_s, _, delivery, n_bits = heapq.heappop(self._inbox)
            self.last_frame_t_s = arrive_s
            ack, new = self.agent.receive(
                delivery.bits if delivery is not None else None, n_bits, self.state()
            )
            if delivery is not None:
                ack["channel_flipped_bits"] = delivery.flipped
            self._missions.append(ack)
            self.acks.append(ack)
            if new is not None:
                ref = new
        if ref is not None:
            self.ref = ref
            self._apply(ref, self._heave_n)
        return ref

    def _control(self, dt: float) -> None:
        v = self.vehicle
        self.depth_m = self.sensor.read(v.z, self.t_s)
        ref = self._deliver(self.t_s) or self.guidance.update(v.x, v.y, self.depth_m, self.t_s)
        self.ref = ref
        self.completion.update(self.guidance, self.t_s)
        heave = self.autopilot.depth_force(ref.depth_m, self.depth_m, dt) if ref.vertical else 0.0
        self._heave_n = heave
        self._apply(ref, heave)

    def _apply(self, ref: Reference, heave_n: float) -> None:
        v = self.vehicle
        if self.battery.empty:
            v.command(0.0, 0.0, 0.0, 0.0)
            return
        t1, t2, t3, t4 = self.autopilot.thrusts(
            ref.course_rad,
            ref.speed_mps,
            heave_n,
            v.psi,
            v.r,
            v.u,
            v.phi,
            v.p,
        )
        if not ref.vertical:
            t3 = t4 = 0.0
        v.command(t1, t2, t3, t4)
