"""The ROS graph a client sees through the simulated rosbridge.

A real vehicle runs ``rosbridge_websocket``, ``rosapi`` (with its helper ``rosapi_params``)
and the vehicle's node; the simulator reproduces that graph: :class:`Graph` holds the nodes,
the topics each publishes and subscribes (the NemeSys contract, the server's own topics, and
those the bridge creates for its clients), and the services. :func:`rosbridge.rosapi.call_service`
answers the rosapi services a client uses about it, in the real ``rosapi`` node's layout;
names are resolved against the root namespace as the real server's ``rclpy`` does
(:func:`expand_name`: ``rosapi/topics`` is ``/rosapi/topics``).
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Final

from rosbridge.errors import (
    InvalidName,
    JsonObject,
    ServiceError,
    TopicNotEstablished,
    TypeMismatch,
)
from rosbridge.types import resolve_type
from vehicle_contract import contract
from vehicle_contract.contract import VEHICLE_NODE
from vehicle_contract.names import check_namespace, topic_name

#: Node names (a real vehicle: rosbridge_websocket_launch.xml plus the vehicle's node).
BRIDGE_NODE: Final = "/rosbridge_websocket"
ROSAPI_NODE: Final = "/rosapi"
ROSAPI_PARAMS_NODE: Final = "/rosapi_params"
#: A fleet's graph (:class:`Graph` with namespaces): the surface station's ME transmitter, the
#: subscriber of the contract's frame topic, through which a frame goes once onto the link
#: that every vehicle hears.
TRANSMITTER_NODE: Final = "/nemesys_me_transmitter"
#: The ROS 2 distribution the simulated graph is modelled on (rosapi/get_ros_version).
ROS_DISTRO: Final = "jazzy"
#: Seconds a publisher the bridge made for its clients outlives their last unadvertise.
UNREGISTER_TIMEOUT_S: Final = 10.0

#: The server's own topics: every node logs to /rosout and announces parameter changes.
ROSOUT_TOPIC: Final = "/rosout"
PARAMETER_EVENTS_TOPIC: Final = "/parameter_events"
CLIENT_COUNT_TOPIC: Final = "/client_count"
CONNECTED_CLIENTS_TOPIC: Final = "/connected_clients"
SERVER_TOPIC_TYPES: Final[Mapping[str, str]] = MappingProxyType(
    {
        ROSOUT_TOPIC: "rcl_interfaces/msg/Log",
        PARAMETER_EVENTS_TOPIC: "rcl_interfaces/msg/ParameterEvent",
        CLIENT_COUNT_TOPIC: "std_msgs/msg/Int32",
        CONNECTED_CLIENTS_TOPIC: "rosbridge_msgs/msg/ConnectedClients",
    }
)

_PARAMETER_SERVICES: Final = (
    ("describe_parameters", "rcl_interfaces/srv/DescribeParameters"),
    ("get_parameter_types", "rcl_interfaces/srv/GetParameterTypes"),
    ("get_parameters", "rcl_interfaces/srv/GetParameters"),
    ("list_parameters", "rcl_interfaces/srv/ListParameters"),
    ("set_parameters", "rcl_interfaces/srv/SetParameters"),
    ("set_parameters_atomically", "rcl_interfaces/srv/SetParametersAtomically"),
)
_TYPE_DESCRIPTION: Final = (
    "get_type_description",
    "type_description_interfaces/srv/GetTypeDescription",
)
#: rosapi's services (name -> type suffix), as ``rosapi_node`` creates them.
ROSAPI_SERVICES: Final = tuple(
    (f"/rosapi/{name}", f"rosapi_msgs/srv/{kind}")
    for name, kind in (
        ("topics", "Topics"),
        ("topics_for_type", "TopicsForType"),
        ("topics_and_raw_types", "TopicsAndRawTypes"),
        ("services", "Services"),
        ("services_for_type", "ServicesForType"),
        ("nodes", "Nodes"),
        ("node_details", "NodeDetails"),
        ("action_servers", "GetActionServers"),
        ("topic_type", "TopicType"),
        ("service_type", "ServiceType"),
        ("publishers", "Publishers"),
        ("subscribers", "Subscribers"),
        ("service_providers", "ServiceProviders"),
        ("service_node", "ServiceNode"),
        ("message_details", "MessageDetails"),
        ("service_request_details", "ServiceRequestDetails"),
        ("service_response_details", "ServiceResponseDetails"),
        ("set_param", "SetParam"),
        ("get_param", "GetParam"),
        ("has_param", "HasParam"),
        ("delete_param", "DeleteParam"),
        ("get_param_names", "GetParamNames"),
        ("get_time", "GetTime"),
        ("get_ros_version", "GetROSVersion"),
    )
)

_TOKEN: Final = re.compile(r"[A-Za-z0-9_]*")


def vehicle_node_of(namespace: str) -> str:
    """The vehicle's node under ``namespace``: ``/auv1/nemesys_vehicle`` (the reference node's
    name, :data:`vehicle_contract.contract.VEHICLE_NODE`, launched in that namespace)."""
    return check_namespace(namespace) + VEHICLE_NODE


def expand_name(name: str, kind: str = "topic", node: str = BRIDGE_NODE) -> str:
    """A topic or service name made absolute as ``rclpy`` does it for the bridge's node (in
    the root namespace): ``x`` -> ``/x``, ``~/x`` -> ``/rosbridge_websocket/x``.

    Raises :class:`InvalidName` with rcl's reason for a name ROS 2 refuses.
    """
    full = name
    if full.startswith("~"):
        full = node + full[1:]
    elif not full.startswith("/"):
        full = "/" + full
    reason = None
    if not name:
        reason = f"{kind} name must not be empty"
    elif any(not _TOKEN.fullmatch(token) for token in full.split("/")):
        reason = (
            f"{kind} name must not contain characters other than alphanumerics, '_', '~', "
            "'{', or '}'"
        )
    elif "//" in full:
        reason = f"{kind} name must not contain repeated '/'"
    elif full.endswith("/") and full != "/":
        reason = f"{kind} name must not end with a forward slash"
    elif any(token[:1].isdigit() for token in full.split("/")):
        reason = f"{kind} name token must not start with a number"
    if reason is not None:
        raise InvalidName(f"Invalid {kind} name: {reason}:\n  '{name}'")
    return full


@dataclass(slots=True)
class _BridgeTopic:
    """A publisher or subscriber the bridge holds on a topic for its clients."""

    type: str
    clients: set[str] = field(default_factory=set)
    linger_until: float = 0.0


class Graph:
    """The simulated ROS graph, shared by every client session of one server.

    ``clock`` is monotonic seconds (publishers outlive their clients by 10 s, as in the real
    server); ``ros_time`` the ROS time in seconds (the vehicle's clock: stamps, get_time).
    """

    def __init__(
        self,
        clock: Callable[[], float] = time.monotonic,
        ros_time: Callable[[], float] = lambda: 0.0,
        vehicle_node: str = VEHICLE_NODE,
        namespaces: Sequence[str] = (),
    ) -> None:
        self.clock = clock
        self.ros_time = ros_time
        self.vehicle_node = vehicle_node
        # One vehicle (no namespaces): its node and the contract's names, as ever. A fleet:
        # each vehicle's node and topics under its namespace, and the station's transmitter
        # on the contract's frame topic (every frame topic is the one shared link).
        vehicles = (
            [(vehicle_node, "")]
            if not namespaces
            else [(vehicle_node_of(ns), ns) for ns in namespaces]
        )
        fleet_nodes = (TRANSMITTER_NODE,) if namespaces else ()
        self._nodes = (
            BRIDGE_NODE,
            ROSAPI_NODE,
            ROSAPI_PARAMS_NODE,
            *(node for node, _ in vehicles),
            *fleet_nodes,
        )
        #: The topics whose messages are frames for the vehicle (or the fleet's shared link).
        self.frame_topics = frozenset(
            {topic_name(contract.FRAME_TOPIC, ns) for _, ns in vehicles}
            | ({contract.FRAME_TOPIC} if namespaces else set())
        )
        # Static endpoints: topic -> {node: type}.
        self._static_pubs: dict[str, dict[str, str]] = {}
        self._static_subs: dict[str, dict[str, str]] = {}
        for node in self._nodes:
            self._static_pubs.setdefault(ROSOUT_TOPIC, {})[node] = SERVER_TOPIC_TYPES[ROSOUT_TOPIC]
            self._static_pubs.setdefault(PARAMETER_EVENTS_TOPIC, {})[node] = SERVER_TOPIC_TYPES[
                PARAMETER_EVENTS_TOPIC
            ]
        for topic in (CLIENT_COUNT_TOPIC, CONNECTED_CLIENTS_TOPIC):
            self._static_pubs[topic] = {BRIDGE_NODE: SERVER_TOPIC_TYPES[topic]}
        for node, ns in vehicles:
            for t in contract.TOPICS:
                if not t.required:  # the simulator publishes no optional topic (no datum)
                    continue
                side = self._static_subs if t.direction is contract.Direction.TO_VEHICLE else None
                (side if side is not None else self._static_pubs).setdefault(
                    topic_name(t.name, ns), {}
                )[node] = t.type
        if namespaces:
            self._static_subs.setdefault(contract.FRAME_TOPIC, {})[TRANSMITTER_NODE] = (
                contract.TOPIC_TYPES[contract.FRAME_TOPIC]
            )
        self._bridge_pubs: dict[str, _BridgeTopic] = {}
        self._bridge_subs: dict[str, _BridgeTopic] = {}
        #: Latched (transient local, depth 1) messages: topic -> the last message's JSON.
        self.latched: dict[str, JsonObject] = {}
        self._services: dict[str, tuple[str, str]] = {}
        for name, kind in ROSAPI_SERVICES:
            self._services[name] = (kind, ROSAPI_NODE)
        for node in self._nodes:
            for suffix, kind in (*_PARAMETER_SERVICES, _TYPE_DESCRIPTION):
                if node != ROSAPI_PARAMS_NODE or suffix == _TYPE_DESCRIPTION[0]:
                    self._services[f"{node}/{suffix}"] = (kind, node)

    # -- topics ------------------------------------------------------------------------------

    def _live(self, table: dict[str, _BridgeTopic]) -> dict[str, _BridgeTopic]:
        now = self.clock()
        return {t: e for t, e in table.items() if e.clients or e.linger_until > now}

    def publishers_by_topic(self) -> dict[str, dict[str, str]]:
        """topic -> {node: type} of every publisher."""
        out = {topic: dict(nodes) for topic, nodes in self._static_pubs.items()}
        for topic, entry in self._live(self._bridge_pubs).items():
            out.setdefault(topic, {})[BRIDGE_NODE] = entry.type
        return out

    def subscribers_by_topic(self) -> dict[str, dict[str, str]]:
        """topic -> {node: type} of every subscriber."""
        out = {topic: dict(nodes) for topic, nodes in self._static_subs.items()}
        for topic, entry in self._live(self._bridge_subs).items():
            out.setdefault(topic, {})[BRIDGE_NODE] = entry.type
        return out

    def topics(self) -> dict[str, str]:
        """Every topic with a publisher or a subscriber, sorted, with its ROS 2 type."""
        merged: dict[str, str] = {}
        for table in (self.publishers_by_topic(), self.subscribers_by_topic()):
            for topic, nodes in table.items():
                merged.setdefault(topic, next(iter(nodes.values())))
        return dict(sorted(merged.items()))

    def topic_type(self, topic: str) -> str | None:
        """The type of an established topic (exact name), else ``None``."""
        return self.topics().get(topic)

    def _establish(self, raw: str, msg_type: str | None) -> tuple[str, str]:
        """``(expanded name, ROS 2 type)`` for a bridge endpoint on ``raw``, checked as the
        real server's publisher and subscriber managers check it."""
        established = self.topic_type(raw)
        if msg_type is None and established is None:
            raise TopicNotEstablished(
                f"Cannot infer topic type for topic {raw} as it is not yet advertised"
            )
        resolved = resolve_type(msg_type) if msg_type is not None else established
        assert resolved is not None
        expanded = expand_name(raw)
        established = established or self.topic_type(expanded)
        if established is not None and established != resolved:
            raise TypeMismatch(
                f"Tried to register topic {raw} with type {resolved} but it is already "
                f"established with type {established}"
            )
        return expanded, resolved

    def add_subscriber(self, client: str, raw: str, msg_type: str | None) -> tuple[str, str]:
        """The bridge subscribes to ``raw`` for ``client``; returns ``(expanded, type)``."""
        expanded, resolved = self._establish(raw, msg_type)
        self._bridge_subs.setdefault(expanded, _BridgeTopic(resolved)).clients.add(client)
        return expanded, resolved

    def remove_subscriber(self, client: str, expanded: str) -> None:
        entry = self._bridge_subs.get(expanded)
        if entry is not None:
            entry.clients.discard(client)
            if not entry.clients:
                del self._bridge_subs[expanded]

    def add_publisher(self, client: str, raw: str, msg_type: str | None) -> tuple[str, str]:
        """The bridge publishes on ``raw`` for ``client``; returns ``(expanded, type)``."""
        expanded = expand_name(raw)
        entry = self._live(self._bridge_pubs).get(expanded)
        if entry is not None and msg_type is None:
            resolved = entry.type
        else:
            expanded, resolved = self._establish(raw, msg_type)
        entry = self._bridge_pubs.setdefault(expanded, _BridgeTopic(resolved))
        entry.clients.add(client)
        return expanded, resolved

    def remove_publisher(self, client: str, expanded: str) -> None:
        """``client`` stops publishing; the publisher outlives its last client by 10 s."""
        entry = self._bridge_pubs.get(expanded)
        if entry is not None and client in entry.clients:
            entry.clients.discard(client)
            if not entry.clients:
                entry.linger_until = self.clock() + UNREGISTER_TIMEOUT_S
                self.latched.pop(expanded, None)

    # -- services ----------------------------------------------------------------------------

    def services(self) -> dict[str, str]:
        """Every service, sorted, with its type."""
        return {name: kind for name, (kind, _) in sorted(self._services.items())}

    def nodes(self) -> list[str]:
        return sorted(self._nodes)

    def node_details(self, node: str) -> JsonObject:
        if node not in self._nodes:
            raise ServiceError("cannot unpack non-iterable NoneType object")
        pubs, subs = self.publishers_by_topic(), self.subscribers_by_topic()
        return {
            "subscribing": sorted(t for t, nodes in subs.items() if node in nodes),
            "publishing": sorted(t for t, nodes in pubs.items() if node in nodes),
            "services": sorted(n for n, (_, owner) in self._services.items() if owner == node),
        }
