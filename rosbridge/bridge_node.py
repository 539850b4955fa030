"""Which node in rosapi's answers is the rosbridge server itself (sans-IO).

In ROS 2 a topic exists while any node publishes or subscribes to it, and a rosbridge server
publishes and subscribes *for its clients*: a client's ``subscribe`` makes the bridge's node a
subscriber of that topic (``rosbridge_library/internal/subscribers.py``), a client's
``advertise`` (or ``publish``) makes it a publisher, kept 10 s after the last client leaves
(``internal/publishers.py``). So ``/rosapi/publishers`` and ``/rosapi/subscribers`` list the
bridge's own node beside the vehicle's, and a topic listed by ``/rosapi/topics`` may be there
only because some client (this one, or any observer) subscribed to it. What the *vehicle*
publishes or subscribes is what the other nodes do.

The real server names its node ``rosbridge_websocket`` (``scripts/rosbridge_websocket.py``; the
launch file keeps the name), under whatever namespace it is launched in, and it always
publishes ``client_count`` and ``connected_clients`` (``rosbridge_msgs/msg/ConnectedClients``,
a type only rosbridge has) in that namespace (``client_manager.py``). A node is taken for the
bridge when its last name token is ``rosbridge_websocket``, or when it publishes a
``ConnectedClients`` topic (a bridge launched under another name): :func:`bridge_topics` finds
those topics in a listing, and their publishers are the ``known`` bridges of :func:`is_bridge`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Final

from rosbridge.types import same_type

#: The node name the real rosbridge_server gives itself (any namespace).
BRIDGE_NODE_NAME: Final = "rosbridge_websocket"
#: The type of the bridge's ``connected_clients`` topic: only a rosbridge server publishes it.
CONNECTED_CLIENTS_TYPE: Final = "rosbridge_msgs/msg/ConnectedClients"
#: The rosapi service listing a topic's publishers (``rosapi_msgs/srv/Publishers``): args
#: ``{"topic": ...}``, answer ``{"publishers": [node names]}``.
PUBLISHERS_SERVICE: Final = "/rosapi/publishers"


def node_names(values: object, key: str) -> list[str] | None:
    """The node names under ``key`` (``"publishers"``, ``"subscribers"``) of a rosapi answer's
    ``values``; None if it holds no such list of strings."""
    names = values.get(key) if isinstance(values, Mapping) else None
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        return None
    return list(names)


def is_bridge(node: str, known: Iterable[str] = ()) -> bool:
    """Whether ``node`` (a full node name as rosapi gives it) is a rosbridge server: named
    ``rosbridge_websocket`` in any namespace, or one of the ``known`` bridges."""
    return node.rsplit("/", 1)[-1] == BRIDGE_NODE_NAME or node in set(known)


def others(nodes: Iterable[str], known: Iterable[str] = ()) -> list[str]:
    """``nodes`` without the bridge's (:func:`is_bridge`), in their order."""
    bridges = set(known)
    return [n for n in nodes if not is_bridge(n, bridges)]


def bridge_topics(listing: Mapping[str, str]) -> list[str]:
    """The topics of a ``/rosapi/topics`` listing (``{name: type}``) that only a rosbridge
    server publishes (``connected_clients``, in any namespace)."""
    return [name for name, kind in listing.items() if same_type(kind, CONNECTED_CLIENTS_TYPE)]
