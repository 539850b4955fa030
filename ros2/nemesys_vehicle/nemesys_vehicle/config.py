"""The node's parameters, as one validated record (``config/params.yaml`` lists them all).

Every field is a ROS 2 parameter of the same name and type; the node declares them with these
defaults. ROS 2 parameters are typed by their default: write floats with a decimal point in a
parameter file (``2.0``, not ``2``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields
from typing import Any, Final

from onboard.guidance import GuidanceConfig
from planner import CircleFence, Limits

#: Where frames come from: the contract's frame topic, or a serial ME receiver.
FRAME_INPUTS: Final = ("topic", "serial")
#: Frames the setpoint is published in (see README: "Setpoints").
SETPOINT_FRAMES: Final = ("enu", "ned")


@dataclass(frozen=True, slots=True)
class VehicleConfig:
    """The node's settings. Units in the names; rates in Hz."""

    #: "topic": frames from ``/nemesys/frame``; "serial": a raw ME receiver stream.
    frame_input: str = "topic"
    #: Anything ``serial.serial_for_url`` opens: ``/dev/ttyUSB0``, ``socket://host:port``.
    serial_url: str = ""
    serial_baud: int = 115_200
    #: How often the serial receiver is polled (non-blocking reads).
    serial_poll_hz: float = 50.0
    #: ``nav_msgs/msg/Odometry`` in, REP-103 (ENU world, FLU body), origin at the surface.
    odometry_topic: str = "/odom"
    #: ``geometry_msgs/msg/PoseStamped`` out: the point guidance aims at.
    setpoint_topic: str = "/nemesys/setpoint"
    #: "enu": in the odometry's own frame (REP-103); "ned": in ``map_ned``.
    setpoint_frame: str = "enu"
    status_hz: float = 2.0
    pose_hz: float = 20.0
    #: Guidance (and setpoint) rate, as the simulator's.
    guidance_hz: float = 10.0
    # operational limits (planner.Limits): a plan that breaks one is rejected
    max_depth_m: float = 100.0
    max_speed_mps: float = 1.0
    #: 0: no geofence; else a circle of this radius around (north, east) in map_ned.
    geofence_radius_m: float = 0.0
    geofence_north_m: float = 0.0
    geofence_east_m: float = 0.0
    # guidance (onboard.guidance.GuidanceConfig)
    lookahead_m: float = 1.5
    capture_m: float = 1.0
    settle_m: float = 0.3
    approach_mps: float = 0.2
    approach_gain_per_s: float = 0.3
    surfaced_depth_m: float = 0.05

    def __post_init__(self) -> None:
        if self.frame_input not in FRAME_INPUTS:
            raise ValueError(f"frame_input must be one of {FRAME_INPUTS}, got {self.frame_input!r}")
        if self.setpoint_frame not in SETPOINT_FRAMES:
            raise ValueError(
                f"setpoint_frame must be one of {SETPOINT_FRAMES}, got {self.setpoint_frame!r}"
            )
        if self.frame_input == "serial" and not self.serial_url:
            raise ValueError("frame_input 'serial' needs a serial_url")
        if self.serial_baud <= 0:
            raise ValueError(f"serial_baud must be > 0, got {self.serial_baud}")
        for name in ("serial_poll_hz", "status_hz", "pose_hz", "guidance_hz", "lookahead_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value!r}")
        if not (math.isfinite(self.geofence_radius_m) and self.geofence_radius_m >= 0):
            raise ValueError(f"geofence_radius_m must be >= 0, got {self.geofence_radius_m!r}")
        self.limits()  # the planner's own checks (positive, within the rated depth)

    # --- what the parts are built from ---------------------------------------------------

    def limits(self) -> Limits:
        fence = (
            CircleFence(self.geofence_radius_m, (self.geofence_north_m, self.geofence_east_m))
            if self.geofence_radius_m > 0
            else None
        )
        return Limits(self.max_depth_m, self.max_speed_mps, fence)

    def guidance_config(self) -> GuidanceConfig:
        return GuidanceConfig(
            lookahead_m=self.lookahead_m,
            capture_m=self.capture_m,
            settle_m=self.settle_m,
            approach_mps=self.approach_mps,
            approach_gain_per_s=self.approach_gain_per_s,
            surfaced_depth_m=self.surfaced_depth_m,
        )

    @property
    def serial_poll_period_s(self) -> float:
        return 1.0 / self.serial_poll_hz

    @property
    def status_period_s(self) -> float:
        return 1.0 / self.status_hz

    @property
    def pose_period_s(self) -> float:
        return 1.0 / self.pose_hz

    @property
    def guidance_period_s(self) -> float:
        return 1.0 / self.guidance_hz

    # --- ROS 2 parameters ----------------------------------------------------------------

    @classmethod
    def parameter_names(cls) -> list[str]:
        return [f.name for f in fields(cls)]

    @classmethod
    def parameter_defaults(cls) -> list[tuple[str, Any]]:
        """``(name, default)`` for ``Node.declare_parameters``."""
        return list(asdict(cls()).items())

    @classmethod
    def from_values(cls, values: Mapping[str, Any]) -> VehicleConfig:
        """A config from parameter values by name (unknown names are an error, missing ones
        take the default)."""
        unknown = set(values) - set(cls.parameter_names())
        if unknown:
            raise ValueError(f"unknown parameters: {sorted(unknown)}")
        return cls(**values)
