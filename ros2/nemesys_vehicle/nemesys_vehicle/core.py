"""The vehicle node's logic, free of ROS: frames in, contract messages out.

:class:`VehicleCore` wraps the onboard agent the simulator runs (:mod:`onboard.agent`:
decode -> validate -> replan -> guidance switch -> one acknowledgement per frame) and the same
guidance (:mod:`onboard.guidance`). Inputs:

* :meth:`VehicleCore.on_frame`: one frame's bytes (``/nemesys/frame``, a UInt8MultiArray's data);
* :meth:`VehicleCore.on_serial_bytes`: a raw ME receiver stream, any chunking
  (:class:`nemesys_vehicle.stream.FrameStream` finds the frames);
* :meth:`VehicleCore.on_odometry`: the navigation solution (:class:`Odometry`, ENU);
* the clock ticks :meth:`tick_status`, :meth:`tick_pose`, :meth:`tick_guidance`.

Outputs go to :class:`Sinks` (and are returned): acknowledgements and status as JSON-ready
dicts (``/nemesys/mission``, ``/nemesys/status``), the pose and the setpoint as PoseStamped
dicts (``/nemesys/pose`` in ``map_ned``; the setpoint in ENU or NED, see ``setpoint_msg``).
Every time is ROS time in seconds, passed in by the caller (the node's clock).

Before the first odometry the vehicle does not know where it is: frames are held (up to the
frame topic's QoS depth) and processed, in order, when it arrives; no pose is published, and
the status says ``null`` for the position, depth, heading and speed. Setpoints are published
only while the agent has an active command: until the first accepted frame the node leaves the
autopilot alone.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import astuple, dataclass, field
from typing import Any, Final

from codec import FRAME_BITS, FRAME_BYTES, GUARD_BITS
from nemesys_vehicle.config import VehicleConfig
from nemesys_vehicle.frames import EnuPose, NedPose, enu_to_ned, ned_to_enu, yaw_deg_of
from nemesys_vehicle.frames import yaw_quaternion as yaw_q
from nemesys_vehicle.stream import FrameStream
from onboard.agent import OnboardAgent, command_json
from onboard.guidance import Guidance, Reference
from planner import VehicleState
from vehicle_contract.codes import Mode
from vehicle_contract.contract import FRAME_TOPIC, topic
from vehicle_contract.endpoint import Pose
from vehicle_contract.messages import pose_stamped_msg, stamp

#: Frames held while waiting for the first odometry (the frame topic's history depth).
PENDING_FRAMES: Final = topic(FRAME_TOPIC).qos.depth

JsonDict = dict[str, Any]


@dataclass(frozen=True, slots=True)
class Odometry:
    """One navigation sample as ``nav_msgs/msg/Odometry`` carries it (REP-103: ENU world,
    FLU body). The world origin must be at the water surface (depth = ``-z_up_m``)."""

    t_s: float
    x_east_m: float
    y_north_m: float
    z_up_m: float
    qx: float
    qy: float
    qz: float
    qw: float
    #: Speed through the water (the norm of the twist's linear velocity).
    speed_mps: float
    #: The odometry's ``header.frame_id``: the frame of ENU setpoints.
    frame_id: str = "odom"

    def is_finite(self) -> bool:
        return all(math.isfinite(v) for v in astuple(self)[:-1])

    def ned(self) -> NedPose:
        enu = EnuPose(
            self.x_east_m,
            self.y_north_m,
            self.z_up_m,
            yaw_deg_of((self.qx, self.qy, self.qz, self.qw)),
        )
        return enu_to_ned(enu)


@dataclass(frozen=True, slots=True)
class Setpoint:
    """What guidance asks for at ``t_s``: the point it aims at (NED), the course to it, the
    speed, and whether the vertical thrusters are on (False: afloat at the surface)."""

    t_s: float
    x_north_m: float
    y_east_m: float
    depth_m: float
    course_deg: float
    speed_mps: float
    vertical: bool
    mode: str


def _ignore(_: JsonDict) -> None:
    return None


@dataclass(slots=True)
class Sinks:
    """Where the core's outputs go (the node publishes them; tests record them)."""

    ack: Callable[[JsonDict], None] = _ignore
    status: Callable[[JsonDict], None] = _ignore
    pose: Callable[[JsonDict], None] = _ignore
    setpoint: Callable[[JsonDict], None] = _ignore


@dataclass(slots=True)
class Recorder:
    """Sinks that keep everything (tests, diagnostics)."""

    acks: list[JsonDict] = field(default_factory=list)
    statuses: list[JsonDict] = field(default_factory=list)
    poses: list[JsonDict] = field(default_factory=list)
    setpoints: list[JsonDict] = field(default_factory=list)

    def sinks(self) -> Sinks:
        return Sinks(
            self.acks.append, self.statuses.append, self.poses.append, self.setpoints.append
        )


def pose_msg(t_s: float, ned: NedPose) -> JsonDict:
    """``geometry_msgs/PoseStamped`` in ``map_ned`` (position NED, heading yaw quaternion):
    the contract's message, built as the simulator's (no roll)."""
    pose = Pose(t_s, ned.x_north_m, ned.y_east_m, ned.z_down_m, 0.0, ned.heading_deg)
    return pose_stamped_msg(pose)


def setpoint_msg(setpoint: Setpoint, frame: str, enu_frame_id: str) -> JsonDict:
    """The setpoint as a ``geometry_msgs/PoseStamped``: position = the point guidance aims at,
    orientation = the course to it as a yaw quaternion, z = the depth reference (NED, in
    ``map_ned``) or its negative (ENU, in ``enu_frame_id``: the odometry's frame)."""
    ned = NedPose(setpoint.x_north_m, setpoint.y_east_m, setpoint.depth_m, setpoint.course_deg)
    if frame == "ned":
        return pose_msg(setpoint.t_s, ned)
    enu = ned_to_enu(ned)
    qx, qy, qz, qw = yaw_q(enu.yaw_deg)
    return {
        "header": {"stamp": stamp(setpoint.t_s), "frame_id": enu_frame_id},
        "pose": {
            "position": {"x": enu.x_east_m, "y": enu.y_north_m, "z": enu.z_up_m},
            "orientation": {"x": qx, "y": qy, "z": qz, "w": qw},
        },
    }


def frame_bits(data: bytes) -> tuple[int | None, int]:
    """A frame message's bits for the agent: ``(bits, n_bits)``; ``None`` when it is not
    ``FRAME_BYTES`` long (acknowledged as malformed), as the simulator does."""
    if len(data) != FRAME_BYTES:
        return None, 8 * len(data)
    return int.from_bytes(data, "big") >> GUARD_BITS, FRAME_BITS


class VehicleCore:
    """A NemeSys's onboard logic behind a ROS 2 node (see the module doc)."""

    def __init__(self, config: VehicleConfig | None = None, sinks: Sinks | None = None) -> None:
        self.config = config or VehicleConfig()
        self.sinks = sinks or Sinks()
        self.guidance = Guidance(self.config.guidance_config())
        self.agent = OnboardAgent(self.guidance, self.config.limits())
        self.stream = FrameStream()
        self.odometry: Odometry | None = None
        #: State of charge when the vehicle reports one (None: unknown, ``null`` in status).
        self.battery_pct: float | None = None
        self.frames_in = 0
        self.frames_dropped = 0  # held before the first odometry and pushed out by newer ones
        self.odometry_rejected = 0  # samples with a non-finite value
        self._pending: deque[tuple[bytes, float]] = deque()

    # --- inputs --------------------------------------------------------------------------

    def on_frame(self, data: bytes, t_s: float, receipt_s: float | None = None) -> JsonDict | None:
        """One received frame (13 bytes; any other length is acknowledged as malformed).

        Returns the acknowledgement (also sent to ``sinks.ack``), or None while the frame is
        held for the first odometry. ``receipt_s``: ``time.perf_counter()`` at arrival (the
        agent's decode latency starts there; default now).
        """
        receipt = time.perf_counter() if receipt_s is None else receipt_s
        self.frames_in += 1
        if self.odometry is None:
            if len(self._pending) == PENDING_FRAMES:
                self._pending.popleft()
                self.frames_dropped += 1
            self._pending.append((bytes(data), receipt))
            return None
        return self._process(bytes(data), t_s, receipt)

    def on_serial_bytes(self, data: bytes, t_s: float) -> list[JsonDict]:
        """Bytes from a serial ME receiver (any chunking): one acknowledgement per frame the
        receiver synchronised on, decoded or not (see :mod:`nemesys_vehicle.stream`)."""
        receipt = time.perf_counter()
        acks = []
        for frame in self.stream.feed(data):
            ack = self.on_frame(frame, t_s, receipt)
            if ack is not None:
                acks.append(ack)
        return acks

    def on_odometry(self, odometry: Odometry) -> bool:
        """A navigation sample; False (and ignored) if a value is not finite. The first one
        sets guidance's hold point (idle: station keeping where the vehicle is) and releases
        the frames held until then."""
        if not odometry.is_finite():
            self.odometry_rejected += 1
            return False
        first = self.odometry is None
        self.odometry = odometry
        if first:
            state = self.state(odometry.t_s)
            self.guidance.hold_here(state.x_m, state.y_m, state.z_m, state.heading_deg)
            while self._pending:
                data, receipt = self._pending.popleft()
                self._process(data, odometry.t_s, receipt)
        return True

    def on_battery(self, battery_pct: float | None) -> None:
        """The state of charge in percent, 0..100 (None: unknown).

        Raises:
            ValueError: not a number within 0..100.
        """
        if battery_pct is not None and not 0.0 <= battery_pct <= 100.0:
            raise ValueError(f"battery_pct must be within 0..100, got {battery_pct!r}")
        self.battery_pct = battery_pct

    # --- clock ticks ---------------------------------------------------------------------

    def tick_status(self, t_s: float) -> JsonDict:
        """The status message (contract schema ``status``). Before the first odometry the
        position, depth, heading and speed are unknown: ``null``, as the contract asks."""
        odometry = self.odometry
        ned = odometry.ned() if odometry is not None else None
        active = self.agent.active
        status: JsonDict = {
            "t_s": t_s,
            "x_m": ned.x_north_m if ned is not None else None,
            "y_m": ned.y_east_m if ned is not None else None,
            "depth_m": ned.z_down_m if ned is not None else None,
            "heading_deg": ned.heading_deg if ned is not None else None,
            "speed_mps": odometry.speed_mps if odometry is not None else None,
            "battery_pct": self.battery_pct,
            "mode": self.guidance.mode.value,
            "pattern": active.pattern if active is not None else None,
            "active": command_json(active.command) if active is not None else None,
        }
        self.sinks.status(status)
        return status

    def tick_pose(self, t_s: float) -> JsonDict | None:
        """The pose in ``map_ned`` (None before the first odometry)."""
        if self.odometry is None:
            return None
        msg = pose_msg(t_s, self.odometry.ned())
        self.sinks.pose(msg)
        return msg

    def tick_guidance(self, t_s: float) -> Setpoint | None:
        """One guidance step from the latest odometry; the setpoint (None, and nothing
        published, before the first odometry or the first accepted command)."""
        odometry = self.odometry
        if odometry is None or self.agent.active is None:
            return None
        ned = odometry.ned()
        ref = self.guidance.update(ned.x_north_m, ned.y_east_m, ned.z_down_m, t_s)
        return self._emit_setpoint(ref, ned, t_s)

    # --- internals -----------------------------------------------------------------------

    def state(self, t_s: float) -> VehicleState:
        """The vehicle as the planner sees it (as :meth:`sim.simulation.Simulation.state`).
        Depth is at least 0: a vehicle afloat whose odometry puts it a little above the
        surface is at the surface."""
        odometry = self.odometry
        if odometry is None:
            raise RuntimeError("no odometry yet")
        ned = odometry.ned()
        g = self.guidance
        segment = g.segment if g.mode is Mode.RUNNING and g.plan is not None else None
        return VehicleState(
            ned.x_north_m,
            ned.y_east_m,
            max(0.0, ned.z_down_m),
            ned.heading_deg,
            odometry.speed_mps,
            t_s,
            segment,
        )

    def _process(self, data: bytes, t_s: float, receipt_s: float) -> JsonDict:
        bits, n_bits = frame_bits(data)
        state = self.state(t_s)
        ack, ref = self.agent.receive(bits, n_bits, state, receipt_s)
        self.sinks.ack(ack)
        if ref is not None:  # accepted and replanned: guidance's first new setpoint, now
            ned = NedPose(state.x_m, state.y_m, state.z_m, state.heading_deg)
            self._emit_setpoint(ref, ned, t_s)
        return ack

    def _emit_setpoint(self, ref: Reference, ned: NedPose, t_s: float) -> Setpoint:
        north_m, east_m = self._aim(ref, ned)
        setpoint = Setpoint(
            t_s,
            north_m,
            east_m,
            ref.depth_m,
            math.degrees(ref.course_rad) % 360.0,
            ref.speed_mps,
            ref.vertical,
            self.guidance.mode.value,
        )
        frame_id = self.odometry.frame_id if self.odometry is not None else "odom"
        self.sinks.setpoint(setpoint_msg(setpoint, self.config.setpoint_frame, frame_id))
        return setpoint

    def _aim(self, ref: Reference, ned: NedPose) -> tuple[float, float]:
        """The point guidance aims at (NED). Path following: the line-of-sight point, along
        the commanded course at ``hypot(lookahead, cross-track)`` (exact on a straight
        segment); station keeping (a hover, the path's end while its last depth change is
        flown, after it) and surfacing: the hold point."""
        g = self.guidance
        following = g.mode is Mode.RUNNING and not g.at_end
        if following and g.plan is not None and g.plan.pattern != "hover":
            reach_m = math.hypot(g.config.lookahead_m, g.cross_track_m)
            return (
                ned.x_north_m + reach_m * math.cos(ref.course_rad),
                ned.y_east_m + reach_m * math.sin(ref.course_rad),
            )
        return g.hold[0], g.hold[1]
