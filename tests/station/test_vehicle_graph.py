"""The one rule the console and ``vehicle-check`` read a vehicle's ROS graph with
(:func:`station.vehicle_graph.verdict_of`, through :func:`station.link.capability_of`):
rosbridge's own node, which publishes and subscribes for its clients, is never the vehicle."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator

import pytest

from rosbridge.client import ClientProtocol
from rosbridge.server import BridgeServer
from rosbridge.transport import RosbridgeClient
from sim.simulation import Simulation
from station.link import Capability, capability_of
from station.vehicle_graph import GraphUnknown, VehicleGraph, read_graph, verdict_of
from tests.fake_vehicle import FRAME_TYPE, STRING_TYPE, WITH_AGENT, Rosbridge, observer
from tests.rosbridge.helpers import LoopThread

FRAME, POSE, MISSION, STATUS, DATUM = (
    "/nemesys/frame",
    "/nemesys/pose",
    "/nemesys/mission",
    "/nemesys/status",
    "/nemesys/datum",
)
TYPES = {
    FRAME: "std_msgs/msg/UInt8MultiArray",
    POSE: "geometry_msgs/msg/PoseStamped",
    MISSION: "std_msgs/msg/String",
    STATUS: "std_msgs/msg/String",
    DATUM: "std_msgs/msg/String",
}
BRIDGE = "/rosbridge_websocket"
VEHICLE = "/nemesys_vehicle"


def graph(
    publishers: dict[str, tuple[str, ...]],
    subscribers: tuple[str, ...],
    *,
    types: dict[str, str] | None = None,
    bridges: frozenset[str] = frozenset(),
) -> VehicleGraph:
    """A graph whose listing has every topic someone is at either end of (the bridge
    subscribes to pose, status and mission for the console, as it does on a real vehicle)."""
    listed = {
        FRAME: TYPES[FRAME],
        POSE: TYPES[POSE],
        MISSION: TYPES[MISSION],
        STATUS: TYPES[STATUS],
    }
    listed.update(types or {})
    pubs = {t: publishers.get(t, ()) for t in (POSE, STATUS, MISSION)}
    return VehicleGraph(listed, pubs, {FRAME: subscribers}, bridges)


def test_a_vehicle_running_the_agent_acknowledges() -> None:
    g = graph({POSE: (VEHICLE,), STATUS: (VEHICLE,), MISSION: (VEHICLE,)}, (BRIDGE, VEHICLE))
    verdict = verdict_of(g)
    assert verdict.agent and verdict.frames and verdict.pose and verdict.status
    assert verdict.problems == ()
    assert capability_of(g) == (Capability.ACKS_AND_TELEMETRY, [])
    assert verdict.findings[MISSION].reason == f"std_msgs/msg/String, published by {VEHICLE}"
    assert verdict.findings[FRAME].reason.endswith(f"subscribed by {VEHICLE}")  # not the bridge


def test_topics_that_only_the_bridge_uses_are_not_the_vehicles() -> None:
    """The bug of issue 21: an observer's subscriptions made every topic exist."""
    g = graph({POSE: ("/navigation",), MISSION: (BRIDGE,)}, (BRIDGE,))
    verdict = verdict_of(g)
    assert not verdict.agent and not verdict.frames and verdict.pose
    capability, problems = capability_of(g)
    assert capability is Capability.TELEMETRY_ONLY
    assert problems[0] == (
        "no onboard agent (only rosbridge publishes /nemesys/mission; no node publishes "
        "/nemesys/status): commands are sent as repeated copies without acknowledgement"
    )
    assert verdict.findings[STATUS].reason == (
        "no node publishes /nemesys/status (it exists because something subscribes to it, such "
        "as rosbridge for its clients)"
    )
    assert problems[1].startswith(
        f"/nemesys/frame has no subscriber but rosbridge's own node ({BRIDGE})"
    )


def test_the_bridge_is_known_in_any_namespace_and_by_its_clients_topic() -> None:
    for bridge, known in (("/boat1/rosbridge_websocket", frozenset()), ("/b", frozenset({"/b"}))):
        g = graph(
            {POSE: (VEHICLE,), STATUS: (bridge,), MISSION: (bridge,)}, (bridge,), bridges=known
        )
        assert capability_of(g)[0] is Capability.TELEMETRY_ONLY, bridge
    # a node merely named like it elsewhere in its name is not the bridge
    g = graph(
        {STATUS: ("/rosbridge_websocket_fan",), MISSION: ("/rosbridge_websocket_fan",)}, (VEHICLE,)
    )
    assert verdict_of(g).agent


def test_the_agent_needs_both_its_topics_with_the_contract_types() -> None:
    only_mission = graph({MISSION: (VEHICLE,)}, (VEHICLE,))
    assert not verdict_of(only_mission).agent
    assert capability_of(only_mission)[0] is Capability.NONE  # no pose, no status either
    wrong = graph(
        {STATUS: (VEHICLE,), MISSION: (VEHICLE,)}, (VEHICLE,), types={MISSION: "std_msgs/msg/Int32"}
    )
    verdict = verdict_of(wrong)
    assert not verdict.agent
    assert verdict.findings[MISSION].reason == (
        "/nemesys/mission is a std_msgs/msg/Int32, not a std_msgs/String: it is ignored"
    )
    ros1 = graph(
        {STATUS: (VEHICLE,), MISSION: (VEHICLE,)}, (VEHICLE,), types={MISSION: "std_msgs/String"}
    )
    assert verdict_of(ros1).agent  # either spelling


def test_a_receiver_only_vehicle_needs_its_frames_another_way() -> None:
    g = graph({POSE: (VEHICLE,), STATUS: (VEHICLE,), MISSION: (VEHICLE,)}, ())
    verdict = verdict_of(g)
    assert verdict.receiver_only
    capability, problems = capability_of(g)
    assert capability is Capability.TELEMETRY_ONLY
    assert problems[0].startswith("receiver-only: ")
    # frames through a modem, acknowledgements over rosbridge: no problem left
    assert capability_of(g, frames_over_rosbridge=False) == (Capability.ACKS_AND_TELEMETRY, [])


def test_the_optional_datum_counts_only_when_a_node_publishes_it() -> None:
    """The console subscribes to the datum, so rosbridge's own subscription lists it on a
    vehicle that has none: no finding then; one published with the wrong type is named."""
    agent = {POSE: (VEHICLE,), STATUS: (VEHICLE,), MISSION: (VEHICLE,)}
    listed_by_the_bridge = graph({**agent, DATUM: ()}, (VEHICLE,), types={DATUM: TYPES[DATUM]})
    assert DATUM not in verdict_of(listed_by_the_bridge).findings
    assert capability_of(listed_by_the_bridge) == (Capability.ACKS_AND_TELEMETRY, [])
    published = VehicleGraph(
        {**TYPES}, {**agent, DATUM: (BRIDGE, VEHICLE)}, {FRAME: (VEHICLE,)}, frozenset()
    )
    assert verdict_of(published).findings[DATUM].reason == (
        f"std_msgs/msg/String, published by {VEHICLE}"
    )
    wrong = VehicleGraph(
        {**TYPES, DATUM: "std_msgs/msg/Int32"},
        {**agent, DATUM: (VEHICLE,)},
        {FRAME: (VEHICLE,)},
        frozenset(),
    )
    assert not verdict_of(wrong).findings[DATUM].ok
    assert verdict_of(wrong).agent  # optional: named, not the agent's


def test_a_topic_nobody_lists_is_named_missing() -> None:
    g = VehicleGraph({POSE: TYPES[POSE]}, {POSE: (VEHICLE,)}, {}, frozenset())
    verdict = verdict_of(g)
    assert verdict.findings[MISSION].reason == "no /nemesys/mission topic: no node publishes it"
    assert verdict.findings[FRAME].reason == "no /nemesys/frame topic: no node subscribes to it"
    assert capability_of(g)[0] is Capability.TELEMETRY_ONLY


# --- asked over the wire ----------------------------------------------------------------------


async def _ask(url: str) -> VehicleGraph | GraphUnknown:
    """The graph as the console's link asks it, subscribed to what the console subscribes."""
    listen = ClientProtocol(advertise=[FRAME], subscribe=[POSE, STATUS, MISSION])
    client = await RosbridgeClient.connect(url, listen)
    try:
        await client.open()
        return await read_graph(client, 2.0)
    finally:
        await client.close()


@pytest.fixture
def training() -> Iterator[str]:
    """The console's own training bridge (the simulator behind rosbridge/server.py)."""
    loop = LoopThread()
    loop.start()
    server = BridgeServer(Simulation(), "127.0.0.1", 0)
    loop.run(server.start())
    try:
        yield f"ws://127.0.0.1:{server.port}"
    finally:
        loop.run(server.stop())
        loop.stop()


def test_the_training_bridge_answers_the_graph_as_a_real_one_does(training: str) -> None:
    """rosbridge/server.py and the stand-in for a real rosbridge_server (tests/fake_vehicle.py,
    written from rosbridge_suite apart from it) give the same answers for the same vehicle,
    with an observer subscribed to the frame and mission topics."""
    real = Rosbridge(WITH_AGENT).start()
    try:
        answers = []
        for url in (training, real.url):
            with observer(url, {FRAME: FRAME_TYPE, MISSION: STRING_TYPE}):
                answers.append(asyncio.run(_ask(url)))
    finally:
        real.stop()
    ours, theirs = answers
    assert isinstance(ours, VehicleGraph) and isinstance(theirs, VehicleGraph)
    assert (
        ours.publishers
        == theirs.publishers
        == {
            POSE: (VEHICLE,),
            STATUS: (VEHICLE,),
            MISSION: (VEHICLE,),
            DATUM: (),  # the optional datum: asked about, published by nobody
        }
    )
    assert ours.subscribers == theirs.subscribers == {FRAME: (VEHICLE, BRIDGE)}
    assert ours.bridges == theirs.bridges == frozenset({BRIDGE})
    for topic in (FRAME, POSE, STATUS, MISSION):
        assert ours.topics[topic] == theirs.topics[topic] == TYPES[topic]
    assert capability_of(ours) == capability_of(theirs) == (Capability.ACKS_AND_TELEMETRY, [])
