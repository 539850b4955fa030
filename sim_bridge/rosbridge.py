"""rosbridge v2 protocol for the NemeSys bridge, sans-IO (no sockets, no clocks, no logging).

One :class:`ClientSession` per websocket connection turns each text message the client sends
into an :class:`Outcome`: what to send back to that client (service responses, opt-in status
messages), the frame bytes to hand to the vehicle, and why a message was dropped. The
websocket server (:mod:`sim_bridge.server`) does the IO and the logging.

Parsing is table driven, as in roslibpy: :data:`OP_PARSERS` maps each rosbridge ``op`` to a
parser that validates the JSON object and returns a frozen request record
(:class:`Advertise`, :class:`Publish`, ...). A message that cannot be understood raises a
:class:`BridgeError` subclass, which the session turns into a dropped message.

Builders make the outgoing messages: :func:`publish_message` around :func:`string_msg`,
:func:`json_string_msg`, :func:`pose_stamped_msg` and :func:`uint8_multiarray_msg`,
serialized by :func:`to_json`.

The client side (what the station's transmitter and the console's link send, and how they read
the answers) is :mod:`sim_bridge.rosbridge_client`.

Topics (see ``docs/bridge.md``):

* :data:`FRAME_TOPIC` ``/nemesys/frame``, ``std_msgs/UInt8MultiArray``, console -> vehicle.
* :data:`POSE_TOPIC` ``/nemesys/pose``, ``geometry_msgs/PoseStamped``, vehicle -> console.
* :data:`MISSION_TOPIC` ``/nemesys/mission``, ``std_msgs/String`` (JSON), vehicle -> console.
* :data:`STATUS_TOPIC` ``/nemesys/status``, ``std_msgs/String`` (JSON), vehicle -> console.

Status messages (``{"op": "status", ...}``) are opt-in: a session starts at status level
``"none"`` and only reports after the client sends ``{"op": "set_level", "level": ...}``.
roslibpy 2.1 has no handler for ``status`` (its table maps it to ``None``) and logs an
exception with a traceback for every one it receives, and the ROS 2 ``rosbridge_server``
itself only logs such errors on the server side; see ``docs/bridge.md``.
"""

from __future__ import annotations

import base64
import binascii
import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Final, TypeAlias

from sim_bridge.endpoint import Pose

# ---------------------------------------------------------------------------------------------
# Topics, types, levels
# ---------------------------------------------------------------------------------------------

#: Console -> vehicle: one packed frame (13 bytes: 100 bits MSB first, 4 zero bits).
FRAME_TOPIC: Final = "/nemesys/frame"
#: Vehicle -> console: the vehicle pose (NED, frame ``map_ned``), at ``pose_hz``.
POSE_TOPIC: Final = "/nemesys/pose"
#: Vehicle -> console: one JSON acknowledgement per frame the onboard agent processed.
MISSION_TOPIC: Final = "/nemesys/mission"
#: Vehicle -> console: JSON vehicle status (depth, battery, mode, link), at ``status_hz``.
STATUS_TOPIC: Final = "/nemesys/status"

#: Canonical (ROS 1 spelling) message types; the ROS 2 spelling ``pkg/msg/Name`` is accepted.
UINT8_MULTIARRAY_TYPE: Final = "std_msgs/UInt8MultiArray"
STRING_TYPE: Final = "std_msgs/String"
POSE_STAMPED_TYPE: Final = "geometry_msgs/PoseStamped"

#: Every topic the bridge knows, with its canonical type.
TOPIC_TYPES: Final[Mapping[str, str]] = MappingProxyType(
    {
        FRAME_TOPIC: UINT8_MULTIARRAY_TYPE,
        POSE_TOPIC: POSE_STAMPED_TYPE,
        MISSION_TOPIC: STRING_TYPE,
        STATUS_TOPIC: STRING_TYPE,
    }
)
#: Topics a client may advertise and publish on (console -> vehicle).
INBOUND_TOPICS: Final = frozenset({FRAME_TOPIC})
#: Topics only the vehicle publishes (clients subscribe).
VEHICLE_TOPICS: Final = frozenset({POSE_TOPIC, MISSION_TOPIC, STATUS_TOPIC})

#: ``header.frame_id`` of every pose: NED world frame (x north, y east, z down), metres.
POSE_FRAME_ID: Final = "map_ned"

#: rosapi services the bridge answers (enough for ``Ros.get_topics()`` and friends).
TOPICS_SERVICE: Final = "/rosapi/topics"
TOPIC_TYPE_SERVICE: Final = "/rosapi/topic_type"
SERVICES_SERVICE: Final = "/rosapi/services"
SERVICES: Final = (TOPICS_SERVICE, TOPIC_TYPE_SERVICE, SERVICES_SERVICE)

#: Status levels of the rosbridge spec, quietest first.
STATUS_LEVELS: Final = ("none", "error", "warning", "info")
#: A new session reports nothing until the client asks with ``set_level`` (see module doc).
DEFAULT_STATUS_LEVEL: Final = "none"
_LEVEL_RANK: Final[Mapping[str, int]] = MappingProxyType(
    {name: rank for rank, name in enumerate(STATUS_LEVELS)}
)

#: Default soft limit on one incoming message, UTF-8 bytes; larger ones are dropped.
DEFAULT_MAX_MESSAGE_BYTES: Final = 65536

#: rosbridge ops that exist in the protocol but that this bridge does not implement.
UNSUPPORTED_OPS: Final = frozenset(
    {
        "advertise_service",
        "unadvertise_service",
        "service_response",
        "advertise_action",
        "unadvertise_action",
        "send_action_goal",
        "cancel_action_goal",
        "action_feedback",
        "action_result",
        "fragment",
        "png",
        "auth",
    }
)

JsonObject: TypeAlias = dict[str, Any]
#: The optional ``id`` of a rosbridge message, echoed in replies.
MessageId: TypeAlias = str | int | None


# ---------------------------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------------------------


class BridgeError(Exception):
    """A client message the bridge drops. ``reason`` is for logs and status messages."""

    def __init__(self, reason: str, op_id: MessageId = None) -> None:
        super().__init__(reason)
        self.reason = reason
        self.op_id = op_id


class MalformedMessage(BridgeError):
    """Not JSON, not a JSON object, or a required field missing or of the wrong JSON type."""


class OversizedMessage(BridgeError):
    """Larger than the session's ``max_message_bytes``."""


class BinaryMessage(BridgeError):
    """A binary websocket frame: rosbridge JSON travels in text frames only."""


class UnknownOp(BridgeError):
    """An ``op`` that rosbridge v2 does not define (or no ``op`` at all)."""


class UnsupportedOp(BridgeError):
    """A rosbridge op or option this bridge does not implement (actions, CBOR, PNG, ...)."""


class UnknownTopic(BridgeError):
    """A topic the bridge does not carry."""


class ReadOnlyTopic(BridgeError):
    """An advertise or publish on a topic only the vehicle publishes."""


class TypeMismatch(BridgeError):
    """A message type (declared or by its fields) that is not the topic's type."""


class InvalidData(BridgeError):
    """``UInt8MultiArray.data`` that is neither a list of ints 0..255 nor valid base64."""


# ---------------------------------------------------------------------------------------------
# Requests (incoming messages, validated)
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Advertise:
    """``advertise``: the client will publish ``type`` on ``topic``."""

    topic: str
    type: str
    id: MessageId = None


@dataclass(frozen=True, slots=True)
class Unadvertise:
    """``unadvertise``: the client stops publishing on ``topic``."""

    topic: str
    id: MessageId = None


@dataclass(frozen=True, slots=True)
class Publish:
    """``publish``: one message ``msg`` (a JSON object) on ``topic``."""

    topic: str
    msg: Mapping[str, Any]
    id: MessageId = None


@dataclass(frozen=True, slots=True)
class Subscribe:
    """``subscribe``: send the client every message on ``topic``; ``type`` is optional."""

    topic: str
    type: str | None = None
    id: MessageId = None


@dataclass(frozen=True, slots=True)
class Unsubscribe:
    """``unsubscribe``: by ``id`` (that subscription) or by ``topic`` alone (all of them)."""

    topic: str | None
    id: MessageId = None


@dataclass(frozen=True, slots=True)
class CallService:
    """``call_service``: ``args`` as sent (the spec says a list, roslibpy sends an object)."""

    service: str
    args: Mapping[str, Any] | tuple[Any, ...] = ()
    id: MessageId = None


@dataclass(frozen=True, slots=True)
class SetLevel:
    """``set_level``: which status messages the client wants (one of :data:`STATUS_LEVELS`)."""

    level: str
    id: MessageId = None


@dataclass(frozen=True, slots=True)
class ClientStatus:
    """A ``status`` message from the client: accepted and ignored."""

    level: str | None
    msg: str | None
    id: MessageId = None


Request: TypeAlias = (
    Advertise
    | Unadvertise
    | Publish
    | Subscribe
    | Unsubscribe
    | CallService
    | SetLevel
    | ClientStatus
)


@dataclass(frozen=True, slots=True)
class Outcome:
    """What one incoming message led to.

    ``replies`` go back to the sending client, in order. ``frame`` is set when the message
    was a valid publish on :data:`FRAME_TOPIC`: the bytes to hand to the vehicle. ``error``
    is set when the message was dropped; ``notice`` is a non-fatal remark (for example an
    unsubscribe that matched nothing). ``request`` is the parsed message, if it parsed.
    """

    request: Request | None = None
    replies: tuple[JsonObject, ...] = ()
    frame: bytes | None = None
    error: BridgeError | None = None
    notice: str | None = None

    @property
    def dropped(self) -> bool:
        """True when the message was dropped (``error`` is set)."""
        return self.error is not None


# ---------------------------------------------------------------------------------------------
# Types and field helpers
# ---------------------------------------------------------------------------------------------


def canonical_type(type_name: str) -> str:
    """The ROS 1 spelling of a message type: ``std_msgs/msg/String`` -> ``std_msgs/String``.

    Names already in ROS 1 form, and names of any other shape, are returned unchanged.
    """
    parts = type_name.strip().split("/")
    if len(parts) == 3 and parts[1] == "msg" and parts[0] and parts[2]:
        return f"{parts[0]}/{parts[2]}"
    return type_name.strip()


def same_type(a: str, b: str) -> bool:
    """True when two type names denote the same message type in either ROS spelling."""
    return canonical_type(a) == canonical_type(b)


def _op_id(obj: Mapping[str, Any]) -> MessageId:
    """The message ``id``: a string or an integer; anything else is malformed."""
    value = obj.get("id")
    if value is None or isinstance(value, str):
        return value
    if isinstance(value, int) and not isinstance(value, bool):
        return value
    raise MalformedMessage(f"'id' must be a string, got {type(value).__name__}")


def _require_str(obj: Mapping[str, Any], key: str, op: str, op_id: MessageId) -> str:
    value = obj.get(key)
    if value is None:
        raise MalformedMessage(f"{op}: missing field '{key}'", op_id)
    if not isinstance(value, str) or not value:
        raise MalformedMessage(f"{op}: '{key}' must be a non-empty string", op_id)
    return value


def _optional_str(obj: Mapping[str, Any], key: str, op: str, op_id: MessageId) -> str | None:
    value = obj.get(key)
    if value is None:
        return None
    if not isinstance(value, str):
        raise MalformedMessage(f"{op}: '{key}' must be a string", op_id)
    return value


def _optional_count(obj: Mapping[str, Any], key: str, op: str, op_id: MessageId) -> None:
    """Validate an ignored numeric option (``throttle_rate``, ``queue_length``): >= 0."""
    value = obj.get(key)
    if value is None:
        return
    if isinstance(value, bool) or not isinstance(value, int | float) or not value >= 0:
        raise MalformedMessage(f"{op}: '{key}' must be a number >= 0", op_id)


# ---------------------------------------------------------------------------------------------
# Parsers, one per op (the dispatch table)
# ---------------------------------------------------------------------------------------------


def _parse_advertise(obj: Mapping[str, Any], op_id: MessageId) -> Advertise:
    topic = _require_str(obj, "topic", "advertise", op_id)
    type_name = _require_str(obj, "type", "advertise", op_id)
    return Advertise(topic=topic, type=type_name, id=op_id)


def _parse_unadvertise(obj: Mapping[str, Any], op_id: MessageId) -> Unadvertise:
    return Unadvertise(topic=_require_str(obj, "topic", "unadvertise", op_id), id=op_id)


def _parse_publish(obj: Mapping[str, Any], op_id: MessageId) -> Publish:
    topic = _require_str(obj, "topic", "publish", op_id)
    msg = obj.get("msg")
    if msg is None:
        raise MalformedMessage("publish: missing field 'msg'", op_id)
    if not isinstance(msg, dict):
        raise MalformedMessage("publish: 'msg' must be a JSON object", op_id)
    return Publish(topic=topic, msg=MappingProxyType(msg), id=op_id)


def _parse_subscribe(obj: Mapping[str, Any], op_id: MessageId) -> Subscribe:
    topic = _require_str(obj, "topic", "subscribe", op_id)
    type_name = _optional_str(obj, "type", "subscribe", op_id)
    compression = _optional_str(obj, "compression", "subscribe", op_id)
    if compression not in (None, "none"):
        raise UnsupportedOp(
            f"subscribe {topic}: compression {compression!r} is not supported, use 'none'", op_id
        )
    for key in ("throttle_rate", "queue_length", "fragment_size"):
        _optional_count(obj, key, "subscribe", op_id)
    return Subscribe(topic=topic, type=type_name or None, id=op_id)


def _parse_unsubscribe(obj: Mapping[str, Any], op_id: MessageId) -> Unsubscribe:
    topic = _optional_str(obj, "topic", "unsubscribe", op_id)
    if not topic and op_id is None:
        raise MalformedMessage("unsubscribe: needs a 'topic' or an 'id'", op_id)
    return Unsubscribe(topic=topic or None, id=op_id)


def _parse_call_service(obj: Mapping[str, Any], op_id: MessageId) -> CallService:
    service = _require_str(obj, "service", "call_service", op_id)
    args = obj.get("args")
    if args is None:
        return CallService(service=service, id=op_id)
    if isinstance(args, dict):
        return CallService(service=service, args=MappingProxyType(args), id=op_id)
    if isinstance(args, list):
        return CallService(service=service, args=tuple(args), id=op_id)
    raise MalformedMessage("call_service: 'args' must be a JSON object or list", op_id)


def _parse_set_level(obj: Mapping[str, Any], op_id: MessageId) -> SetLevel:
    level = _require_str(obj, "level", "set_level", op_id)
    if level not in _LEVEL_RANK:
        raise MalformedMessage(
            f"set_level: level {level!r} is not one of {', '.join(STATUS_LEVELS)}", op_id
        )
    return SetLevel(level=level, id=op_id)


def _parse_status(obj: Mapping[str, Any], op_id: MessageId) -> ClientStatus:
    level, msg = obj.get("level"), obj.get("msg")
    return ClientStatus(
        level=level if isinstance(level, str) else None,
        msg=msg if isinstance(msg, str) else None,
        id=op_id,
    )


Parser: TypeAlias = Callable[[Mapping[str, Any], MessageId], Request]

#: The dispatch table: rosbridge ``op`` -> parser of that op's JSON object.
OP_PARSERS: Final[Mapping[str, Parser]] = MappingProxyType(
    {
        "advertise": _parse_advertise,
        "unadvertise": _parse_unadvertise,
        "publish": _parse_publish,
        "subscribe": _parse_subscribe,
        "unsubscribe": _parse_unsubscribe,
        "call_service": _parse_call_service,
        "set_level": _parse_set_level,
        "status": _parse_status,
    }
)


def parse_object(obj: object) -> Request:
    """Validate one decoded JSON value as a rosbridge message and parse it.

    Raises :class:`MalformedMessage` (not an object, bad ``id``, bad fields),
    :class:`UnknownOp`, or :class:`UnsupportedOp`. Errors carry the message ``id`` if any.
    """
    if not isinstance(obj, dict):
        raise MalformedMessage(f"expected a JSON object, got {_json_kind(obj)}")
    op_id = _op_id(obj)
    op = obj.get("op")
    if op is None:
        raise UnknownOp("message has no 'op'", op_id)
    if not isinstance(op, str):
        raise MalformedMessage("'op' must be a string", op_id)
    parser = OP_PARSERS.get(op)
    if parser is not None:
        return parser(obj, op_id)
    if op in UNSUPPORTED_OPS:
        raise UnsupportedOp(f"op {op!r} is not supported by this bridge", op_id)
    raise UnknownOp(f"unknown op {op!r}; supported: {', '.join(OP_PARSERS)}", op_id)


def parse_message(text: str) -> Request:
    """Parse one rosbridge text message (a JSON object with an ``op``); see :func:`parse_object`."""
    try:
        obj = json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise MalformedMessage(f"not valid JSON: {exc}") from None
    return parse_object(obj)


def _json_kind(value: object) -> str:
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, str):
        return "a string"
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, int | float):
        return "a number"
    return type(value).__name__


# ---------------------------------------------------------------------------------------------
# std_msgs/UInt8MultiArray decoding
# ---------------------------------------------------------------------------------------------

_UINT8_MULTIARRAY_FIELDS: Final = frozenset({"layout", "data"})


def decode_uint8_data(data: object, op_id: MessageId = None) -> bytes:
    """Bytes of a ``uint8[]`` field: a JSON list of ints 0..255, or a base64 string.

    Raises :class:`InvalidData` for anything else (floats, booleans, out-of-range values,
    bad base64 including embedded whitespace), so no malformed data reaches the vehicle.
    """
    if isinstance(data, str):
        try:
            return base64.b64decode(data, validate=True)
        except (binascii.Error, ValueError) as exc:
            raise InvalidData(f"data is not valid base64: {exc}", op_id) from None
    if isinstance(data, list):
        for index, value in enumerate(data):
            if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 255:
                raise InvalidData(f"data[{index}] = {value!r} is not an integer 0..255", op_id)
        return bytes(data)
    raise InvalidData(
        f"data must be a list of integers 0..255 or a base64 string, got {_json_kind(data)}",
        op_id,
    )


def decode_uint8_multiarray(msg: Mapping[str, Any], op_id: MessageId = None) -> bytes:
    """Bytes carried by a ``std_msgs/UInt8MultiArray`` message (``layout`` is ignored).

    Raises :class:`TypeMismatch` when the fields are not those of a UInt8MultiArray (for
    example a PoseStamped) and :class:`InvalidData` when ``data`` is not bytes.
    """
    extra = sorted(set(msg) - _UINT8_MULTIARRAY_FIELDS)
    if extra:
        raise TypeMismatch(
            f"fields {', '.join(extra)} are not in {UINT8_MULTIARRAY_TYPE} (layout, data)", op_id
        )
    if "data" not in msg:
        raise TypeMismatch(f"{UINT8_MULTIARRAY_TYPE} message without 'data'", op_id)
    layout = msg.get("layout")
    if layout is not None and not isinstance(layout, dict):
        raise TypeMismatch("'layout' must be a MultiArrayLayout object", op_id)
    return decode_uint8_data(msg["data"], op_id)


# ---------------------------------------------------------------------------------------------
# Outgoing messages
# ---------------------------------------------------------------------------------------------


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


def pose_stamped_msg(pose: Pose, frame_id: str = POSE_FRAME_ID) -> JsonObject:
    """``geometry_msgs/PoseStamped`` of a vehicle pose: NED metres, stamp from ``pose.t_s``."""
    qx, qy, qz, qw = quaternion_from_roll_yaw(pose.roll_deg, pose.heading_deg)
    return {
        "header": {"stamp": stamp(pose.t_s), "frame_id": frame_id},
        "pose": {
            "position": {"x": pose.x_m, "y": pose.y_m, "z": pose.z_m},
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
    """``std_msgs/UInt8MultiArray`` with ``data`` as a JSON list of ints (empty layout)."""
    return {"layout": {"dim": [], "data_offset": 0}, "data": list(data)}


def publish_message(topic: str, msg: Mapping[str, Any]) -> JsonObject:
    """A server -> client ``publish``: roslibpy hands ``msg`` to the topic's callbacks."""
    return {"op": "publish", "topic": topic, "msg": dict(msg)}


def status_message(level: str, text: str, op_id: MessageId = None) -> JsonObject:
    """A rosbridge ``status`` message; ``id`` is echoed when the cause had one."""
    message: JsonObject = {"op": "status", "level": level, "msg": text}
    if op_id is not None:
        message["id"] = op_id
    return message


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

    NaN and infinities become ``null`` (browsers' ``JSON.parse`` rejects ``NaN``); numpy
    scalars and arrays become numbers and lists. Raises ``TypeError`` for other objects.
    """
    try:
        return json.dumps(message, separators=(",", ":"), allow_nan=False, default=_json_default)
    except ValueError:
        # Out-of-range floats somewhere: round-trip through lenient JSON, then clean them.
        plain = json.loads(json.dumps(message, default=_json_default))
        return json.dumps(_finite(plain), separators=(",", ":"), allow_nan=False)


# ---------------------------------------------------------------------------------------------
# Session: one client's protocol state
# ---------------------------------------------------------------------------------------------


@dataclass(slots=True)
class _Subscriptions:
    """Subscription ids per topic (``None`` stands for a subscription without an id)."""

    by_topic: dict[str, set[MessageId]] = field(default_factory=dict)

    def add(self, topic: str, sub_id: MessageId) -> None:
        self.by_topic.setdefault(topic, set()).add(sub_id)

    def remove(self, topic: str | None, sub_id: MessageId) -> int:
        """Remove by id (optionally within ``topic``) or, with no id, the whole topic."""
        removed = 0
        topics = [topic] if topic is not None else list(self.by_topic)
        for name in topics:
            ids = self.by_topic.get(name)
            if ids is None:
                continue
            if sub_id is None:
                removed += len(ids)
                ids.clear()
            elif sub_id in ids:
                ids.discard(sub_id)
                removed += 1
            if not ids:
                del self.by_topic[name]
        return removed


class ClientSession:
    """The rosbridge state of one client: advertisements, subscriptions, status level.

    Feed it every message the client sends (:meth:`receive_text`, :meth:`receive_binary`)
    and act on the returned :class:`Outcome`. Ask :meth:`is_subscribed` before sending a
    topic's messages to the client. Never raises for the client's input.
    """

    def __init__(
        self,
        max_message_bytes: int = DEFAULT_MAX_MESSAGE_BYTES,
        status_level: str = DEFAULT_STATUS_LEVEL,
    ) -> None:
        """``max_message_bytes``: larger messages (UTF-8 bytes) are dropped unparsed."""
        if max_message_bytes <= 0:
            raise ValueError("max_message_bytes must be positive")
        if status_level not in _LEVEL_RANK:
            raise ValueError(f"status_level must be one of {', '.join(STATUS_LEVELS)}")
        self.max_message_bytes = max_message_bytes
        self._status_level = status_level
        self._subscriptions = _Subscriptions()
        self._advertised: dict[str, str] = {}
        # Topics this client advertised with a wrong type: its publishes there are refused.
        self._refused_adverts: dict[str, str] = {}

    # -- state ------------------------------------------------------------------------------

    @property
    def status_level(self) -> str:
        """The client's status level: which ``status`` messages it gets."""
        return self._status_level

    @property
    def advertised(self) -> Mapping[str, str]:
        """Topics this client advertised, with the type it declared."""
        return MappingProxyType(self._advertised)

    @property
    def subscriptions(self) -> Mapping[str, frozenset[MessageId]]:
        """Topics this client subscribes to, with the subscription ids."""
        return {topic: frozenset(ids) for topic, ids in self._subscriptions.by_topic.items()}

    def is_subscribed(self, topic: str) -> bool:
        """True when the client has at least one subscription to ``topic``."""
        return topic in self._subscriptions.by_topic

    def wants_status(self, level: str) -> bool:
        """True when a status message of ``level`` should be sent to this client."""
        rank = _LEVEL_RANK.get(level, len(STATUS_LEVELS))
        return 0 < rank <= _LEVEL_RANK[self._status_level]

    # -- input -------------------------------------------------------------------------------

    def receive_text(self, text: str) -> Outcome:
        """Handle one text message: size check, parse, dispatch."""
        # UTF-8 takes at most 4 bytes per code point: only long texts need encoding to measure.
        size = len(text)
        if size * 4 > self.max_message_bytes:
            size = len(text.encode("utf-8", "surrogatepass"))
        if size > self.max_message_bytes:
            return self._drop(
                OversizedMessage(
                    f"message of {size} bytes exceeds the limit of {self.max_message_bytes}"
                )
            )
        try:
            request = parse_message(text)
        except BridgeError as error:
            return self._drop(error)
        return self.handle(request)

    def receive_binary(self, data: bytes) -> Outcome:
        """Handle a binary frame: always dropped (rosbridge JSON is text; no CBOR/BSON here)."""
        return self._drop(
            BinaryMessage(f"binary frame of {len(data)} bytes dropped: send JSON text frames")
        )

    def handle(self, request: Request) -> Outcome:
        """Act on one parsed request."""
        try:
            match request:
                case Advertise():
                    return self._advertise(request)
                case Unadvertise():
                    return self._unadvertise(request)
                case Publish():
                    return self._publish(request)
                case Subscribe():
                    return self._subscribe(request)
                case Unsubscribe():
                    return self._unsubscribe(request)
                case CallService():
                    return self._call_service(request)
                case SetLevel():
                    self._status_level = request.level
                    return Outcome(request)
                case ClientStatus():
                    return Outcome(request)
        except BridgeError as error:
            return self._drop(error, request)
        raise TypeError(f"not a request: {request!r}")  # pragma: no cover - exhaustive match

    # -- op handlers -------------------------------------------------------------------------

    def _check_topic(self, topic: str, op_id: MessageId) -> str:
        expected = TOPIC_TYPES.get(topic)
        if expected is None:
            raise UnknownTopic(f"unknown topic {topic!r}; topics: {', '.join(TOPIC_TYPES)}", op_id)
        return expected

    def _advertise(self, request: Advertise) -> Outcome:
        expected = self._check_topic(request.topic, request.id)
        if request.topic not in INBOUND_TOPICS:
            raise ReadOnlyTopic(
                f"advertise {request.topic}: only the vehicle publishes on this topic", request.id
            )
        if not same_type(request.type, expected):
            self._refused_adverts[request.topic] = request.type
            raise TypeMismatch(
                f"advertise {request.topic}: type {request.type!r} is not {expected}", request.id
            )
        self._refused_adverts.pop(request.topic, None)
        self._advertised[request.topic] = request.type
        return Outcome(request)

    def _unadvertise(self, request: Unadvertise) -> Outcome:
        self._refused_adverts.pop(request.topic, None)
        if self._advertised.pop(request.topic, None) is None:
            return self._note(request, f"unadvertise {request.topic}: topic was not advertised")
        return Outcome(request)

    def _publish(self, request: Publish) -> Outcome:
        self._check_topic(request.topic, request.id)
        if request.topic not in INBOUND_TOPICS:
            raise ReadOnlyTopic(
                f"publish {request.topic}: only the vehicle publishes on this topic", request.id
            )
        refused = self._refused_adverts.get(request.topic)
        if refused is not None:
            raise TypeMismatch(
                f"publish {request.topic}: advertised as {refused!r}, "
                f"the topic's type is {TOPIC_TYPES[request.topic]}",
                request.id,
            )
        frame = decode_uint8_multiarray(request.msg, request.id)
        replies: tuple[JsonObject, ...] = ()
        if self.wants_status("info"):
            text = f"publish {request.topic}: {len(frame)} bytes handed to the vehicle"
            replies = (status_message("info", text, request.id),)
        return Outcome(request, replies=replies, frame=frame)

    def _subscribe(self, request: Subscribe) -> Outcome:
        expected = self._check_topic(request.topic, request.id)
        if request.type is not None and not same_type(request.type, expected):
            raise TypeMismatch(
                f"subscribe {request.topic}: type {request.type!r} is not {expected}", request.id
            )
        self._subscriptions.add(request.topic, request.id)
        return Outcome(request)

    def _unsubscribe(self, request: Unsubscribe) -> Outcome:
        if self._subscriptions.remove(request.topic, request.id) == 0:
            what = request.topic if request.topic is not None else f"id {request.id!r}"
            return self._note(request, f"unsubscribe {what}: no such subscription")
        return Outcome(request)

    def _call_service(self, request: CallService) -> Outcome:
        if request.service == TOPICS_SERVICE:
            values: JsonObject = {"topics": list(TOPIC_TYPES), "types": list(TOPIC_TYPES.values())}
        elif request.service == TOPIC_TYPE_SERVICE:
            topic = _service_arg(request.args, "topic")
            values = {"type": TOPIC_TYPES.get(topic, "") if topic is not None else ""}
        elif request.service == SERVICES_SERVICE:
            values = {"services": list(SERVICES)}
        else:
            text = f"service {request.service} does not exist; services: {', '.join(SERVICES)}"
            reply = service_response(request.service, text, False, request.id)
            return Outcome(request, replies=(reply,), notice=text)
        return Outcome(
            request, replies=(service_response(request.service, values, True, request.id),)
        )

    # -- helpers -----------------------------------------------------------------------------

    def _drop(self, error: BridgeError, request: Request | None = None) -> Outcome:
        replies: tuple[JsonObject, ...] = ()
        if self.wants_status("error"):
            replies = (status_message("error", error.reason, error.op_id),)
        return Outcome(request, replies=replies, error=error)

    def _note(self, request: Request, text: str) -> Outcome:
        replies: tuple[JsonObject, ...] = ()
        if self.wants_status("warning"):
            replies = (status_message("warning", text, request.id),)
        return Outcome(request, replies=replies, notice=text)


def _service_arg(args: Mapping[str, Any] | tuple[Any, ...], name: str) -> str | None:
    """A string service argument, by name (object args) or first position (list args)."""
    value = args.get(name) if isinstance(args, Mapping) else (args[0] if args else None)
    return value if isinstance(value, str) else None
