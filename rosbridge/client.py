"""rosbridge v2, the client side, sans-IO: what a client sends, and what it makes of what the
server sends. The transport under it is :mod:`rosbridge.transport`, the one client the
console's link (:mod:`station.link`), the station's transmitter (:mod:`station.transmit`) and
``nemesys vehicle-check`` use; the server side is :mod:`rosbridge.protocol`.

:class:`ClientProtocol` makes the messages (as roslibpy makes them, ids included),
:func:`decode_server_message` and :func:`decode_json_string` read what comes back, and
:func:`topics_listing` reads a ``/rosapi/topics`` answer.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Iterable, Mapping
from typing import Any

from rosbridge.protocol import (
    TOPIC_TYPES,
    BinaryMessage,
    InvalidData,
    JsonObject,
    MalformedMessage,
    to_json,
)
from vehicle_contract.names import contract_topic_of


def _type(topic: str) -> str:
    """The type a client names for a contract topic, under a vehicle namespace or not."""
    return TOPIC_TYPES[contract_topic_of(topic)]


class ClientProtocol:
    """The messages a rosbridge client sends, shaped and numbered as roslibpy does (sans-IO).

    ``advertise`` are the topics the client publishes on, ``subscribe`` those it listens to,
    each with its type from :data:`TOPIC_TYPES` (a vehicle's topic under a namespace has its
    contract topic's type). Each advertisement and subscription gets its
    id once, so every connection opens (:meth:`open_messages`) and closes
    (:meth:`close_messages`) with the same messages; each :meth:`publish` gets a new id.
    """

    def __init__(self, advertise: Iterable[str], subscribe: Iterable[str]) -> None:
        self._count = itertools.count(1)
        self._advertised = {
            topic: (_type(topic), self._id("advertise", topic)) for topic in advertise
        }
        self._subscribed = {
            topic: (_type(topic), self._id("subscribe", topic)) for topic in subscribe
        }

    def _id(self, op: str, topic: str) -> str:
        return f"{op}:{topic}:{next(self._count)}"

    def open_messages(self) -> tuple[str, ...]:
        """Every advertisement, then every subscription."""
        advertise = (
            {
                "op": "advertise",
                "id": op_id,
                "type": type_name,
                "topic": topic,
                "latch": False,
                "queue_size": 100,
            }
            for topic, (type_name, op_id) in self._advertised.items()
        )
        subscribe = (self._subscribe(topic) for topic in self._subscribed)
        return tuple(to_json(message) for message in (*advertise, *subscribe))

    def _subscribe(self, topic: str) -> JsonObject:
        type_name, op_id = self._subscribed[topic]
        return {
            "op": "subscribe",
            "id": op_id,
            "type": type_name,
            "topic": topic,
            "compression": "none",
            "throttle_rate": 0,
            "queue_length": 0,
        }

    def resubscribe(self, topics: Iterable[str]) -> tuple[str, ...]:
        """Unsubscribe and subscribe again to each of ``topics`` (with its id): a rosbridge
        server makes a new ROS subscription, with the QoS that suits the publishers there now,
        when this client was its last subscriber (a subscription another client holds keeps
        the QoS it was made with)."""
        out: list[JsonObject] = []
        for topic in topics:
            out.append({"op": "unsubscribe", "id": self._subscribed[topic][1], "topic": topic})
            out.append(self._subscribe(topic))
        return tuple(to_json(message) for message in out)

    def close_messages(self) -> tuple[str, ...]:
        """Every unsubscribe, then every unadvertise, with the ids they were opened with."""
        unsubscribe = (
            {"op": "unsubscribe", "id": op_id, "topic": topic}
            for topic, (_, op_id) in self._subscribed.items()
        )
        unadvertise = (
            {"op": "unadvertise", "id": op_id, "topic": topic}
            for topic, (_, op_id) in self._advertised.items()
        )
        return tuple(to_json(message) for message in (*unsubscribe, *unadvertise))

    def call_service(self, service: str, args: Mapping[str, Any] | None = None) -> tuple[str, str]:
        """A ``call_service`` request: (its id, to match the ``service_response``; the text)."""
        op_id = self._id("call_service", service)
        message = {"op": "call_service", "id": op_id, "service": service, "args": dict(args or {})}
        return op_id, to_json(message)

    def publish(self, topic: str, msg: Mapping[str, Any]) -> str:
        """A client -> server ``publish`` of ``msg`` on ``topic``."""
        return to_json(
            {
                "op": "publish",
                "id": self._id("publish", topic),
                "topic": topic,
                "msg": dict(msg),
                "latch": False,
            }
        )


def decode_server_message(data: str | bytes) -> JsonObject:
    """One message a rosbridge server sent: a JSON object (its ``op`` is not checked).

    Raises :class:`BinaryMessage` for a binary frame and :class:`MalformedMessage` for text
    that is not a JSON object; the reason quotes at most 80 characters of it.
    """
    if isinstance(data, bytes):
        raise BinaryMessage(f"a binary message of {len(data)} bytes")
    try:
        message = json.loads(data)
    except (ValueError, RecursionError):
        raise MalformedMessage(f"a message that is not JSON: {data!r:.80}") from None
    if not isinstance(message, dict):
        raise MalformedMessage(f"a message that is not a JSON object: {data!r:.80}")
    return message


def decode_json_string(msg: object) -> JsonObject:
    """The JSON object a ``std_msgs/String`` message carries in ``data`` (the inverse of
    :func:`json_string_msg`); ``data`` already decoded to an object is taken as it is.

    Raises :class:`InvalidData` when there is no JSON object.
    """
    data = msg.get("data") if isinstance(msg, Mapping) else None
    if isinstance(data, str):
        try:
            data = json.loads(data)
        except (ValueError, RecursionError):
            raise InvalidData(f"data is not JSON: {data!r:.80}") from None
    if not isinstance(data, dict):
        raise InvalidData(f"no JSON object in the data of {msg!r:.80}")
    return data


def topics_listing(values: object) -> dict[str, str]:
    """``{topic: type}`` from the ``values`` of a ``/rosapi/topics`` answer
    (``{"topics": [...], "types": [...]}``, parallel lists). Types are given as the server
    spells them (``pkg/Name`` or ``pkg/msg/Name``).

    Raises :class:`InvalidData` when the lists are missing, not strings, or of different
    lengths.
    """
    if not isinstance(values, Mapping):
        raise InvalidData(f"a rosapi/topics answer that is not an object: {values!r:.80}")
    topics, types = values.get("topics"), values.get("types")
    if not isinstance(topics, list) or not isinstance(types, list):
        raise InvalidData(f"a rosapi/topics answer without topics and types: {values!r:.80}")
    if len(topics) != len(types):
        raise InvalidData(
            f"a rosapi/topics answer with {len(topics)} topics but {len(types)} types"
        )
    if not all(isinstance(x, str) for x in (*topics, *types)):
        raise InvalidData("a rosapi/topics answer with a topic or type that is not a string")
    return dict(zip(topics, types, strict=True))
