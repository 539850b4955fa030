"""Errors of the rosbridge protocol layer, and the JSON aliases the other modules share.

Each class stands for one of the exceptions the real ``rosbridge_server`` (ROS 2) raises and
logs; ``reason`` is its text, worded as the real server words it where a client could
compare (the real server only logs it: a ROS 2 client never receives it, see
``docs/bridge.md``). The server side is :mod:`rosbridge.protocol`; the client side
(:mod:`rosbridge.client`, :mod:`station.transmit`, :mod:`station.link`) uses
the same classes for what it cannot read.
"""

from __future__ import annotations

from typing import Any, TypeAlias

JsonObject: TypeAlias = dict[str, Any]
#: The optional ``id`` of a rosbridge message: any JSON value, echoed in replies as sent.
MessageId: TypeAlias = Any


class BridgeError(Exception):
    """A message that failed. ``reason`` is for the log; ``op_id`` the message's ``id``."""

    def __init__(self, reason: str, op_id: MessageId = None) -> None:
        super().__init__(reason)
        self.reason = reason
        self.op_id = op_id


class MalformedMessage(BridgeError):
    """Not a rosbridge message: no ``op``, a required field missing or of the wrong type
    (the real server's ``MissingArgumentException`` / ``InvalidArgumentException``)."""


class OversizedMessage(BridgeError):
    """Larger than the session's ``max_message_bytes``."""


class BinaryMessage(BridgeError):
    """A binary websocket frame that is not UTF-8 text (client side: any binary frame)."""


class UnknownOp(BridgeError):
    """An ``op`` the ROS 2 server does not register (``set_level``, ``status``, ``auth``...)."""


class UnsupportedOp(BridgeError):
    """An op the real server registers and this bridge does not implement (services and
    actions provided by clients)."""


class TopicNotEstablished(BridgeError):
    """A topic nobody publishes or subscribes yet, used without a type."""


class InvalidName(BridgeError):
    """A topic or service name ROS 2 does not accept (``/a b``, ``/a//b``, ``/1x``)."""


class InvalidType(BridgeError):
    """A message type name that does not resolve (``foo``, ``nopkg/Thing``)."""


class TypeMismatch(BridgeError):
    """A type conflict (the topic has another type), or a message whose fields do not fit
    its type (an unknown field, a string for a number...)."""


class InvalidData(BridgeError):
    """``uint8[]`` data that is neither base64 nor a list of integers 0..255."""


class ServiceError(BridgeError):
    """A ``call_service`` that failed: answered with ``result: false``, ``values`` this text."""


class FragmentError(BridgeError):
    """An outgoing message that cannot be split with the client's ``fragment_size``, or an
    incoming fragment that cannot be stored."""
