"""Incoming rosbridge messages: the op table, one parser per op, and the records of what a
message led to (:class:`Outcome`).

:func:`parse_object` checks one value's
``op`` against :data:`OP_PARSERS` (the ops the ROS 2 server registers, in its order) and
returns a frozen request record (:class:`Advertise`, :class:`Publish`, ...), raising the
real server's errors with its words: :class:`MalformedMessage` for a missing or mistyped
field, :class:`UnknownOp` for an op it does not register (``set_level``, ``status``).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Final, TypeAlias

from rosbridge.errors import (
    BridgeError,
    JsonObject,
    MalformedMessage,
    MessageId,
    UnknownOp,
)

# ---------------------------------------------------------------------------------------------
# Requests
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Advertise:
    """``advertise``: the client will publish ``type`` on ``topic``."""

    topic: str
    type: str
    id: MessageId = None
    latch: bool = False


@dataclass(frozen=True, slots=True)
class Unadvertise:
    """``unadvertise``: by ``id`` (that advertisement) or all of the client's on ``topic``."""

    topic: str
    id: MessageId = None


@dataclass(frozen=True, slots=True)
class Publish:
    """``publish``: one message ``msg`` on ``topic`` (an absent ``msg`` is ``{}``)."""

    topic: str
    msg: Any
    id: MessageId = None
    latch: bool = False


@dataclass(frozen=True, slots=True)
class Subscribe:
    """``subscribe``: send the client ``topic``'s messages; ``type`` is optional.

    ``throttle_rate`` (ms between messages) and ``queue_length`` (messages kept) shape the
    delivery; ``fragment_size`` is handled for every op by the session.
    """

    topic: str
    type: str | None = None
    id: MessageId = None
    throttle_rate: int = 0
    queue_length: int = 0
    compression: str = "none"


@dataclass(frozen=True, slots=True)
class Unsubscribe:
    """``unsubscribe``: by ``id`` (that subscription) or, without one, all on ``topic``."""

    topic: str
    id: MessageId = None


@dataclass(frozen=True, slots=True)
class CallService:
    """``call_service``: ``args`` as sent (an object, a list, or anything: no arguments)."""

    service: str
    args: Any = ()
    id: MessageId = None


@dataclass(frozen=True, slots=True)
class Fragment:
    """``fragment``: part ``num`` of ``total`` of the message ``id`` (fields as sent)."""

    id: Any
    num: Any
    total: Any
    data: Any


@dataclass(frozen=True, slots=True)
class Unimplemented:
    """An op the real server registers (services and actions a client provides) that this
    bridge does not implement."""

    op: str
    id: MessageId = None


Request: TypeAlias = (
    Advertise
    | Unadvertise
    | Publish
    | Subscribe
    | Unsubscribe
    | CallService
    | Fragment
    | Unimplemented
)

# ---------------------------------------------------------------------------------------------
# What a message led to
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class LogLine:
    """A line the real server writes to its log (and to ``/rosout``) for this message."""

    level: int  # rcl level: 20 info, 30 warn, 40 error
    text: str
    op_id: MessageId = None


@dataclass(frozen=True, slots=True)
class Publication:
    """A client's message on a topic: ``msg`` as subscribers receive it; ``frame`` the bytes
    for the vehicle when the topic is :data:`contract.FRAME_TOPIC`."""

    topic: str
    type: str
    msg: JsonObject
    frame: bytes | None = None


@dataclass(frozen=True, slots=True)
class Outcome:
    """What one message led to. ``error`` is set when it failed (only logged, as ``logs``);
    ``close`` when the real server would drop the connection. ``texts`` are sent as they
    are (``bytes``: a binary frame, a CBOR message)."""

    request: Request | None = None
    replies: tuple[JsonObject, ...] = ()
    texts: tuple[str | bytes, ...] = ()
    publication: Publication | None = None
    error: BridgeError | None = None
    logs: tuple[LogLine, ...] = ()
    close: bool = False

    @property
    def dropped(self) -> bool:
        return self.error is not None

    @property
    def frame(self) -> bytes | None:
        return self.publication.frame if self.publication is not None else None


# ---------------------------------------------------------------------------------------------
# Field checks (the real server's ``Capability.basic_type_check``)
# ---------------------------------------------------------------------------------------------

#: Longest quote of a message in an error text, characters.
_QUOTE_LIMIT: Final = 2000
_TYPE_NAMES: Final = {str: "str", int: "int", bool: "bool", type(None): "NoneType"}


def _check(obj: Mapping[str, Any], name: str, types: tuple[type, ...], required: bool) -> None:
    if name not in obj:
        if required:
            raise MalformedMessage(f"Expected a {name} field but none was found.")
        return
    if not isinstance(obj[name], types):
        shown = ", ".join(f"<class '{_TYPE_NAMES[t]}'>" for t in types)
        shown = f"({shown},)" if len(types) == 1 else f"({shown})"
        raise MalformedMessage(
            f"Expected field {name} to be one of {shown}. Invalid value: {obj[name]}"
        )


def _parse_advertise(obj: Mapping[str, Any], op_id: MessageId) -> Advertise:
    _check(obj, "topic", (str,), True)
    _check(obj, "type", (str,), True)
    return Advertise(obj["topic"], obj["type"], op_id, bool(obj.get("latch", False)))


def _parse_unadvertise(obj: Mapping[str, Any], op_id: MessageId) -> Unadvertise:
    _check(obj, "topic", (str,), True)
    return Unadvertise(obj["topic"], op_id)


def _parse_publish(obj: Mapping[str, Any], op_id: MessageId) -> Publish:
    _check(obj, "topic", (str,), True)
    return Publish(obj["topic"], obj.get("msg", {}), op_id, bool(obj.get("latch", False)))


def _parse_subscribe(obj: Mapping[str, Any], op_id: MessageId) -> Subscribe:
    _check(obj, "topic", (str,), True)
    _check(obj, "type", (str,), False)
    for name in ("throttle_rate", "fragment_size", "queue_length"):
        _check(obj, name, (int,), False)
    _check(obj, "compression", (str,), False)
    return Subscribe(
        topic=obj["topic"],
        type=obj.get("type"),
        id=op_id,
        throttle_rate=int(obj.get("throttle_rate", 0)),
        queue_length=int(obj.get("queue_length", 0)),
        compression=obj.get("compression", "none"),
    )


def _parse_unsubscribe(obj: Mapping[str, Any], op_id: MessageId) -> Unsubscribe:
    _check(obj, "topic", (str,), True)
    return Unsubscribe(obj["topic"], op_id)


def _parse_call_service(obj: Mapping[str, Any], op_id: MessageId) -> CallService:
    _check(obj, "service", (str,), True)
    _check(obj, "fragment_size", (int, type(None)), False)
    _check(obj, "compression", (str,), False)
    return CallService(obj["service"], obj.get("args", []), op_id)


def _parse_fragment(obj: Mapping[str, Any], op_id: MessageId) -> Fragment:
    return Fragment(op_id, obj.get("num"), obj.get("total"), obj.get("data"))


def _unimplemented(op: str) -> Parser:
    def parse(obj: Mapping[str, Any], op_id: MessageId) -> Unimplemented:
        return Unimplemented(op, op_id)

    return parse


Parser: TypeAlias = Callable[[Mapping[str, Any], MessageId], Request]

#: The dispatch table: every op the ROS 2 ``rosbridge_server`` registers, in its order.
OP_PARSERS: Final[Mapping[str, Parser]] = MappingProxyType(
    {
        "advertise": _parse_advertise,
        "unadvertise": _parse_unadvertise,
        "publish": _parse_publish,
        "subscribe": _parse_subscribe,
        "unsubscribe": _parse_unsubscribe,
        "fragment": _parse_fragment,
        "advertise_service": _unimplemented("advertise_service"),
        "call_service": _parse_call_service,
        "service_response": _unimplemented("service_response"),
        "unadvertise_service": _unimplemented("unadvertise_service"),
        "advertise_action": _unimplemented("advertise_action"),
        "action_feedback": _unimplemented("action_feedback"),
        "action_result": _unimplemented("action_result"),
        "send_action_goal": _unimplemented("send_action_goal"),
        "cancel_action_goal": _unimplemented("cancel_action_goal"),
        "unadvertise_action": _unimplemented("unadvertise_action"),
    }
)
#: Ops the real server registers that this bridge does not implement.
UNSUPPORTED_OPS: Final = frozenset(
    {
        "advertise_service",
        "service_response",
        "unadvertise_service",
        "advertise_action",
        "action_feedback",
        "action_result",
        "send_action_goal",
        "cancel_action_goal",
        "unadvertise_action",
    }
)


def op_of(obj: object, text: str = "") -> str:
    """The ``op`` of a decoded JSON value; raises :class:`UnknownOp` as the real server
    logs it (no op, or one it does not register). ``text`` is the message as received."""
    op_id = obj.get("id") if isinstance(obj, dict) else None
    if len(text) > _QUOTE_LIMIT:  # the real server quotes it whole; a log line stays short
        text = text[:_QUOTE_LIMIT] + "..."
    if not isinstance(obj, dict) or "op" not in obj:
        if isinstance(obj, dict) and "receiver" in obj:
            raise UnknownOp(
                "Received a rosbridge v1.0 message.  Please refer to rosbridge.org for the "
                f"correct format of rosbridge v2.0 messages.  Original message was: {text}"
            )
        raise UnknownOp(
            "Received a message without an op.  All messages require 'op' field with value "
            f"one of: {list(OP_PARSERS)}.  Original message was: {text}",
            op_id,
        )
    op = obj["op"]
    if not isinstance(op, str) or op not in OP_PARSERS:
        raise UnknownOp(f"Unknown operation: {op}.  Allowed operations: {list(OP_PARSERS)}", op_id)
    return op


def parse_object(obj: object, text: str = "") -> Request:
    """Check one decoded JSON value as a rosbridge message and parse it.

    Raises :class:`UnknownOp` or :class:`MalformedMessage` (with the message ``id``)."""
    op = op_of(obj, text)
    assert isinstance(obj, dict)
    op_id = obj.get("id")
    try:
        return OP_PARSERS[op](obj, op_id)
    except MalformedMessage as error:
        raise MalformedMessage(f"{op}: {error.reason}", op_id) from None


def parse_message(text: str) -> Request:
    """Parse one rosbridge text message (one JSON object with an ``op``)."""
    try:
        obj = json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise MalformedMessage(f"not valid JSON: {exc}") from None
    return parse_object(obj, text)


#: The op of each request record (the log's prefix for its failures).
OP_NAMES: Final[Mapping[type, str]] = MappingProxyType(
    {
        Advertise: "advertise",
        Unadvertise: "unadvertise",
        Publish: "publish",
        Subscribe: "subscribe",
        Unsubscribe: "unsubscribe",
        CallService: "call_service",
    }
)


def op_name(request: Request) -> str | None:
    """The op of a request record (None for a fragment or an unimplemented op)."""
    return OP_NAMES.get(type(request))


def id_key(op_id: MessageId) -> Any:
    """An id as a dictionary key (the real server's dicts refuse a list or object id)."""
    try:
        hash(op_id)
    except TypeError:
        raise BridgeError(f"unhashable type: '{type(op_id).__name__}'", None) from None
    return op_id
