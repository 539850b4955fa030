"""rosbridge v2 for the NemeSys bridge, sans-IO: the server side of the protocol, behaving as
the real ROS 2 ``rosbridge_server`` (with ``rosapi``) does wherever a client can tell.

The websocket server (:mod:`rosbridge.server`) does the IO, the clocks and the logging; this
package layer does the rest, split along its seams:

* :mod:`rosbridge.messages`: the op table and a parser per op (requests), and
  :class:`Outcome`, what one message led to;
* :mod:`rosbridge.flow`: the input buffer, subscription pacing (``throttle_rate``,
  ``queue_length``) and incoming fragments;
* :mod:`rosbridge.session`: :class:`ClientSession`, one client's state;
* :mod:`rosbridge.graph`: the ROS graph (nodes, topics, services) and rosapi;
* :mod:`rosbridge.types` and :mod:`rosbridge.convert`: message types
  and the JSON conversion (``uint8[]`` as base64, NaN as ``null``);
* :mod:`rosbridge.typedefs`: full message definitions (rosapi's ``topics_and_raw_types``)
  and the ROS 2 type store; :mod:`rosbridge.compression`: ``cbor`` and ``cbor-raw``;
* :mod:`rosbridge.wire`: builders, serialization and outgoing fragments (the pose message,
  the time stamps and the JSON payloads are the vehicle contract's,
  :mod:`vehicle_contract.messages`);
* :mod:`rosbridge.errors`: the errors, named after the real server's.

As in the ROS 2 server, a client never receives an error: failures are written to the
server's log and to ``/rosout`` only (no ``status`` op, no ``set_level``). The differences
that remain, and what a client should do about each, are tabled in ``docs/bridge.md``.

The topics come from :mod:`vehicle_contract.contract` (see ``docs/vehicle.md``). This module keeps
the names other modules import: the topic constants, :data:`TOPIC_TYPES` (the ROS 1 spelling
the client side sends, which a ROS 2 rosbridge accepts; :data:`ROS2_TOPIC_TYPES` is what rosapi
reports), the errors and the builders. The client side is :mod:`rosbridge.client`.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Final

from rosbridge.convert import (
    decode_uint8_data,
    decode_uint8_multiarray,
    extract,
    populate,
)
from rosbridge.errors import (
    BinaryMessage,
    BridgeError,
    FragmentError,
    InvalidData,
    InvalidName,
    InvalidType,
    JsonObject,
    MalformedMessage,
    MessageId,
    OversizedMessage,
    ServiceError,
    TopicNotEstablished,
    TypeMismatch,
    UnknownOp,
    UnsupportedOp,
)
from rosbridge.flow import Defragmenter, IncomingBuffer, MessageHandler
from rosbridge.graph import (
    BRIDGE_NODE,
    CLIENT_COUNT_TOPIC,
    CONNECTED_CLIENTS_TOPIC,
    PARAMETER_EVENTS_TOPIC,
    ROSOUT_TOPIC,
    SERVER_TOPIC_TYPES,
    Graph,
    expand_name,
)
from rosbridge.messages import (
    OP_PARSERS,
    UNSUPPORTED_OPS,
    Advertise,
    CallService,
    Fragment,
    LogLine,
    Outcome,
    Publication,
    Publish,
    Request,
    Subscribe,
    Unadvertise,
    Unimplemented,
    Unsubscribe,
    parse_message,
    parse_object,
)
from rosbridge.session import (
    DEFAULT_FRAGMENT_SIZE,
    DEFAULT_MAX_MESSAGE_BYTES,
    ClientSession,
)
from rosbridge.types import canonical_type, resolve_type, ros2_type, same_type
from rosbridge.wire import (
    connected_clients_msg,
    fragments,
    json_string_msg,
    log_msg,
    publish_message,
    service_response,
    string_msg,
    uint8_multiarray_msg,
    wire_json,
)
from vehicle_contract import contract
from vehicle_contract.contract import POSE_FRAME_ID, VEHICLE_NODE
from vehicle_contract.messages import pose_stamped_msg, quaternion_from_roll_yaw, stamp, to_json

#: Console -> vehicle: one packed frame (13 bytes: 100 bits MSB first, 4 zero bits).
FRAME_TOPIC: Final = contract.FRAME_TOPIC
#: Vehicle -> console: the vehicle pose (NED, frame ``map_ned``), at ``pose_hz``.
POSE_TOPIC: Final = contract.POSE_TOPIC
#: Vehicle -> console: one JSON acknowledgement per frame the onboard agent processed.
MISSION_TOPIC: Final = contract.MISSION_TOPIC
#: Vehicle -> console: JSON vehicle status (depth, battery, mode, link), at ``status_hz``.
STATUS_TOPIC: Final = contract.STATUS_TOPIC

#: The contract's topics with their ROS 2 type (what rosapi reports).
ROS2_TOPIC_TYPES: Final[Mapping[str, str]] = MappingProxyType(dict(contract.TOPIC_TYPES))
#: The same in the ROS 1 spelling (what the client side advertises and subscribes with).
TOPIC_TYPES: Final[Mapping[str, str]] = MappingProxyType(
    {name: canonical_type(kind) for name, kind in contract.TOPIC_TYPES.items()}
)
UINT8_MULTIARRAY_TYPE: Final = TOPIC_TYPES[FRAME_TOPIC]
STRING_TYPE: Final = TOPIC_TYPES[MISSION_TOPIC]
POSE_STAMPED_TYPE: Final = TOPIC_TYPES[POSE_TOPIC]

#: rosapi services the console and the clients use.
TOPICS_SERVICE: Final = "/rosapi/topics"
TOPIC_TYPE_SERVICE: Final = "/rosapi/topic_type"
SERVICES_SERVICE: Final = "/rosapi/services"

__all__ = [
    "BRIDGE_NODE",
    "CLIENT_COUNT_TOPIC",
    "CONNECTED_CLIENTS_TOPIC",
    "DEFAULT_FRAGMENT_SIZE",
    "DEFAULT_MAX_MESSAGE_BYTES",
    "FRAME_TOPIC",
    "MISSION_TOPIC",
    "OP_PARSERS",
    "PARAMETER_EVENTS_TOPIC",
    "POSE_FRAME_ID",
    "POSE_STAMPED_TYPE",
    "POSE_TOPIC",
    "ROS2_TOPIC_TYPES",
    "ROSOUT_TOPIC",
    "SERVER_TOPIC_TYPES",
    "SERVICES_SERVICE",
    "STATUS_TOPIC",
    "STRING_TYPE",
    "TOPICS_SERVICE",
    "TOPIC_TYPES",
    "TOPIC_TYPE_SERVICE",
    "UINT8_MULTIARRAY_TYPE",
    "UNSUPPORTED_OPS",
    "VEHICLE_NODE",
    "Advertise",
    "BinaryMessage",
    "BridgeError",
    "CallService",
    "ClientSession",
    "Defragmenter",
    "Fragment",
    "FragmentError",
    "Graph",
    "IncomingBuffer",
    "InvalidData",
    "InvalidName",
    "InvalidType",
    "JsonObject",
    "LogLine",
    "MalformedMessage",
    "MessageHandler",
    "MessageId",
    "Outcome",
    "OversizedMessage",
    "Publication",
    "Publish",
    "Request",
    "ServiceError",
    "Subscribe",
    "TopicNotEstablished",
    "TypeMismatch",
    "Unadvertise",
    "Unimplemented",
    "UnknownOp",
    "Unsubscribe",
    "UnsupportedOp",
    "canonical_type",
    "connected_clients_msg",
    "decode_uint8_data",
    "decode_uint8_multiarray",
    "expand_name",
    "extract",
    "fragments",
    "json_string_msg",
    "log_msg",
    "parse_message",
    "parse_object",
    "populate",
    "pose_stamped_msg",
    "publish_message",
    "quaternion_from_roll_yaw",
    "resolve_type",
    "ros2_type",
    "same_type",
    "service_response",
    "stamp",
    "string_msg",
    "to_json",
    "uint8_multiarray_msg",
    "wire_json",
]
