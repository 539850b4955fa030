"""A vehicle under a ROS namespace (``/auv1/nemesys/...``, several vehicles in one graph): the
console's link and the station's transmitter name every topic from the contract's one
function, and the graph rule finds the vehicle's node (``/auv1/nemesys_vehicle``) by the
namespaced topics it publishes and subscribes, whatever it is called."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator, Mapping
from typing import Any

import pytest

from codec import encode_frame
from rosbridge.client import ClientProtocol
from rosbridge.transport import RosbridgeClient
from station.link import Capability, RosbridgeLink, capability_of
from station.link_modem import open_link
from station.transmit import RosbridgeTransmitter, open_transmitter
from station.vehicle_graph import GraphUnknown, VehicleGraph, read_graph
from tests.backend.conftest import wait_until
from tests.fake_vehicle import AGENT, FRAME_TYPE, GraphNode, Rosbridge
from vehicle_contract.names import topic_names

NAMES = topic_names("auv1")
#: The reference node launched under /auv1: its node and every contract topic in it.
AUV1 = GraphNode(
    "/auv1/nemesys_vehicle",
    {f"/auv1{name}": kind for name, kind in AGENT.publishes.items()},
    {NAMES.frame: FRAME_TYPE},
    best_effort=frozenset({NAMES.pose}),
)
FRAME = encode_frame("circle", speed=0.2, depth=2, radius=3, direction="cw").frame


@pytest.fixture
def auv1() -> Iterator[Rosbridge]:
    bridge = Rosbridge((AUV1,)).start()
    try:
        yield bridge
    finally:
        bridge.stop()


def _by_op(bridge: Rosbridge, op: str) -> dict[str, Any]:
    """topic -> type (or message) of every ``op`` the bridge received."""
    received = list(bridge.received)
    return {m["topic"]: m.get("type", m) for m in received if "topic" in m and m.get("op") == op}


def _graph(url: str, names: Mapping[str, str]) -> VehicleGraph | GraphUnknown:
    async def ask() -> VehicleGraph | GraphUnknown:
        client = await RosbridgeClient.connect(url, ClientProtocol([], []))
        try:
            await client.open()
            return await read_graph(client, 2.0, names=names)
        finally:
            await client.close()

    return asyncio.run(ask())


def test_capability_is_judged_on_the_namespaced_topics() -> None:
    """Two vehicles in one graph, /auv1 and one without a namespace: each is found by its
    own topics' publishers and subscriber."""
    fleet = Rosbridge((AUV1, AGENT)).start()
    try:
        ours = _graph(fleet.url, NAMES.by_topic())
        default = _graph(fleet.url, topic_names().by_topic())
    finally:
        fleet.stop()
    assert isinstance(ours, VehicleGraph) and isinstance(default, VehicleGraph)
    assert capability_of(ours) == (Capability.ACKS_AND_TELEMETRY, [])
    assert ours.vehicle_nodes("/nemesys/mission") == ["/auv1/nemesys_vehicle"]
    assert ours.vehicle_nodes("/nemesys/frame") == ["/auv1/nemesys_vehicle"]
    assert default.vehicle_nodes("/nemesys/mission") == ["/nemesys_vehicle"]

    alone = Rosbridge((AUV1,)).start()  # asked at the default names: another vehicle's
    try:
        elsewhere = _graph(alone.url, topic_names().by_topic())
    finally:
        alone.stop()
    assert isinstance(elsewhere, VehicleGraph)
    capability, problems = capability_of(elsewhere)
    assert capability is Capability.NONE
    assert problems[0].startswith("no onboard agent (no /nemesys/mission topic")


def test_the_link_names_every_topic_under_the_namespace(auv1: Rosbridge) -> None:
    link = open_link(auv1.url, 36000.0, namespace="auv1")
    assert isinstance(link, RosbridgeLink)

    async def run() -> tuple[str | None, Capability]:
        await link.start()
        try:
            assert await link.wait_connected(10.0)
            return await link.transmit(FRAME), link.capability
        finally:
            await link.stop()

    assert asyncio.run(run()) == (None, Capability.ACKS_AND_TELEMETRY)
    assert link.names == NAMES
    wait_until(lambda: "publish" in auv1.ops(), what="the frame's publish")
    assert _by_op(auv1, "advertise") == {NAMES.frame: "std_msgs/UInt8MultiArray"}
    assert _by_op(auv1, "subscribe") == {
        NAMES.pose: "geometry_msgs/PoseStamped",
        NAMES.status: "std_msgs/String",
        NAMES.mission: "std_msgs/String",
        NAMES.datum: "std_msgs/String",
    }
    assert list(_by_op(auv1, "publish")) == [NAMES.frame]
    assert not any(m.get("topic", "").startswith("/nemesys/") for m in auv1.received)


def test_the_transmitter_names_its_topics_under_the_namespace(auv1: Rosbridge) -> None:
    opened = open_transmitter(auv1.url, namespace="/auv1/")
    assert isinstance(opened, RosbridgeTransmitter) and opened.names == NAMES
    tx = RosbridgeTransmitter(auv1.url, namespace="auv1", subscriber_wait_s=0.0)
    try:
        result = tx.send(FRAME, wait_ack_s=0.0)
    finally:
        tx.close()
    assert result.sent, result
    assert _by_op(auv1, "advertise") == {NAMES.frame: "std_msgs/UInt8MultiArray"}
    assert _by_op(auv1, "subscribe") == {NAMES.mission: "std_msgs/String"}
    assert list(_by_op(auv1, "publish")) == [NAMES.frame]


def test_a_bad_namespace_is_refused_naming_the_rule() -> None:
    with pytest.raises(ValueError, match="letter or an underscore"):
        open_transmitter("ws://127.0.0.1:9", namespace="auv-1")
    with pytest.raises(ValueError, match="letter or an underscore"):
        RosbridgeLink("ws://127.0.0.1:9", namespace="1auv")


@pytest.mark.slow  # vehicle-check's real listening window
def test_vehicle_check_finds_the_namespaced_node_by_its_topics(
    auv1: Rosbridge, capsys: pytest.CaptureFixture[str]
) -> None:
    from tests.station.test_vehicle_check import rows, run

    fast = ["--window", "1", "--timeout", "1"]
    status, out, _ = run(["vehicle-check", auv1.url, "--namespace", "auv1", *fast], capsys)
    table = rows(out)
    assert table["topic /auv1/nemesys/mission"] == (
        "pass",
        "std_msgs/msg/String, published by /auv1/nemesys_vehicle",
    )
    assert table["topic /auv1/nemesys/frame"][1].endswith("subscribed by /auv1/nemesys_vehicle")
    result, reason = table["onboard agent"]
    assert result == "pass" and reason.startswith(
        "running: /auv1/nemesys_vehicle publishes /auv1/nemesys/mission and /auv1/nemesys/status"
    )
    # the stand-in has no agent to answer: the probe went to the namespaced frame topic
    assert "published on /auv1/nemesys/frame: no acknowledgement" in table["ack path (probe)"][1]
    assert list(_by_op(auv1, "publish")) == [NAMES.frame]
    assert status == 1

    status, out, _ = run(["vehicle-check", auv1.url, *fast], capsys)  # without the namespace
    result, reason = rows(out)["onboard agent"]
    assert status == 1 and result == "fail"
    # vehicle-check's own subscription made /nemesys/mission exist: nobody else publishes it
    assert reason.startswith("no onboard agent (no node publishes /nemesys/mission;")

    status, _, err = run(["vehicle-check", auv1.url, "--namespace", "auv-1"], capsys)
    assert status == 2 and "--namespace: vehicle namespace 'auv-1'" in err
