"""The one edge from the console's NED to Foxglove's scene frame, and its time stamps.

Everything in the console is NED metres from the datum: ``x`` north, ``y`` east, ``z`` down
(depth). Foxglove's 3D panel, like ROS (REP 103/105), draws a right-handed frame with ``+z``
up, so the live view publishes in one frame, :data:`FRAME` (``"map"``): ENU about the same
origin as the vehicle's ``map_ned`` (the datum), ``x`` east, ``y`` north, ``z`` up
(``-depth``). It is the same frame the console's own 3D view draws in
(:mod:`backend.viewer.draw`), so the two views agree; this module does not import viser.

* :func:`enu` for positions;
* :func:`attitude_xyzw` for the vehicle's heading and roll (a quaternion);
* :func:`heading_rad` for :class:`foxglove.messages.LocationFix`'s ``heading`` (radians
  clockwise from north);
* :func:`stamp` for a message's time stamp from nanoseconds on the dive's clock
  (:mod:`backend.foxglove_live.clock`).
"""

from __future__ import annotations

import math
from typing import Final

from foxglove.messages import Point3, Quaternion, Timestamp, Vector3

#: The scene frame of every Foxglove message (ENU about the datum).
FRAME: Final = "map"


def enu(x_m: float, y_m: float, z_m: float) -> tuple[float, float, float]:
    """NED metres (north, east, depth) to the scene frame (east, north, up) = ``(y, x, -z)``
    (``+ 0.0``: a surface point's up is 0.0, not -0.0)."""
    return (float(y_m), float(x_m), -float(z_m) + 0.0)


def vector(x_m: float, y_m: float, z_m: float) -> Vector3:
    """A NED position as the scene frame's :class:`Vector3` (:func:`enu`)."""
    e, n, u = enu(x_m, y_m, z_m)
    return Vector3(x=e, y=n, z=u)


def point(x_m: float, y_m: float, z_m: float) -> Point3:
    """A NED position as the scene frame's :class:`Point3` (:func:`enu`)."""
    e, n, u = enu(x_m, y_m, z_m)
    return Point3(x=e, y=n, z=u)


def attitude_xyzw(heading_deg: float, roll_deg: float = 0.0) -> tuple[float, float, float, float]:
    """The vehicle's attitude as the rotation from its body frame (``+x`` forward, ``+y``
    port, ``+z`` up: ROS's FLU) to the scene frame.

    ``heading_deg`` is clockwise from north (NED yaw): the nose points along ENU
    ``(sin psi, cos psi, 0)``, a yaw of ``90 - psi`` degrees about ``+z``. ``roll_deg`` is
    NED roll, starboard side down positive: the same rotation about the forward axis in FLU
    (port side up), applied before the yaw: ``q = q_yaw(90 deg - psi) * q_roll(phi)``.
    Poses carry no pitch. Returns ``(x, y, z, w)``."""
    yaw = math.radians(90.0 - heading_deg) / 2.0
    roll = math.radians(roll_deg) / 2.0
    cy, sy = math.cos(yaw), math.sin(yaw)
    cr, sr = math.cos(roll), math.sin(roll)
    return (cy * sr, sy * sr, sy * cr, cy * cr)


def attitude(heading_deg: float, roll_deg: float = 0.0) -> Quaternion:
    """:func:`attitude_xyzw` as a :class:`Quaternion`."""
    x, y, z, w = attitude_xyzw(heading_deg, roll_deg)
    return Quaternion(x=x, y=y, z=z, w=w)


def heading_rad(heading_deg: float) -> float:
    """A heading in degrees clockwise from north as LocationFix's: radians clockwise from
    north, in [0, 2 pi)."""
    return math.radians(heading_deg % 360.0)


def stamp(ns: int) -> Timestamp:
    """Nanoseconds on the dive's clock as a message's time stamp."""
    sec, nsec = divmod(max(0, ns), 1_000_000_000)
    return Timestamp(sec, nsec)


__all__ = ["FRAME", "attitude", "attitude_xyzw", "enu", "heading_rad", "point", "stamp", "vector"]
