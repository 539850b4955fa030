"""A vehicle under a ROS namespace (``/auv1/nemesys/...``, several vehicles in one graph): the
console's link and the station's transmitter name every topic from the contract's one
function, and judge the capability from the namespaced topics."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from typing import Any

import pytest

from codec import encode_frame
from station.link import Capability, RosbridgeLink, capability_of
from station.link_modem import open_link
from station.transmit import RosbridgeTransmitter, open_transmitter
from tests.backend.conftest import wait_until
from tests.fake_vehicle import WITH_AGENT, Rosbridge
from vehicle_contract.contract import topic_names

NAMES = topic_names("auv1")
#: What /rosapi/topics lists on a graph whose NemeSys vehicle runs under /auv1.
UNDER_AUV1 = {
    (f"/auv1{name}" if name.startswith("/nemesys/") else name): kind
    for name, kind in WITH_AGENT.items()
}
FRAME = encode_frame("circle", speed=0.2, depth=2, radius=3, direction="cw").frame


@pytest.fixture
def auv1() -> Iterator[Rosbridge]:
    bridge = Rosbridge(UNDER_AUV1).start()
    try:
        yield bridge
    finally:
        bridge.stop()


def _by_op(bridge: Rosbridge, op: str) -> dict[str, Any]:
    """topic -> type (or message) of every ``op`` the bridge received."""
    received = list(bridge.received)
    return {m["topic"]: m.get("type", m) for m in received if m.get("op") == op}


def test_capability_is_judged_on_the_namespaced_topics() -> None:
    assert capability_of(UNDER_AUV1, NAMES) == (Capability.ACKS_AND_TELEMETRY, [])
    capability, problems = capability_of(WITH_AGENT, NAMES)  # another vehicle's topics
    assert capability is Capability.NONE
    assert problems[0].startswith("no /auv1/nemesys/mission topic")
    assert any("no /auv1/nemesys/pose topic" in p for p in problems)
    assert capability_of(WITH_AGENT)[0] is Capability.ACKS_AND_TELEMETRY  # no namespace


def test_the_link_names_every_topic_under_the_namespace(auv1: Rosbridge) -> None:
    link = open_link(auv1.url, 36000.0, namespace="auv1")
    assert isinstance(link, RosbridgeLink)

    async def run() -> str | None:
        await link.start()
        try:
            assert await link.wait_connected(10.0)
            return await link.transmit(FRAME)
        finally:
            await link.stop()

    assert asyncio.run(run()) is None
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
