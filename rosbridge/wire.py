"""What the rosbridge server sends: message builders, JSON, and fragments.

Builders make the ``msg`` of each NemeSys topic (:func:`pose_stamped_msg`,
:func:`json_string_msg`, :func:`uint8_multiarray_msg`), the server's own topics
(:func:`log_msg`, :func:`connected_clients_msg`) and the envelopes (:func:`publish_message`,
:func:`service_response`); :func:`wire_json` serializes them as the real server does (NaN as
``null``), :func:`to_json` compactly (JSON payloads, the client side), and
:func:`fragments` splits a serialized message into ``fragment`` ops exactly as the real
server's ``Protocol.send`` does.
"""

from __future__ import annotations

import base64
import json
import math
from collections.abc import Mapping
from typing import Any, Final

from rosbridge.convert import time_msg
from rosbridge.errors import FragmentError, JsonObject, MessageId
from vehicle_contract.endpoint import Pose

#: ``header.frame_id`` of every pose: NED world frame (x north, y east, z down), metres.
POSE_FRAME_ID: Final = "map_ned"

#: rcl log levels (``rcl_interfaces/msg/Log``).
LOG_DEBUG: Final = 10
LOG_INFO: Final = 20
LOG_WARN: Final = 30
LOG_ERROR: Final = 40


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


def stamp(t_s: float) -> JsonObject:
    """``builtin_interfaces/Time`` of a time in seconds (see :func:`time_msg`)."""
    return time_msg(t_s)


def pose_stamped_msg(pose: Pose, frame_id: str = POSE_FRAME_ID) -> JsonObject:
    """``geometry_msgs/PoseStamped`` of a vehicle pose: NED metres, stamp from ``pose.t_s``."""
    qx, qy, qz, qw = quaternion_from_roll_yaw(pose.roll_deg, pose.heading_deg)
    return {
        "header": {"stamp": stamp(pose.t_s), "frame_id": frame_id},
        "pose": {
            "position": {"x": float(pose.x_m), "y": float(pose.y_m), "z": float(pose.z_m)},
            "orientation": {"x": qx, "y": qy, "z": qz, "w": qw},
        },
    }


def string_msg(text: str) -> JsonObject:
    """``std_msgs/String``."""
    return {"data": text}


def json_string_msg(value: Any) -> JsonObject:
    """``std_msgs/String`` carrying ``value`` as JSON (:func:`to_json`): missions, status."""
    return string_msg(to_json(value))


def uint8_multiarray_msg(data: bytes) -> JsonObject:
    """``std_msgs/UInt8MultiArray`` as the real server sends it: ``data`` a base64 string,
    the default (empty) layout."""
    return {
        "layout": {"dim": [], "data_offset": 0},
        "data": base64.b64encode(data).decode("ascii"),
    }


def log_msg(
    t_s: float, level: int, name: str, text: str, function: str = "log", line: int = 0
) -> JsonObject:
    """``rcl_interfaces/msg/Log``: one line of a node's log, as ``/rosout`` carries it."""
    return {
        "stamp": stamp(t_s),
        "level": level,
        "name": name,
        "msg": text,
        "file": "protocol.py",
        "function": function,
        "line": line,
    }


def connected_clients_msg(clients: list[tuple[str, float]]) -> JsonObject:
    """``rosbridge_msgs/msg/ConnectedClients`` of ``(ip_address, connection time s)``."""
    return {
        "clients": [
            {"ip_address": address, "connection_time": stamp(t_s)} for address, t_s in clients
        ]
    }


def publish_message(topic: str, msg: Mapping[str, Any]) -> JsonObject:
    """A server -> client ``publish``: roslibpy hands ``msg`` to the topic's callbacks."""
    return {"op": "publish", "topic": topic, "msg": dict(msg)}


def service_response(
    service: str, values: Mapping[str, Any] | str, result: bool, op_id: MessageId = None
) -> JsonObject:
    """A ``service_response``. ``values`` is always present (roslibpy reads it unconditionally);
    on failure it is the error text, as ``rosbridge_server`` sends it."""
    message: JsonObject = {
        "op": "service_response",
        "service": service,
        "values": dict(values) if isinstance(values, Mapping) else values,
        "result": result,
    }
    if op_id is not None:
        message["id"] = op_id
    return message


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


def to_json(message: Any) -> str:
    """Compact, strictly valid JSON of a message.

    NaN and infinities become ``null`` (as the real server sends them; browsers'
    ``JSON.parse`` rejects ``NaN``); numpy scalars and arrays become numbers and lists.
    Raises ``TypeError`` for other objects.
    """
    try:
        return json.dumps(message, separators=(",", ":"), allow_nan=False, default=_json_default)
    except ValueError:
        # Out-of-range floats somewhere: round-trip through lenient JSON, then clean them.
        plain = json.loads(json.dumps(message, default=_json_default))
        return json.dumps(_finite(plain), separators=(",", ":"), allow_nan=False)


def wire_json(message: Any) -> str:
    """A server -> client message serialized as the real server does it: Python's default
    ``json.dumps`` (``", "`` and ``": "`` separators, non-ASCII escaped), NaN as ``null``.
    Fragment boundaries and sizes therefore match the real server's."""
    try:
        return json.dumps(message, allow_nan=False, default=_json_default)
    except ValueError:
        plain = json.loads(json.dumps(message, default=_json_default))
        return json.dumps(_finite(plain), allow_nan=False)


def fragments(text: str, fragment_size: object, op_id: MessageId = None) -> tuple[str, ...]:
    """``text`` as the real server sends it to a client whose fragment size is
    ``fragment_size``: unchanged when it fits (or the size is ``None``), else ``fragment`` ops.

    As the real server (``protocol.py``, ``fragmentation.py``): the serialized text is cut
    every ``fragment_size`` characters; ``id`` is the message's own id or ``0`` (roslibjs
    ignores fragments whose id is falsy); ``num`` counts from 0; ``total`` is
    ``(len - 1) / size + 1`` computed in floating point, so it is a float such as ``3.4``
    (clients floor it). Raises :class:`FragmentError` where the real server's send fails: a
    size that is not a number, zero, negative (it would send nothing) or a float.
    """
    if fragment_size is None:
        return (text,)
    if not isinstance(fragment_size, int | float):  # a boolean counts as 0 or 1, as in Python
        raise FragmentError(
            f"'>' not supported between instances of 'int' and '{type(fragment_size).__name__}'"
        )
    if len(text) <= fragment_size:
        return (text,)
    if isinstance(fragment_size, float):
        raise FragmentError("'float' object cannot be interpreted as an integer")
    if fragment_size <= 0:
        raise FragmentError(f"fragment_size {fragment_size} sends nothing")
    mid = 0 if op_id is None else op_id
    total = (len(text) - 1) / fragment_size + 1
    return tuple(
        wire_json(
            {
                "op": "fragment",
                "id": mid,
                "data": text[start : start + fragment_size],
                "num": num,
                "total": total,
            }
        )
        for num, start in enumerate(range(0, len(text), fragment_size))
    )
