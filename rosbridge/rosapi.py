"""The rosapi services the simulator's graph answers, as the real rosapi node does (rosbridge_suite,
ros2 branch, ``rosapi/proxy.py``): a dispatch table from the service's name to its request
fields and its answer, read from the :class:`~rosbridge.graph.Graph`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any, Final

from rosbridge.convert import populate
from rosbridge.errors import BridgeError, JsonObject, ServiceError
from rosbridge.graph import ROS_DISTRO, Graph
from rosbridge.typedefs import full_text
from vehicle_contract.messages import stamp


def call_service(graph: Graph, service: str, args: Any) -> JsonObject:
    """Call a service of the graph (``service`` already expanded) with the client's
    ``args`` (an object, a list of positional values, or anything else for none).

    Raises :class:`ServiceError` with the real server's text: no such service, bad
    arguments, or a service the simulator does not model (parameters, ``*_details``).
    """
    kinds = graph.services()
    if service not in kinds:
        raise ServiceError(f"Service {service} does not exist")
    kind = kinds[service]
    handler = _ROSAPI.get(service)
    if handler is None:
        raise ServiceError(
            f"{service} ({kind}) exists on a real vehicle but is not modelled by the "
            "NemeSys simulator"
        )
    fields, answer = handler
    request_name = kind.replace("/srv/", "/") + "_Request"
    if isinstance(args, list):
        args = dict(zip((name for name, _ in fields), args, strict=False))
    elif not isinstance(args, dict):
        args = {}
    try:
        request = populate(request_name, args, fields=fields)
    except BridgeError as exc:
        raise ServiceError(exc.reason) from None
    return answer(graph, request)


def _topics(graph: Graph, _: JsonObject) -> JsonObject:
    topics = graph.topics()
    return {"topics": list(topics), "types": list(topics.values())}


def _topics_and_raw_types(graph: Graph, _: JsonObject) -> JsonObject:
    """rosapi's answer Foxglove's rosbridge player asks for: each type's full definition."""
    topics = graph.topics()
    kinds = list(topics.values())
    return {
        "topics": list(topics),
        "types": kinds,
        "typedefs_full_text": list(map(full_text, kinds)),
    }


def _topics_for_type(graph: Graph, request: JsonObject) -> JsonObject:
    return {"topics": [t for t, kind in graph.topics().items() if kind == request["type"]]}


def _services(graph: Graph, _: JsonObject) -> JsonObject:
    return {"services": list(graph.services())}


def _services_for_type(graph: Graph, request: JsonObject) -> JsonObject:
    return {"services": [s for s, kind in graph.services().items() if kind == request["type"]]}


def _service_providers(graph: Graph, request: JsonObject) -> JsonObject:
    wanted = request["service"]
    return {
        "providers": [
            node
            for node in graph.nodes()
            if any(graph.services()[s] == wanted for s in graph.node_details(node)["services"])
        ]
    }


def _service_node(graph: Graph, request: JsonObject) -> JsonObject:
    nodes = [n for n in graph.nodes() if request["service"] in graph.node_details(n)["services"]]
    return {"node": nodes[0] if nodes else ""}


_STRING: Final = "string"
#: rosapi services answered: name -> (request fields, answer).
_ROSAPI: Final[
    Mapping[str, tuple[tuple[tuple[str, str], ...], Callable[[Graph, JsonObject], JsonObject]]]
] = MappingProxyType(
    {
        "/rosapi/topics": ((), _topics),
        "/rosapi/topics_for_type": ((("type", _STRING),), _topics_for_type),
        "/rosapi/topics_and_raw_types": ((), _topics_and_raw_types),
        "/rosapi/services": ((), _services),
        "/rosapi/services_for_type": ((("type", _STRING),), _services_for_type),
        "/rosapi/nodes": ((), lambda g, _: {"nodes": g.nodes()}),
        "/rosapi/node_details": ((("node", _STRING),), lambda g, r: g.node_details(r["node"])),
        "/rosapi/action_servers": ((), lambda g, _: {"action_servers": []}),
        "/rosapi/topic_type": (
            (("topic", _STRING),),
            lambda g, r: {"type": g.topics().get(r["topic"], "")},
        ),
        "/rosapi/service_type": (
            (("service", _STRING),),
            lambda g, r: {"type": g.services().get(r["service"], "")},
        ),
        "/rosapi/publishers": (
            (("topic", _STRING),),
            lambda g, r: {"publishers": sorted(g.publishers_by_topic().get(r["topic"], {}))},
        ),
        "/rosapi/subscribers": (
            (("topic", _STRING),),
            lambda g, r: {"subscribers": sorted(g.subscribers_by_topic().get(r["topic"], {}))},
        ),
        "/rosapi/service_providers": ((("service", _STRING),), _service_providers),
        "/rosapi/service_node": ((("service", _STRING),), _service_node),
        "/rosapi/get_time": ((), lambda g, _: {"time": stamp(g.ros_time())}),
        "/rosapi/get_ros_version": ((), lambda g, _: {"version": 2, "distro": ROS_DISTRO}),
    }
)
