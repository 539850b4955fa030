"""A simulated fleet on one rosbridge server: each vehicle's node and topics under its
namespace, and every frame topic the one shared ME link (a frame published once is heard by
every vehicle). The single-vehicle graph is unchanged. Loopback only; every wait is on a
message, bounded."""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from typing import Any

from websockets.asyncio.client import ClientConnection, connect

from codec import encode_frame
from rosbridge.client import ClientProtocol
from rosbridge.graph import BRIDGE_NODE, TRANSMITTER_NODE, Graph
from rosbridge.server import BridgeServer
from rosbridge.transport import RosbridgeClient
from sim.fleet import FleetSimulation
from station.capability import Capability, capability_of
from station.vehicle_graph import VehicleGraph, read_graph
from vehicle_contract.contract import FRAME_TOPIC, TOPIC_TYPES, VEHICLE_NODE
from vehicle_contract.fleet import parse_vehicles
from vehicle_contract.names import topic_names

NAMESPACES = ("/auv1", "/auv2", "/auv3")
FRAME_TYPE = TOPIC_TYPES[FRAME_TOPIC]
SQUARE_TO_2 = encode_frame(
    "square", {"speed": 0.2, "depth": 2.5, "side_span": 6, "direction": "ccw"}, address=2
).frame
SURFACE_ALL = encode_frame("surface", address=0).frame


def test_the_fleet_graph_lists_each_vehicles_node_and_namespaced_topics() -> None:
    graph = Graph(clock=lambda: 0.0, namespaces=NAMESPACES)
    nodes = graph.nodes()
    assert [n for n in nodes if n.endswith(VEHICLE_NODE)] == [
        "/auv1/nemesys_vehicle",
        "/auv2/nemesys_vehicle",
        "/auv3/nemesys_vehicle",
    ]
    assert TRANSMITTER_NODE in nodes and VEHICLE_NODE not in nodes
    topics = graph.topics()
    publishers, subscribers = graph.publishers_by_topic(), graph.subscribers_by_topic()
    for ns in NAMESPACES:
        names = topic_names(ns)
        node = f"{ns}{VEHICLE_NODE}"
        for name in (names.pose, names.status, names.mission):
            assert list(publishers[name]) == [node]
        assert list(subscribers[names.frame]) == [node]
        assert topics[names.pose] == "geometry_msgs/msg/PoseStamped"
        assert names.datum not in topics  # the simulator publishes no optional topic
        details = graph.node_details(node)
        assert details["subscribing"] == [names.frame]
        assert details["publishing"] == sorted(
            [names.mission, names.pose, names.status, "/parameter_events", "/rosout"]
        )
    assert list(subscribers[FRAME_TOPIC]) == [TRANSMITTER_NODE]
    assert "/nemesys/pose" not in topics
    assert graph.frame_topics == {FRAME_TOPIC, *(topic_names(ns).frame for ns in NAMESPACES)}


def test_the_single_vehicle_graph_is_unchanged() -> None:
    graph = Graph(clock=lambda: 0.0)
    assert graph.nodes() == sorted([BRIDGE_NODE, "/rosapi", "/rosapi_params", VEHICLE_NODE])
    assert graph.frame_topics == {FRAME_TOPIC}
    assert list(graph.subscribers_by_topic()[FRAME_TOPIC]) == [VEHICLE_NODE]
    assert not any(t.startswith("/auv") for t in graph.topics())


# --- the server ------------------------------------------------------------------------------


@asynccontextmanager
async def fleet_server() -> AsyncIterator[tuple[BridgeServer, FleetSimulation]]:
    fleet = FleetSimulation(parse_vehicles("3"))
    server = BridgeServer(fleet, "127.0.0.1", 0)
    await server.start()
    try:
        yield server, fleet
    finally:
        await server.stop()


async def send(ws: ClientConnection, message: dict[str, Any]) -> None:
    await ws.send(json.dumps(message))


async def receive(
    ws: ClientConnection, want: Callable[[dict[str, Any]], bool], timeout: float = 5.0
) -> dict[str, Any]:
    """The first message satisfying ``want`` (others are skipped)."""
    async with asyncio.timeout(timeout):
        while True:
            message: dict[str, Any] = json.loads(await ws.recv())
            if want(message):
                return message


async def service(ws: ClientConnection, name: str, **args: Any) -> dict[str, Any]:
    await send(ws, {"op": "call_service", "id": name, "service": name, "args": args})
    reply = await receive(ws, lambda m: m.get("op") == "service_response" and m["id"] == name)
    assert reply["result"] is True
    values: dict[str, Any] = reply["values"]
    return values


async def acks_of_each(ws: ClientConnection, count: int) -> dict[str, list[dict[str, Any]]]:
    """``count`` acknowledgements on each vehicle's mission topic (subscribed before)."""
    missions = {topic_names(ns).mission: ns for ns in NAMESPACES}
    got: dict[str, list[dict[str, Any]]] = {ns: [] for ns in NAMESPACES}
    while any(len(a) < count for a in got.values()):
        m = await receive(ws, lambda m: m.get("op") == "publish" and m["topic"] in missions)
        got[missions[m["topic"]]].append(json.loads(m["msg"]["data"]))
    return got


def test_one_server_serves_every_vehicle_and_a_frame_is_heard_by_all() -> None:
    async def scenario() -> None:
        async with (
            fleet_server() as (server, fleet),
            connect(f"ws://127.0.0.1:{server.port}") as ws,
        ):
            nodes = (await service(ws, "/rosapi/nodes"))["nodes"]
            assert {f"{ns}{VEHICLE_NODE}" for ns in NAMESPACES} <= set(nodes)
            topics = (await service(ws, "/rosapi/topics"))["topics"]
            for ns in NAMESPACES:
                names = topic_names(ns)
                assert {names.frame, names.pose, names.mission, names.status} <= set(topics)
            for ns in NAMESPACES:
                await send(ws, {"op": "subscribe", "topic": topic_names(ns).mission})
            await service(ws, "/rosapi/topics")  # the subscriptions are in before the frame
            # the station's transmitter: one frame, every vehicle's agent answers it
            await send(ws, {"op": "advertise", "topic": FRAME_TOPIC, "type": FRAME_TYPE})
            data = list(SQUARE_TO_2.to_bytes())
            await send(ws, {"op": "publish", "topic": FRAME_TOPIC, "msg": {"data": data}})
            acks = await acks_of_each(ws, 1)
            assert [(a[0]["outcome"], a[0]["reason"]) for a in acks.values()] == [
                ("rejected", "other_vehicle"),
                ("accepted", None),
                ("rejected", "other_vehicle"),
            ]
            assert fleet.transmissions == 1
            # a vehicle's own frame topic is the same link: Surface all there surfaces all
            auv3 = topic_names("auv3").frame
            await send(ws, {"op": "advertise", "topic": auv3, "type": FRAME_TYPE})
            data = list(SURFACE_ALL.to_bytes())
            await send(ws, {"op": "publish", "topic": auv3, "msg": {"data": data}})
            acks = await acks_of_each(ws, 1)
            assert all(a[0]["outcome"] == "accepted" for a in acks.values())
            assert all(a[0]["active"]["pattern"] == "surface" for a in acks.values())
            assert fleet.transmissions == 2
            # each vehicle's status under its namespace says which vehicle it is
            await send(ws, {"op": "subscribe", "topic": topic_names("auv2").status})
            status = await receive(
                ws,
                lambda m: m.get("op") == "publish" and m["topic"] == "/auv2/nemesys/status",
            )
            assert json.loads(status["msg"]["data"])["address"] == 2

    asyncio.run(asyncio.wait_for(scenario(), 20.0))


def test_the_consoles_graph_rule_finds_each_vehicles_agent() -> None:
    """What a console's link per vehicle (``RosbridgeLink(namespace="auv2")``) judges."""

    async def scenario() -> list[Capability]:
        async with fleet_server() as (server, _):
            client = await RosbridgeClient.connect(
                f"ws://127.0.0.1:{server.port}", ClientProtocol([], [])
            )
            try:
                await client.open()
                out = []
                for ns in NAMESPACES:
                    graph = await read_graph(client, 3.0, names=topic_names(ns).by_topic())
                    assert isinstance(graph, VehicleGraph)
                    assert graph.vehicle_nodes("/nemesys/mission") == [f"{ns}{VEHICLE_NODE}"]
                    capability, problems = capability_of(graph)
                    assert problems == []
                    out.append(capability)
                return out
            finally:
                await client.close()

    capabilities = asyncio.run(asyncio.wait_for(scenario(), 20.0))
    assert capabilities == [Capability.ACKS_AND_TELEMETRY] * 3
