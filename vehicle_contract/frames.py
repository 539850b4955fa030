"""The one NED <-> ENU edge: the contract's ``map_ned`` on one side, ROS (REP-103) on the other.

The contract and the planner are NED: x north, y east, z down (depth), the heading from
north, clockwise. ROS world frames are ENU: x east, y north, z up, the yaw from east,
counter-clockwise about +z up. Each direction is ONE function, position and heading together
(the axes only): :func:`ned_to_enu` where the console hands a pose to ROS tools (the dive
exports), :func:`enu_to_ned` where the reference node reads its odometry
(``nemesys_vehicle.frames``, which adds the odometry's own origin and declination). Angles in
degrees.
"""

from __future__ import annotations

from typing import NamedTuple


class EnuPose(NamedTuple):
    """A position and yaw in a ROS world frame (REP-103)."""

    x_east_m: float
    y_north_m: float
    z_up_m: float
    #: From east, counter-clockwise (about +z up), in [-180, 180).
    yaw_deg: float


class NedPose(NamedTuple):
    """A position and heading in the contract's ``map_ned`` frame."""

    x_north_m: float
    y_east_m: float
    #: Depth when the ENU origin is at the water surface.
    z_down_m: float
    #: From north, clockwise, in [0, 360).
    heading_deg: float


def enu_to_ned(pose: EnuPose) -> NedPose:
    """ENU (x east, y north, z up, yaw from east CCW) -> NED (x north, y east, z down, heading
    from north CW): ``heading_deg = (90 - yaw_deg) mod 360``."""
    return NedPose(
        pose.y_north_m + 0.0,
        pose.x_east_m + 0.0,
        -pose.z_up_m + 0.0,  # + 0.0: no -0.0 in the JSON
        (90.0 - pose.yaw_deg) % 360.0,
    )


def ned_to_enu(pose: NedPose) -> EnuPose:
    """The inverse of :func:`enu_to_ned`: ``yaw_deg = 90 - heading_deg``, wrapped to
    [-180, 180)."""
    return EnuPose(
        pose.y_east_m + 0.0,
        pose.x_north_m + 0.0,
        -pose.z_down_m + 0.0,
        (90.0 - pose.heading_deg + 180.0) % 360.0 - 180.0,
    )
