"""The contract's pose and status messages, written once: built by the simulator's bridge and
the reference ROS 2 node, read by the console and ``nemesys vehicle-check``.

* The time base (:data:`vehicle_contract.contract.TIME_BASE`): :func:`stamp` writes a ROS time
  in seconds as ``builtin_interfaces/Time``; :func:`pose_from_message` reads it back.
* The pose (``geometry_msgs/PoseStamped`` in ``map_ned``): :func:`pose_stamped_msg` builds it
  with the heading (and roll) as :func:`quaternion_from_roll_yaw`; :func:`pose_from_message`
  reads it as flat numbers (:data:`POSE_KEYS`), ``None`` where the vehicle sent none.
* The acknowledgement and status (the JSON ``data`` of a ``std_msgs/String``):
  :func:`to_json` writes strict JSON (NaN and infinities as ``null``, as rosbridge sends
  them); :func:`status_from_message` reads the numbers the console uses (:data:`STATUS_NUMBERS`).

No I/O, and nothing of rosbridge: a vehicle's node imports this without the station's code.
NED metres (x north, y east, z down), degrees, seconds.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from typing import Any, Final

from vehicle_contract.contract import POSE_FRAME_ID
from vehicle_contract.endpoint import Pose

#: Numbers of a pose, each ``None`` when the vehicle sent none (null, NaN, missing).
POSE_KEYS: Final = ("t_s", "x_m", "y_m", "z_m", "heading_deg", "roll_deg")
#: Numbers of the vehicle's status the console reads.
STATUS_NUMBERS: Final = ("t_s", "depth_m", "heading_deg", "speed_mps", "battery_pct", "x_m", "y_m")

#: A pose as read from a message: :data:`POSE_KEYS` -> a finite number or ``None``.
PoseFields = dict[str, float | None]
#: A message as JSON (a ROS message's fields by name).
JsonDict = dict[str, Any]

# --- writing --------------------------------------------------------------------------------


def stamp(t_s: float) -> JsonDict:
    """``builtin_interfaces/Time`` of a time in seconds: ``{"sec": int, "nanosec": int}``.

    ``nanosec`` is in 0..999_999_999 (``sec`` is floored, so negative times stay valid).
    Non-finite times give 0.
    """
    if not math.isfinite(t_s):
        return {"sec": 0, "nanosec": 0}
    sec = math.floor(t_s)
    nanosec = round((t_s - sec) * 1e9)
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return {"sec": int(sec), "nanosec": int(nanosec)}


def quaternion_from_roll_yaw(roll_deg: float, yaw_deg: float) -> tuple[float, float, float, float]:
    """Unit quaternion ``(x, y, z, w)`` for roll then yaw (pitch 0), NED body axes.

    ZYX (yaw-pitch-roll) convention: ``q = q_z(yaw) * q_x(roll)``. In NED, yaw is the heading
    (0 = north = +x, 90 deg = east = +y, rotating about +z down) and a positive roll puts the
    starboard side (+y body) down. Angles in degrees.

    ``q`` and ``-q`` are the same rotation; the one with ``w >= 0`` is returned (no ``-0.0``),
    so a heading of 359 deg and one of -1 deg give the same quaternion.
    """
    half_roll = math.radians(roll_deg) / 2.0
    half_yaw = math.radians(yaw_deg) / 2.0
    cr, sr = math.cos(half_roll), math.sin(half_roll)
    cy, sy = math.cos(half_yaw), math.sin(half_yaw)
    q = (sr * cy, sr * sy, cr * sy, cr * cy)
    sign = -1.0 if q[3] < 0.0 else 1.0
    x, y, z, w = (sign * c + 0.0 for c in q)
    return (x, y, z, w)


def pose_stamped_msg(pose: Pose, frame_id: str = POSE_FRAME_ID) -> JsonDict:
    """``geometry_msgs/PoseStamped`` of a vehicle pose: NED metres, stamp from ``pose.t_s``."""
    qx, qy, qz, qw = quaternion_from_roll_yaw(pose.roll_deg, pose.heading_deg)
    return {
        "header": {"stamp": stamp(pose.t_s), "frame_id": frame_id},
        "pose": {
            "position": {"x": float(pose.x_m), "y": float(pose.y_m), "z": float(pose.z_m)},
            "orientation": {"x": qx, "y": qy, "z": qz, "w": qw},
        },
    }


def _finite(value: Any) -> Any:
    """A copy of a JSON-ready value with NaN and infinities replaced by ``None``."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {key: _finite(item) for key, item in value.items()}
    if isinstance(value, list):
        return [_finite(item) for item in value]
    return value


def _json_default(value: Any) -> Any:
    """JSON for values ``json`` does not know: numpy scalars and arrays, sets, mappings."""
    tolist = getattr(value, "tolist", None)
    if callable(tolist):
        return tolist()
    if isinstance(value, set | frozenset):
        return sorted(value, key=repr)
    if isinstance(value, Mapping):
        return dict(value)
    raise TypeError(f"{type(value).__name__} is not JSON serializable")


def strict_json(value: Any, separators: tuple[str, str] = (",", ":")) -> str:
    """Strictly valid JSON of a value, with ``separators`` (``json.dumps``'s).

    NaN and infinities become ``null`` (as rosbridge sends them; browsers' ``JSON.parse``
    rejects ``NaN``); numpy scalars and arrays become numbers and lists. Raises ``TypeError``
    for other objects.
    """
    try:
        return json.dumps(value, separators=separators, allow_nan=False, default=_json_default)
    except ValueError:
        # Out-of-range floats somewhere: round-trip through lenient JSON, then clean them.
        plain = json.loads(json.dumps(value, default=_json_default))
        return json.dumps(_finite(plain), separators=separators, allow_nan=False)


def to_json(value: Any) -> str:
    """Compact strict JSON (:func:`strict_json`): the ``data`` of an acknowledgement or status
    ``std_msgs/String``."""
    return strict_json(value)


# --- reading --------------------------------------------------------------------------------


def number(value: object) -> float | None:
    """A finite number, or ``None``: rosbridge_server sends NaN and infinity as ``null``, and
    a field may be missing or of another type. Booleans are not numbers."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    out = float(value)
    return out if math.isfinite(out) else None


def _dict(value: object) -> dict[str, Any]:
    return value if isinstance(value, dict) else {}


def heading_roll_from_quaternion(q: dict[str, Any]) -> tuple[float | None, float | None]:
    """(heading_deg in [0, 360), roll_deg) from a NED body quaternion with pitch 0; both
    ``None`` when a component is not a number."""
    x, y, z, w = (number(q.get(k)) for k in ("x", "y", "z", "w"))
    if x is None or y is None or z is None or w is None:
        return None, None
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    return math.degrees(yaw) % 360.0, math.degrees(roll)


def pose_from_message(msg: dict[str, Any]) -> PoseFields:
    """A PoseStamped message (NED, ``map_ned``) as a flat pose dict; a number the vehicle
    did not send (null, NaN, missing) is ``None``. ``t_s`` is the vehicle's ROS time."""
    pose = _dict(msg.get("pose"))
    pos = _dict(pose.get("position"))
    heading, roll = heading_roll_from_quaternion(_dict(pose.get("orientation")))
    time_msg = _dict(_dict(msg.get("header")).get("stamp"))
    sec, nanosec = number(time_msg.get("sec")), number(time_msg.get("nanosec"))
    return {
        "t_s": None if sec is None else sec + (nanosec or 0.0) * 1e-9,
        "x_m": number(pos.get("x")),
        "y_m": number(pos.get("y")),
        "z_m": number(pos.get("z")),
        "heading_deg": heading,
        "roll_deg": roll,
    }


def status_from_message(msg: dict[str, Any]) -> tuple[dict[str, Any], int]:
    """The vehicle's status with every number it should hold (:data:`STATUS_NUMBERS`) made a
    finite float or ``None``, and how many were unknown (null, NaN or missing)."""
    status = dict(msg)
    unknown = 0
    for key in STATUS_NUMBERS:
        status[key] = number(msg.get(key))
        unknown += status[key] is None
    return status, unknown


def unknown_count(pose: PoseFields) -> int:
    """How many of a pose's numbers are unknown."""
    return sum(pose[k] is None for k in POSE_KEYS)


def position_known(pose: PoseFields | None) -> bool:
    """Whether a pose holds its whole position (x, y and z)."""
    return pose is not None and all(pose[k] is not None for k in ("x_m", "y_m", "z_m"))
