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

from nemesys_vehicle.geo import check_lat_lon
from onboard.guidance import GuidanceConfig
from planner import CircleFence, Limits
from vehicle_contract.codes import MAX_ADDRESS
from vehicle_contract.names import check_namespace

#: Where frames come from: the contract's frame topic, or a serial ME receiver.
FRAME_INPUTS: Final = ("topic", "serial")
#: Frames the setpoint is published in (see README: "Setpoints").
SETPOINT_FRAMES: Final = ("enu", "ned")
#: What the vehicle does when its navigation goes stale (README: "Navigation health").
NAV_FAULT_ACTIONS: Final = ("surface", "hold")
#: Where the datum comes from (README: "Datum").
DATUM_SOURCES: Final = ("navsatfix", "parameters")


@dataclass(frozen=True, slots=True)
class VehicleConfig:
    """The node's settings. Units in the names; rates in Hz."""

    #: The contract topics go under ``/<vehicle_namespace>/nemesys/...`` ("": ``/nemesys/...``).
    vehicle_namespace: str = ""
    #: This vehicle's address in a fleet sharing one ME link, 1-15 (docs/protocol.md,
    #: "Addressing"): it then takes frames addressed to it or to all, and of unaddressed
    #: frames only surface. 0: none, the single-vehicle frames only (as before addresses).
    vehicle_address: int = 0
    #: "topic": frames from ``/nemesys/frame``; "serial": a raw ME receiver stream.
    frame_input: str = "topic"
    #: Anything ``serial.serial_for_url`` opens: ``/dev/ttyUSB0``, ``socket://host:port``.
    serial_url: str = ""
    serial_baud: int = 115_200
    #: How often the serial receiver is polled (non-blocking reads).
    serial_poll_hz: float = 50.0
    #: ``nav_msgs/msg/Odometry`` in, REP-103 (ENU world, FLU body), origin at the surface.
    odometry_topic: str = "/odom"
    #: Navigation older than this (s since the last odometry arrived) is stale.
    nav_timeout_s: float = 2.0
    #: With stale navigation: "surface" or "hold" (depth and position) where last known.
    nav_fault_action: str = "surface"
    #: The datum: "navsatfix" (the first fix at the surface) or "parameters" (below).
    datum_source: str = "navsatfix"
    datum_lat_deg: float = 0.0
    datum_lon_deg: float = 0.0
    #: datum_source "parameters" only: True: navigation starts at the datum (no fix needed);
    #: False: the first fix at the surface places the odometry's origin.
    odometry_origin_at_datum: bool = False
    #: ``sensor_msgs/msg/NavSatFix`` in (a GPS, used at the surface only).
    navsatfix_topic: str = "/fix"
    #: A fix counts as "at the surface" when the odometry's depth is at most this (m).
    fix_max_depth_m: float = 0.5
    #: The angle from true north to the odometry's north (+y), clockwise (deg): 0 for a
    #: true-north ENU frame (REP-103), the local declination for a magnetic one.
    magnetic_declination_deg: float = 0.0
    #: ``sensor_msgs/msg/BatteryState`` in (its ``percentage``, 0..1).
    battery_topic: str = "/battery_state"
    #: ``geometry_msgs/msg/PoseStamped`` out: the point guidance aims at. A name without a
    #: leading "/" goes under the vehicle namespace (as every topic parameter's).
    setpoint_topic: str = "nemesys/setpoint"
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
        self._check_navigation()
        self.limits()  # the planner's own checks (positive, within the rated depth)

    def _check_navigation(self) -> None:
        check_namespace(self.vehicle_namespace)  # ValueError naming what is allowed
        if type(self.vehicle_address) is not int or not 0 <= self.vehicle_address <= MAX_ADDRESS:
            raise ValueError(
                f"vehicle_address must be 0 (none: single-vehicle frames only) or this "
                f"vehicle's address in a fleet, 1 to {MAX_ADDRESS}; got {self.vehicle_address!r}"
            )
        if not (math.isfinite(self.nav_timeout_s) and self.nav_timeout_s > 0):
            raise ValueError(f"nav_timeout_s must be a positive number, got {self.nav_timeout_s!r}")
        if self.nav_fault_action not in NAV_FAULT_ACTIONS:
            raise ValueError(
                f"nav_fault_action must be one of {NAV_FAULT_ACTIONS}, got "
                f"{self.nav_fault_action!r}"
            )
        if self.datum_source not in DATUM_SOURCES:
            raise ValueError(
                f"datum_source must be one of {DATUM_SOURCES}, got {self.datum_source!r}"
            )
        check_lat_lon(self.datum_lat_deg, self.datum_lon_deg)
        if self.odometry_origin_at_datum and self.datum_source != "parameters":
            raise ValueError(
                "odometry_origin_at_datum needs datum_source 'parameters' (with 'navsatfix' "
                "the datum is where the vehicle was at its first fix)"
            )
        if not (math.isfinite(self.fix_max_depth_m) and self.fix_max_depth_m >= 0):
            raise ValueError(f"fix_max_depth_m must be >= 0, got {self.fix_max_depth_m!r}")
        if not (
            math.isfinite(self.magnetic_declination_deg)
            and -180.0 <= self.magnetic_declination_deg <= 180.0
        ):
            raise ValueError(
                "magnetic_declination_deg must be in [-180, 180], got "
                f"{self.magnetic_declination_deg!r}"
            )
        for name in ("odometry_topic", "navsatfix_topic", "battery_topic", "setpoint_topic"):
            if not getattr(self, name).strip("/"):
                raise ValueError(f"{name} must name a topic, got {getattr(self, name)!r}")

    # --- what the parts are built from ---------------------------------------------------

    @property
    def address(self) -> int | None:
        """The agent's address: ``None`` when ``vehicle_address`` is 0 (no fleet)."""
        return self.vehicle_address or None

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

    def resolve(self, name: str) -> str:
        """A topic parameter's absolute name: one without a leading "/" goes under the
        vehicle namespace (``nemesys/setpoint`` -> ``/auv1/nemesys/setpoint``)."""
        if name.startswith("/"):
            return name
        return f"{check_namespace(self.vehicle_namespace)}/{name}"

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
