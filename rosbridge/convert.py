"""JSON <-> ROS messages for the rosbridge server, as the real server's
``message_conversion`` does it.

* :func:`populate` checks an incoming JSON message against its type and fills every missing
  field with its default (a ``std_msgs/Header`` stamp with now), raising the real server's
  errors (unknown field, wrong JSON type, bad ``uint8[]``).
* :func:`extract` turns a populated message into what a subscriber receives: ``uint8[]`` as a
  base64 string, NaN and infinities as ``null``.
"""

from __future__ import annotations

import base64
import binascii
import math
from typing import Any

from rosbridge.errors import InvalidData, JsonObject, TypeMismatch
from rosbridge.types import (
    BINARY,
    BOOLS,
    FIELD_DEFAULTS,
    FLOATS,
    INT_RANGES,
    MESSAGE_FIELDS,
    TIMES,
    python_type,
    ros2_type,
    short_type,
)
from vehicle_contract.messages import stamp

# ---------------------------------------------------------------------------------------------
# Incoming: JSON -> a complete message
# ---------------------------------------------------------------------------------------------


def populate(
    type_name: str,
    msg: object,
    now_s: float = 0.0,
    fields: tuple[tuple[str, str], ...] | None = None,
) -> Any:
    """A complete message of ``type_name`` (ROS 2 spelling) from the JSON ``msg``.

    Missing fields take their defaults; ``uint8[]`` becomes ``bytes``; a ``std_msgs/Header``
    stamp is ``now_s`` unless given. A type that is not laid out is returned as sent.
    ``fields`` lays out a type that is not in :data:`MESSAGE_FIELDS` (service requests).
    Raises :class:`TypeMismatch` or :class:`InvalidData`.
    """
    layout = fields if fields is not None else MESSAGE_FIELDS.get(type_name)
    if layout is None:
        if not isinstance(msg, dict):
            raise TypeMismatch(
                f"Expected a JSON object for type {short_type(type_name)} "
                f"but received a {python_type(msg)}"
            )
        return msg
    root = short_type(type_name)
    return _object(msg, type_name, layout, root, [], now_s)


def _object(
    msg: object,
    type_name: str,
    layout: tuple[tuple[str, str], ...],
    root: str,
    stack: list[str],
    now_s: float,
) -> JsonObject:
    if not isinstance(msg, dict):
        raise _mismatch(root, stack, short_type(type_name), msg)
    out: JsonObject = {name: default(field, type_name, name) for name, field in layout}
    if type_name == "std_msgs/msg/Header":
        out["stamp"] = stamp(now_s)
    types = dict(layout)
    for name, value in msg.items():
        where = [*stack, name]
        if name not in types:
            raise TypeMismatch(f"Message type {root} does not have a field {'.'.join(where)}")
        out[name] = _value(value, types[name], root, where, now_s)
    return out


def _value(value: object, field: str, root: str, stack: list[str], now_s: float) -> Any:
    if field in BINARY:
        return decode_uint8_data(value, field_name=stack[-1])
    if field in TIMES:
        return _time(value, now_s, root, stack)
    if field in INT_RANGES or field in FLOATS or field in BOOLS or field == "string":
        return _primitive(value, field, root, stack)
    if field.startswith("sequence<"):
        if not isinstance(value, list):
            raise _mismatch(root, stack, field, value)
        inner = field[len("sequence<") : -1]
        return [_value(item, inner, root, stack, now_s) for item in value]
    nested = ros2_type(field)
    layout = MESSAGE_FIELDS.get(nested)
    if layout is None:  # pragma: no cover - every laid-out type only nests laid-out types
        return value
    return _object(value, nested, layout, root, stack, now_s)


def _primitive(value: object, field: str, root: str, stack: list[str]) -> Any:
    if field in FLOATS:
        if isinstance(value, int):  # the real server casts ints (and booleans) to float
            return float(value)
        if isinstance(value, float):
            return value
    elif field in BOOLS:
        if isinstance(value, bool):
            return value
    elif field == "string":
        if isinstance(value, str):
            return value
    elif type(value) is int:
        low, high = INT_RANGES[field]
        if not low <= value <= high:
            raise TypeMismatch(f"The '{stack[-1]}' field must be an integer in [{low}, {high}]")
        return value
    raise _mismatch(root, stack, field, value)


def _time(value: object, now_s: float, root: str, stack: list[str]) -> JsonObject:
    """``builtin_interfaces/Time``: ``"now"``, or an object with ``sec``/``secs`` and
    ``nanosec``/``nsecs`` (other keys ignored, as the real server does)."""
    if value == "now":
        return stamp(now_s)
    if isinstance(value, str):
        if any(key in value for key in ("sec", "nsecs")):
            raise TypeMismatch("string indices must be integers, not 'str'")
        return {"sec": 0, "nanosec": 0}
    if not isinstance(value, dict):
        raise TypeMismatch(f"argument of type '{type(value).__name__}' is not iterable")
    out: JsonObject = {"sec": 0, "nanosec": 0}
    for key, names in (("sec", ("sec", "secs")), ("nanosec", ("nanosec", "nsecs"))):
        for name in names:
            if name in value:
                field = "int32" if key == "sec" else "uint32"
                out[key] = _primitive(value[name], field, root, [*stack, key])
                break
    return out


def _mismatch(root: str, stack: list[str], expected: str, found: object) -> TypeMismatch:
    if not stack:
        return TypeMismatch(
            f"Expected a JSON object for type {root} but received a {python_type(found)}"
        )
    return TypeMismatch(
        f"{root} message requires a {expected} for field {'.'.join(stack)}, "
        f"but got a {python_type(found)}"
    )


def default(field: str, owner: str = "", name: str = "") -> Any:
    """The default value of a field of rosidl type ``field`` (of ``owner.name``)."""
    special = FIELD_DEFAULTS.get((owner, name))
    if special is not None:
        return special
    if field in BINARY:
        return b""
    if field.startswith("sequence<"):
        return []
    if field in TIMES:
        return {"sec": 0, "nanosec": 0}
    if field in FLOATS:
        return 0.0
    if field in BOOLS:
        return False
    if field == "string":
        return ""
    if field in INT_RANGES:
        return 0
    nested = ros2_type(field)
    layout = MESSAGE_FIELDS.get(nested, ())
    return {n: default(f, nested, n) for n, f in layout}


# ---------------------------------------------------------------------------------------------
# uint8[]
# ---------------------------------------------------------------------------------------------


def decode_uint8_data(data: object, op_id: Any = None, field_name: str = "data") -> bytes:
    """Bytes of a ``uint8[]`` field: a base64 string or a JSON list of integers 0..255.

    As the real server: base64 is decoded leniently (characters outside the alphabet, such
    as whitespace, are skipped; wrong padding fails), and booleans count as 0 and 1 in a
    list. Raises :class:`InvalidData` for anything else, so no malformed data reaches the
    vehicle.
    """
    if isinstance(data, str):
        try:
            return base64.b64decode(data)
        except (binascii.Error, ValueError) as exc:
            raise InvalidData(f"{field_name} is not valid base64: {exc}", op_id) from None
    if isinstance(data, list):
        for index, value in enumerate(data):
            if not isinstance(value, int) or not 0 <= value <= 255:
                raise InvalidData(
                    f"The '{field_name}' field must be a set or sequence and each value of "
                    f"type 'int' and each unsigned integer in [0, 255] "
                    f"({field_name}[{index}] = {value!r})",
                    op_id,
                )
        return bytes(data)
    raise InvalidData(
        f"{field_name} must be a list of integers 0..255 or a base64 string, "
        f"got {python_type(data)}",
        op_id,
    )


def decode_uint8_multiarray(msg: object, op_id: Any = None) -> bytes:
    """Bytes carried by a ``std_msgs/UInt8MultiArray`` message, checked as the real server
    checks it (unknown fields, field types, ``data``); missing fields are empty."""
    try:
        message = populate("std_msgs/msg/UInt8MultiArray", msg)
    except (TypeMismatch, InvalidData) as exc:
        raise type(exc)(exc.reason, op_id) from None
    data: bytes = message["data"]
    return data


# ---------------------------------------------------------------------------------------------
# Outgoing: a complete message -> JSON
# ---------------------------------------------------------------------------------------------


def extract(type_name: str, message: Any) -> Any:
    """The JSON a subscriber receives for a populated message: ``uint8[]`` as base64 text,
    NaN and infinite floats as ``None``. Types not laid out pass through unchanged."""
    layout = MESSAGE_FIELDS.get(type_name)
    if layout is None or not isinstance(message, dict):
        return message
    return {name: _extract_value(field, message.get(name)) for name, field in layout}


def _extract_value(field: str, value: Any) -> Any:
    if field in BINARY:
        return base64.b64encode(bytes(value)).decode("ascii")
    if field in FLOATS:
        return value if isinstance(value, float) and math.isfinite(value) else None
    if field.startswith("sequence<"):
        inner = field[len("sequence<") : -1]
        return [_extract_value(inner, item) for item in value]
    if field in TIMES or field in INT_RANGES or field in BOOLS or field == "string":
        return value
    return extract(ros2_type(field), value)
