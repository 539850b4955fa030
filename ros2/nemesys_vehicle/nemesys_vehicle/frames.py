"""Frame conventions: ROS (REP-103) on one side, the NemeSys contract on the other.

ROS odometry (``nav_msgs/msg/Odometry``) is ENU: world x east, y north, z up, with an FLU body
(x forward, y left, z up), and yaw measured from east, counter-clockwise, about +z up. The
contract (``vehicle_contract.contract``: frame ``map_ned``) and the planner are NED: x north,
y east,
z down (depth), with an FRD body, and the heading measured from north, clockwise.

Each direction is ONE function: :func:`enu_to_ned` and :func:`ned_to_enu` (position and
heading together, the axes only), kept in :mod:`vehicle_contract.frames` (the console's dive
exports convert with the same function) and re-exported here. The odometry's ENU frame has its
origin wherever the navigation started, and maybe a magnetic north: :func:`odometry_to_map` is
the one edge from it to the contract's ``map_ned`` about the datum (the axes, then the
declination, then the origin's offset, :class:`MapOrigin`), :func:`map_to_odometry` its inverse
(setpoints in the odometry's frame). The quaternion helpers read the yaw out of an orientation
and build the yaw-only quaternion the contract publishes; :func:`quaternion_enu_to_ned` converts
a full attitude (used to cross-check the yaw path in the tests). Angles in degrees.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from vehicle_contract.frames import EnuPose, NedPose, enu_to_ned, ned_to_enu
from vehicle_contract.messages import quaternion_from_roll_yaw

__all__ = [
    "EnuPose",
    "MapOrigin",
    "NedPose",
    "Quaternion",
    "enu_to_ned",
    "map_to_odometry",
    "ned_to_enu",
    "odometry_to_map",
    "quaternion_enu_to_ned",
    "quaternion_product",
    "yaw_deg_of",
    "yaw_quaternion",
]

#: A quaternion ``(x, y, z, w)``.
Quaternion = tuple[float, float, float, float]

_HALF_SQRT2 = math.sqrt(0.5)
#: ENU -> NED world axes: 180 degrees about (1, 1, 0) / sqrt(2) (swaps x and y, negates z).
_Q_ENU_TO_NED: Quaternion = (_HALF_SQRT2, _HALF_SQRT2, 0.0, 0.0)
#: FRD -> FLU body axes: 180 degrees about x (negates y and z).
_Q_FRD_TO_FLU: Quaternion = (1.0, 0.0, 0.0, 0.0)


class MapOrigin(NamedTuple):
    """Where the odometry's frame sits in ``map_ned``: its origin (m north and east of the
    datum) and the angle from true north to its own north (+y ENU), clockwise (deg): the
    magnetic declination for a magnetic frame, 0 for a true-north one (REP-103)."""

    north_m: float = 0.0
    east_m: float = 0.0
    declination_deg: float = 0.0


def odometry_to_map(pose: EnuPose, origin: MapOrigin) -> NedPose:
    """An odometry pose (ENU about where navigation started) in ``map_ned`` about the datum:
    :func:`enu_to_ned`, turned by the declination (its north -> true north), plus the origin.
    Depth is unchanged (the odometry's origin is at the water surface)."""
    ned = enu_to_ned(pose)
    d = math.radians(origin.declination_deg)
    cos_d, sin_d = math.cos(d), math.sin(d)
    return NedPose(
        ned.x_north_m * cos_d - ned.y_east_m * sin_d + origin.north_m + 0.0,
        ned.x_north_m * sin_d + ned.y_east_m * cos_d + origin.east_m + 0.0,
        ned.z_down_m,
        (ned.heading_deg + origin.declination_deg) % 360.0,
    )


def map_to_odometry(pose: NedPose, origin: MapOrigin) -> EnuPose:
    """The inverse of :func:`odometry_to_map`: a ``map_ned`` pose in the odometry's ENU."""
    north_m, east_m = pose.x_north_m - origin.north_m, pose.y_east_m - origin.east_m
    d = math.radians(origin.declination_deg)
    cos_d, sin_d = math.cos(d), math.sin(d)
    return ned_to_enu(
        NedPose(
            north_m * cos_d + east_m * sin_d,
            -north_m * sin_d + east_m * cos_d,
            pose.z_down_m,
            (pose.heading_deg - origin.declination_deg) % 360.0,
        )
    )


def yaw_deg_of(q: Quaternion) -> float:
    """The yaw (ZYX convention, about the frame's z axis) of an orientation, in [-180, 180].

    Scale-invariant, so a quaternion that is not quite unit still gives the right angle. In an
    ENU frame it is the ENU yaw; in a NED frame, the heading.
    """
    x, y, z, w = q
    return math.degrees(math.atan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z))


def yaw_quaternion(yaw_deg: float) -> Quaternion:
    """A rotation of ``yaw_deg`` about the frame's z axis (roll and pitch 0), ``w >= 0``.

    In ``map_ned`` this is the contract's heading quaternion (the simulator's own builder).
    """
    return quaternion_from_roll_yaw(0.0, yaw_deg)


def quaternion_product(a: Quaternion, b: Quaternion) -> Quaternion:
    """Hamilton product ``a * b`` of ``(x, y, z, w)`` quaternions."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def quaternion_enu_to_ned(q: Quaternion) -> Quaternion:
    """An ENU/FLU attitude (body FLU -> world ENU) as NED/FRD (body FRD -> world NED),
    ``w >= 0``."""
    out = quaternion_product(quaternion_product(_Q_ENU_TO_NED, q), _Q_FRD_TO_FLU)
    sign = -1.0 if out[3] < 0.0 else 1.0
    x, y, z, w = (sign * c + 0.0 for c in out)
    return (x, y, z, w)
