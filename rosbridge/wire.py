"""What the rosbridge server sends: message builders, JSON, and fragments.

Builders make the ``msg`` of the NemeSys topics that rosbridge carries (:func:`json_string_msg`,
:func:`uint8_multiarray_msg`; the pose is the contract's,
:func:`vehicle_contract.messages.pose_stamped_msg`), the server's own topics
(:func:`log_msg`, :func:`connected_clients_msg`) and the envelopes (:func:`publish_message`,
:func:`service_response`); :func:`wire_json` serializes them as the real server does (NaN as
``null``; :func:`vehicle_contract.messages.to_json` is the compact form), and
:func:`fragments` splits a serialized message into ``fragment`` ops exactly as the real
server's ``Protocol.send`` does; :func:`binary_frame` checks a CBOR message against the
fragment size as the real server's send does (it cannot fragment one).
"""

from __future__ import annotations

import base64
from collections.abc import Mapping
from typing import Any, Final

from rosbridge.errors import FragmentError, JsonObject, MessageId
from vehicle_contract.messages import stamp, strict_json, to_json

#: rcl log levels (``rcl_interfaces/msg/Log``).
LOG_DEBUG: Final = 10
LOG_INFO: Final = 20
LOG_WARN: Final = 30
LOG_ERROR: Final = 40


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


def wire_json(message: Any) -> str:
    """A server -> client message serialized as the real server does it: Python's default
    ``json.dumps`` (``", "`` and ``": "`` separators, non-ASCII escaped), NaN as ``null``.
    Fragment boundaries and sizes therefore match the real server's."""
    return strict_json(message, (", ", ": "))


def binary_frame(data: bytes, fragment_size: object) -> bytes:
    """A CBOR message (``cbor``, ``cbor-raw``) as the real server sends it: whole, when it fits
    ``fragment_size`` (or the size is ``None``). The real server cannot fragment one: its send
    fails (``'bytes' object has no attribute 'get'``, rosbridge_suite issue #844), as it does
    for a size that is not a number: both raise :class:`FragmentError` with its words."""
    if fragment_size is None:
        return data
    if not isinstance(fragment_size, int | float):
        raise FragmentError(
            f"'>' not supported between instances of 'int' and '{type(fragment_size).__name__}'"
        )
    if len(data) > fragment_size:
        raise FragmentError("'bytes' object has no attribute 'get'")
    return data


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
