"""The core's values in and out: an odometry sample, a setpoint, where outputs go, and the
PoseStamped dicts of the pose and the setpoint (:mod:`nemesys_vehicle.core` uses them; the
node converts them to and from ROS messages in :mod:`nemesys_vehicle.convert`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import astuple, dataclass, field
from typing import Any

from codec import FRAME_BITS, FRAME_BYTES, GUARD_BITS
from nemesys_vehicle.frames import EnuPose, MapOrigin, NedPose, map_to_odometry, yaw_deg_of
from nemesys_vehicle.frames import yaw_quaternion as yaw_q
from vehicle_contract.endpoint import Pose
from vehicle_contract.messages import pose_stamped_msg, stamp

JsonDict = dict[str, Any]


@dataclass(frozen=True, slots=True)
class Odometry:
    """One navigation sample as ``nav_msgs/msg/Odometry`` carries it (REP-103: ENU world,
    FLU body), with its origin wherever the navigation started, at the water surface
    (depth = ``-z_up_m``). ``t_s``: when it reached the node (ROS time)."""

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

    def enu(self) -> EnuPose:
        """Position and yaw in the odometry's own frame (``map_ned`` is the georef's)."""
        return EnuPose(
            self.x_east_m,
            self.y_north_m,
            self.z_up_m,
            yaw_deg_of((self.qx, self.qy, self.qz, self.qw)),
        )

    @property
    def depth_m(self) -> float:
        return -self.z_up_m + 0.0


@dataclass(frozen=True, slots=True)
class Setpoint:
    """What guidance asks for at ``t_s``: the point it aims at (``map_ned``), the course to
    it, the speed, and whether the vertical thrusters are on (False: afloat at the surface)."""

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
    datum: Callable[[JsonDict], None] = _ignore


@dataclass(slots=True)
class Recorder:
    """Sinks that keep everything (tests, diagnostics)."""

    acks: list[JsonDict] = field(default_factory=list)
    statuses: list[JsonDict] = field(default_factory=list)
    poses: list[JsonDict] = field(default_factory=list)
    setpoints: list[JsonDict] = field(default_factory=list)
    datums: list[JsonDict] = field(default_factory=list)

    def sinks(self) -> Sinks:
        return Sinks(
            self.acks.append,
            self.statuses.append,
            self.poses.append,
            self.setpoints.append,
            self.datums.append,
        )


def pose_msg(t_s: float, ned: NedPose) -> JsonDict:
    """``geometry_msgs/PoseStamped`` in ``map_ned`` (position NED, heading yaw quaternion):
    the contract's message, built as the simulator's (no roll)."""
    pose = Pose(t_s, ned.x_north_m, ned.y_east_m, ned.z_down_m, 0.0, ned.heading_deg)
    return pose_stamped_msg(pose)


def setpoint_msg(
    setpoint: Setpoint, frame: str, enu_frame_id: str, origin: MapOrigin | None = None
) -> JsonDict:
    """The setpoint as a ``geometry_msgs/PoseStamped``: position = the point guidance aims at,
    orientation = the course to it as a yaw quaternion, z = the depth reference (NED, in
    ``map_ned``) or its negative (ENU, in ``enu_frame_id``: the odometry's frame, whose place
    in ``map_ned`` is ``origin``)."""
    ned = NedPose(setpoint.x_north_m, setpoint.y_east_m, setpoint.depth_m, setpoint.course_deg)
    if frame == "ned":
        return pose_msg(setpoint.t_s, ned)
    enu = map_to_odometry(ned, origin or MapOrigin())
    qx, qy, qz, qw = yaw_q(enu.yaw_deg)
    return {
        "header": {"stamp": stamp(setpoint.t_s), "frame_id": enu_frame_id},
        "pose": {
            "position": {"x": enu.x_east_m, "y": enu.y_north_m, "z": enu.z_up_m},
            "orientation": {"x": qx, "y": qy, "z": qz, "w": qw},
        },
    }


def frame_bits(data: bytes, addressed: bool = False) -> tuple[int | None, int]:
    """A frame message's bits for the agent: ``(bits, n_bits)``; ``None`` when it is not
    ``FRAME_BYTES`` long (acknowledged as malformed), as the simulator does. ``addressed``
    (a vehicle with an address): 14 bytes are a 108-bit addressed frame too."""
    if addressed and len(data) == FRAME_BYTES + 1:
        from codec import ADDRESSED_FRAME_BITS

        return int.from_bytes(data, "big") >> GUARD_BITS, ADDRESSED_FRAME_BITS
    if len(data) != FRAME_BYTES:
        return None, 8 * len(data)
    return int.from_bytes(data, "big") >> GUARD_BITS, FRAME_BITS
