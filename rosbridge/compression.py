"""Outgoing ``cbor`` and ``cbor-raw`` messages, as the real ROS 2 ``rosbridge_server`` sends
them to a subscription that asked for that ``compression``.

* Which applies (``capabilities/subscribe.py``): a client's subscriptions to one topic share
  one stream, compressed the strongest way any of them asked (:func:`strongest`:
  ``cbor-raw``, then ``cbor``, then ``png``); any other value, unknown ones included, means
  JSON, with nothing logged.
* ``cbor`` (``internal/cbor_conversion.py``): the ``publish`` op with ``msg`` the message's
  values: strings, booleans, integers, floats (NaN stays NaN), nested messages as maps,
  ``uint8[]``/``char[]`` as a byte string, ``bool[]`` and ``string[]`` as arrays, and other
  numeric arrays as RFC 8746 typed arrays (tags 69-86, little-endian).
* ``cbor-raw``: ``msg`` is ``{"secs", "nsecs", "bytes"}``: ``bytes`` the message serialized
  as ROS 2 does (CDR, with its 4-byte encapsulation header, as a raw ``rclpy`` subscription
  takes it), ``secs``/``nsecs`` the bridge's ROS time when it is sent.

Either way the whole op is CBOR-encoded (:mod:`cbor2`) and goes as one binary websocket frame.

The simulator holds a topic's message as subscribers get it in JSON (``uint8[]`` as base64,
NaN and infinities as ``null``); :func:`typed` turns it back into the typed ROS 2 message
through the type store (:mod:`rosbridge.typedefs`): base64 to bytes, ``null`` to NaN, a
missing field to its default. Fixed-size arrays are encoded like sequences (the real server
cannot CBOR-encode them); ``byte[]`` goes as a byte string like ``uint8[]``.
"""

from __future__ import annotations

import base64
import binascii
import math
import struct
from collections.abc import Iterable, Mapping
from typing import Any, Final

import cbor2
import numpy as np
from rosbags.interfaces import Nodetype
from rosbags.interfaces.typing import FieldDesc

from rosbridge.typedefs import (
    UnknownDefinition,
    fields_of,
    message_fields,
    ros2_name,
    typestore,
)
from rosbridge.types import FIELD_DEFAULTS
from vehicle_contract.messages import stamp

#: The compressions that change what is sent, strongest first (the real server's order).
COMPRESSIONS: Final = ("cbor-raw", "cbor", "png")

#: Typed-array tags (RFC 8746, little-endian) of numeric arrays, with their numpy dtype.
TYPED_ARRAY_TAGS: Final[Mapping[str, tuple[int, str]]] = {
    "uint16": (69, "<u2"),
    "uint32": (70, "<u4"),
    "uint64": (71, "<u8"),
    "int8": (72, "i1"),
    "int16": (77, "<i2"),
    "int32": (78, "<i4"),
    "int64": (79, "<i8"),
    "float32": (85, "<f4"),
    "float64": (86, "<f8"),
}
_BYTES: Final = frozenset({"uint8", "char", "byte"})
_STRINGS: Final = frozenset({"string", "wstring"})
_FLOATS: Final = frozenset({"float32", "float64"})
_MISSING: Final = object()


class EncodeError(ValueError):
    """A message that cannot be encoded as its subscription asks (the real server logs it as
    a failed subscribe callback and sends nothing)."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


def strongest(asked: Iterable[str]) -> str:
    """The compression of a client's stream on one topic, from what its subscriptions asked."""
    values = set(asked)
    return next((c for c in COMPRESSIONS if c in values), "none")


# ---------------------------------------------------------------------------------------------
# JSON -> the typed message
# ---------------------------------------------------------------------------------------------


def typed(type_name: str, msg: object) -> Any:
    """The rosbags message of ``type_name`` for its JSON form. Raises :class:`EncodeError`
    (also for a type the store does not define)."""
    try:
        return _message(type_name, msg)
    except UnknownDefinition as exc:
        raise EncodeError(str(exc)) from None
    except (TypeError, ValueError, OverflowError, binascii.Error) as exc:
        raise EncodeError(f"{type_name}: {exc}") from None


def _message(type_name: str, msg: object) -> Any:
    if not isinstance(msg, Mapping):
        raise TypeError(f"a message must be an object, got {type(msg).__name__}")
    full = ros2_name(type_name)
    values: dict[str, Any] = {}
    for name, desc in fields_of(full):
        value = msg.get(name, _MISSING)
        if value is _MISSING and (full, name) in FIELD_DEFAULTS:
            value = FIELD_DEFAULTS[(full, name)]
        values[name] = _field(desc, value, name)
    return typestore().types[full](**values)


def _field(desc: FieldDesc, value: Any, name: str) -> Any:
    if desc[0] == Nodetype.BASE:
        return _scalar(desc[1][0], value)
    if desc[0] == Nodetype.NAME:
        return _message(desc[1], {} if value is _MISSING else value)
    inner, size = desc[1]
    items = _array(inner, [] if value is _MISSING or value is None else value)
    if desc[0] == Nodetype.ARRAY and len(items) != size:
        raise ValueError(f"field {name} needs {size} values, got {len(items)}")
    return items


def _scalar(base: str, value: Any) -> Any:
    if base in _STRINGS:
        return "" if value is _MISSING else str(value)
    if base in _FLOATS:
        if value is None:  # NaN and infinities went out as null
            return math.nan
        return 0.0 if value is _MISSING else float(value)
    if base == "bool":
        return False if value is _MISSING else bool(value)
    return 0 if value is _MISSING else int(value)


def _array(inner: Any, value: Any) -> Any:
    if inner[0] == Nodetype.NAME:
        return [_message(inner[1], item) for item in value]
    base = inner[1][0]
    if base in _STRINGS:
        return [str(item) for item in value]
    if base in _BYTES:
        data = base64.b64decode(value) if isinstance(value, str) else bytes(value)
        return np.frombuffer(data, dtype=np.uint8)
    if base == "bool":
        return np.array([bool(item) for item in value], dtype=np.bool_)
    items = [math.nan if item is None else item for item in value]
    return np.array(items, dtype=TYPED_ARRAY_TAGS[base][1])


# ---------------------------------------------------------------------------------------------
# The typed message -> CBOR values
# ---------------------------------------------------------------------------------------------


def cbor_values(type_name: str, message: Any) -> dict[str, Any]:
    """A typed message's values for ``cbor`` compression (the real ``extract_cbor_values``
    rules, in field order)."""
    out: dict[str, Any] = {}
    for name, desc in message_fields(type_name):
        value = getattr(message, name)
        if desc[0] == Nodetype.BASE:
            out[name] = value
        elif desc[0] == Nodetype.NAME:
            out[name] = cbor_values(desc[1], value)
        else:
            out[name] = _cbor_array(desc[1][0], value)
    return out


def _cbor_array(inner: Any, value: Any) -> Any:
    if inner[0] == Nodetype.NAME:
        return [cbor_values(inner[1], item) for item in value]
    base = inner[1][0]
    if base in _BYTES:
        return bytes(np.asarray(value, dtype=np.uint8).tobytes())
    if base == "bool":
        return [bool(item) for item in value]
    if base in _STRINGS:
        return [str(item) for item in value]
    tag, dtype = TYPED_ARRAY_TAGS[base]
    return cbor2.CBORTag(tag, np.asarray(value).astype(dtype).tobytes())


# ---------------------------------------------------------------------------------------------
# The binary frames
# ---------------------------------------------------------------------------------------------


def cbor_publish(topic: str, type_name: str, msg: object) -> bytes:
    """The binary frame of a ``publish`` of ``msg`` (JSON form) with ``cbor`` compression. A
    type the store does not define goes with its values as held (it was relayed as sent).
    Raises :class:`EncodeError`."""
    try:
        values: Any = cbor_values(type_name, typed(type_name, msg))
    except EncodeError:
        if fields_defined(type_name):
            raise
        values = msg
    return _dumps({"op": "publish", "topic": topic, "msg": values})


def cbor_raw_publish(topic: str, type_name: str, msg: object, now_s: float) -> bytes:
    """The binary frame of a ``publish`` of ``msg`` (JSON form) with ``cbor-raw`` compression:
    its CDR, stamped with the bridge's ROS time ``now_s``. Raises :class:`EncodeError`."""
    message = typed(type_name, msg)
    try:
        cdr = bytes(typestore().serialize_cdr(message, ros2_name(type_name)))
    except (TypeError, ValueError, OverflowError, AttributeError, struct.error) as exc:
        raise EncodeError(f"{type_name}: {exc}") from None
    time = stamp(now_s)
    raw = {"secs": time["sec"], "nsecs": time["nanosec"], "bytes": cdr}
    return _dumps({"op": "publish", "topic": topic, "msg": raw})


def fields_defined(type_name: str) -> bool:
    """True when the type store defines ``type_name``."""
    return ros2_name(type_name) in typestore().fielddefs


def _dumps(value: Any) -> bytes:
    try:
        return cbor2.dumps(value)
    except (cbor2.CBOREncodeError, TypeError, ValueError) as exc:
        raise EncodeError(f"cannot encode as CBOR: {exc}") from None
