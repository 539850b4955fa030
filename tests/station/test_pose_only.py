"""A ROS 2 vehicle without the NemeSys onboard agent: a rosbridge-like server that behaves like
a real rosbridge_server in front of a ROS 2 graph (:mod:`tests.fake_vehicle`: a topic exists
while anyone uses it, rosbridge's node subscribes for its clients; rosapi types in ROS 2
spelling, NaN floats as ``null``, ROS time stamps far from the station's clock).

The console detects it as ``telemetry_only``, even when an observer subscribed to the frame and
mission topics first (they exist then, through rosbridge's own node): commands go out as copies
and end ``sent``; unknown pose numbers are shown as unknown and counted; the telemetry age is
the arrival age; the agent starting later, or a reconnect to a vehicle that runs it, is
detected; a pose publisher that starts after the console subscribed is heard (the console
subscribes again)."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Iterator
from typing import Any

import pytest
from fastapi.testclient import TestClient

from codec import encode_frame
from station.link import Capability, RosbridgeLink
from tests.backend.conftest import CIRCLE, MakeClient, send, wait_state, wait_until
from tests.fake_vehicle import (
    FRAME,
    FRAME_TYPE,
    MISSION,
    POSE,
    POSE_ONLY,
    RECEIVER_ONLY,
    ROS_EPOCH_S,
    STRING_TYPE,
    WITH_AGENT,
    GraphNode,
    Rosbridge,
    observer,
)


@pytest.fixture
def pose_only() -> Iterator[Rosbridge]:
    bridge = Rosbridge(POSE_ONLY).start()
    try:
        yield bridge
    finally:
        bridge.stop()


def link_of(client: TestClient) -> dict[str, Any]:
    r = client.get("/api/vehicle")
    assert r.status_code == 200, r.text
    link: dict[str, Any] = r.json()["link"]
    return link


def wait_capability(client: TestClient, capability: str, timeout_s: float = 10.0) -> None:
    wait_until(
        lambda: link_of(client)["capability"] == capability,
        timeout_s,
        what=f"capability {capability}",
    )


def test_a_vehicle_without_the_agent_is_telemetry_only(
    make_client: MakeClient, pose_only: Rosbridge
) -> None:
    client = make_client(target=pose_only.url, link_ber=1e-2, copy_interval_s=0.05)
    wait_capability(client, "telemetry_only")
    link = link_of(client)
    assert link["connected"] is True
    assert link["acknowledges"] is False and link["telemetry"] is True
    agent = [p for p in link["problems"] if "no onboard agent" in p]
    assert agent and "/nemesys/mission" in agent[0], link["problems"]
    assert link["copies"] == 3  # chosen from link_ber 1e-2 for the 0.999 target
    assert client.get("/api/session").json()["link"] == {
        "capability": "telemetry_only",
        "acknowledges": False,
        "telemetry": True,
    }
    # the console asked rosapi, advertised the frame topic, subscribed to the pose
    ops = pose_only.ops()
    assert "call_service" in ops and "advertise" in ops and "subscribe" in ops

    cmd = send(client, "circle", CIRCLE)
    assert cmd["copies"] == 3 and cmd["two_way"] is False
    rec = wait_state(client, cmd["id"])
    assert rec["state"] == "sent", rec  # not timed_out: no acknowledgement is expected
    assert rec["copies_sent"] == rec["attempts"] == 3
    wait_until(lambda: pose_only.frame_count() >= 3, what="three frames at the vehicle")
    expected = bytes.fromhex(rec["hex"] + "0")  # 100 bits + 4 zero padding bits
    assert pose_only.frames == [expected] * 3
    frames = link_of(client)["frames"]["dive"]
    assert frames["frames"] == frames["sent"] == 3 and frames["timed_out"] == 0


def test_an_observer_does_not_make_a_pose_only_vehicle_look_complete(
    make_client: MakeClient, pose_only: Rosbridge
) -> None:
    """The frame and mission topics exist (rosbridge subscribes to them for the observer),
    but nothing of the vehicle's is at their ends: no agent, so copies that end sent."""
    with observer(pose_only.url, {FRAME: FRAME_TYPE, MISSION: STRING_TYPE}):
        client = make_client(target=pose_only.url, link_ber=1e-2, copy_interval_s=0.05)
        wait_capability(client, "telemetry_only")
        link = link_of(client)
        assert link["acknowledges"] is False
        problems = " | ".join(link["problems"])
        assert "no onboard agent" in problems and "/rosbridge_websocket" in problems, problems
        assert "/nemesys/frame has no subscriber but rosbridge's own node" in problems

        cmd = send(client, "circle", CIRCLE)
        assert cmd["two_way"] is False and cmd["copies"] == 3
        rec = wait_state(client, cmd["id"])
        assert rec["state"] == "sent" and rec["copies_sent"] == rec["attempts"] == 3, rec
        wait_until(lambda: pose_only.frame_count() >= 3, what="three frames at the vehicle")
        assert link_of(client)["capability"] == "telemetry_only"


def test_the_agent_starting_while_connected_is_detected(make_client: MakeClient) -> None:
    """The graph is asked again while connected: no reconnect is needed."""
    vehicle = Rosbridge(POSE_ONLY).start()
    try:
        client = make_client(target=vehicle.url)
        wait_capability(client, "telemetry_only")
        vehicle.set_nodes(WITH_AGENT)
        wait_capability(client, "acks_and_telemetry")
        assert vehicle.connections == 1
        vehicle.set_nodes(POSE_ONLY)
        wait_capability(client, "telemetry_only")
        assert vehicle.connections == 1
    finally:
        vehicle.stop()


def test_a_pose_publisher_that_starts_later_is_heard(make_client: MakeClient) -> None:
    """rosbridge made the console's pose subscription RELIABLE (no publisher was there), which
    does not hear the best-effort pose: once the publisher appears the console subscribes
    again, and the new subscription is best-effort."""
    vehicle = Rosbridge(()).start()
    try:
        client = make_client(target=vehicle.url)
        wait_capability(client, "none")
        assert vehicle.subscriptions(POSE) == 1
        vehicle.set_nodes(POSE_ONLY)
        wait_until(lambda: client.get("/api/vehicle").json()["pose"] is not None, what="a pose")
        assert vehicle.subscriptions(POSE) == 2 and vehicle.poses_sent > 0
        wait_capability(client, "telemetry_only")
        assert vehicle.connections == 1
        ops = [m for m in vehicle.received if m.get("topic") == POSE]
        assert [m["op"] for m in ops] == ["subscribe", "unsubscribe", "subscribe"]
        assert ops[0]["id"] == ops[1]["id"] == ops[2]["id"]
    finally:
        vehicle.stop()


def test_a_datum_publisher_that_starts_later_is_subscribed_again() -> None:
    """The datum is optional: on a vehicle without it the console's subscription is there
    (and lists the topic) with nothing to hear and no problem named; once a node publishes it
    the link subscribes again (rosbridge made the first subscription with no publisher), and
    the datum reaches the console. Nothing else is subscribed again."""
    datum_topic = "/nemesys/datum"
    vehicle = Rosbridge(WITH_AGENT).start()
    (agent,) = WITH_AGENT
    with_datum = GraphNode(
        agent.name,
        {**agent.publishes, datum_topic: STRING_TYPE},
        agent.subscribes,
        agent.best_effort,
    )
    heard: list[dict[str, Any]] = []

    def polls() -> int:
        """How many times the link asked /rosapi/topics."""
        received = list(vehicle.received)
        return sum(m.get("service") == "/rosapi/topics" for m in received)

    async def run() -> tuple[Capability, list[str]]:
        link = RosbridgeLink(vehicle.url, graph_poll_s=0.1)
        link.on_datum = heard.append
        await link.start()
        try:
            assert await link.wait_connected(5.0)
            assert link.capability_problems == []
            deadline = time.monotonic() + 10.0
            while vehicle.subscriptions(datum_topic) < 1:
                assert time.monotonic() < deadline, "the datum was not subscribed"
                await asyncio.sleep(0.02)
            # two more readings of the graph with no datum publisher: no new subscription
            asked = polls() + 2
            while polls() < asked:
                assert time.monotonic() < deadline, "the graph was not asked again"
                await asyncio.sleep(0.02)
            assert vehicle.subscriptions(datum_topic) == 1
            assert link.capability_problems == []
            await asyncio.to_thread(vehicle.set_nodes, (with_datum,))
            while vehicle.subscriptions(datum_topic) < 2:
                assert time.monotonic() < deadline, "the datum was not subscribed again"
                await asyncio.sleep(0.02)
            body = {"data": '{"lat_deg": 43.1, "lon_deg": 5.9, "source": "fix"}'}
            await asyncio.to_thread(vehicle.publish, datum_topic, body)
            while not heard:
                assert time.monotonic() < deadline, "the datum did not reach the console"
                await asyncio.sleep(0.02)
            return link.capability, list(link.capability_problems)
        finally:
            await link.stop()

    try:
        capability, problems = asyncio.run(run())
    finally:
        vehicle.stop()
    assert capability is Capability.ACKS_AND_TELEMETRY and problems == []
    assert heard == [{"lat_deg": 43.1, "lon_deg": 5.9, "source": "fix"}]
    assert vehicle.subscriptions(POSE) == vehicle.subscriptions(MISSION) == 1


@pytest.mark.slow  # a rosbridge vehicle on loopback
def test_null_pose_numbers_are_unknown_and_counted(
    make_client: MakeClient, pose_only: Rosbridge
) -> None:
    client = make_client(target=pose_only.url)
    wait_capability(client, "telemetry_only")

    def vehicle() -> dict[str, Any]:
        r = client.get("/api/vehicle")
        assert r.status_code == 200, r.text
        body: dict[str, Any] = r.json()
        return body

    unknown = wait_until(
        lambda: (v := vehicle())["pose"] is not None and v["pose"]["x_m"] is None and v,
        what="a pose with an unknown position",
    )
    pose = unknown["pose"]
    assert pose["heading_deg"] is None and pose["roll_deg"] is None
    assert pose["y_m"] == 2.0 and pose["z_m"] == 3.0
    known = wait_until(
        lambda: (v := vehicle())["pose"] is not None and v["pose"]["x_m"] is not None and v,
        what="a pose with a known position",
    )
    assert known["pose"]["heading_deg"] == pytest.approx(30.0)
    # the vehicle's ROS time is ~1000 s; the age is measured from the arrival
    assert known["pose"]["t_s"] == pytest.approx(ROS_EPOCH_S, abs=60)
    link = known["link"]
    assert link["unknown_values"] > 0
    assert any("telemetry number" in p and "unknown" in p for p in link["problems"]), link
    assert link["last_telemetry_age_s"] is not None and 0 <= link["last_telemetry_age_s"] < 1.0
    assert known["age_s"] is not None and known["age_s"] < 1.0
    assert link["level"] == "amber"
    # it keeps serving while the nulls keep coming
    for _ in range(5):
        assert client.get("/api/vehicle").status_code == 200
        assert client.get("/api/session").status_code == 200
    assert pose_only.poses_sent >= 3


def test_a_reconnect_redetects_the_capability(make_client: MakeClient) -> None:
    first = Rosbridge(POSE_ONLY).start()
    port = first.port
    client = make_client(target=first.url)
    bridges = [first]
    try:
        wait_capability(client, "telemetry_only")
        first.stop()
        bridges.remove(first)
        wait_until(lambda: not link_of(client)["connected"], what="the link noticing the close")
        assert link_of(client)["capability"] == "unknown"

        agent = Rosbridge(WITH_AGENT, port=port).start()
        bridges.append(agent)
        wait_capability(client, "acks_and_telemetry")
        link = link_of(client)
        assert link["acknowledges"] is True
        assert not any("/nemesys/mission" in p for p in link["problems"]), link["problems"]
        assert agent.connections == 1
        # every connection subscribes afresh
        assert agent.subscriptions(POSE) == agent.subscriptions(MISSION) == 1

        agent.stop()
        bridges.remove(agent)
        again = Rosbridge(POSE_ONLY, port=port).start()
        bridges.append(again)
        wait_capability(client, "telemetry_only")
        assert link_of(client)["acknowledges"] is False
    finally:
        for bridge in bridges:
            bridge.stop()


@pytest.mark.slow  # the link's real rosapi timeout
def test_rosapi_that_never_answers_is_unknown_naming_rosapi() -> None:
    silent = Rosbridge(POSE_ONLY, rosapi=False).start()

    async def run() -> tuple[bool, float, Capability, list[str], bool, bool]:
        link = RosbridgeLink(silent.url, rosapi_timeout_s=0.5)
        began = time.monotonic()
        await link.start()
        try:
            ready = await link.wait_connected(5.0)
            took_s = time.monotonic() - began
            # read while connected: a closed link starts again from unknown, no problems
            return (
                ready,
                took_s,
                link.capability,
                list(link.capability_problems),
                link.acknowledges,
                link.telemetry,
            )
        finally:
            await link.stop()

    try:
        ready, took_s, capability, problems, acknowledges, telemetry = asyncio.run(run())
    finally:
        silent.stop()
    assert ready
    assert took_s >= 0.5
    assert capability is Capability.UNKNOWN
    assert any("no answer from /rosapi/topics" in p for p in problems), problems
    assert acknowledges is False and telemetry is False


@pytest.mark.slow  # the link's real rosapi timeout
def test_the_rosapi_problem_names_the_timeout_it_waited() -> None:
    silent = Rosbridge(POSE_ONLY, rosapi=False).start()

    async def run() -> list[str]:
        link = RosbridgeLink(silent.url, rosapi_timeout_s=0.5)
        await link.start()
        try:
            await link.wait_connected(5.0)
            return list(link.capability_problems)
        finally:
            await link.stop()

    try:
        problems = asyncio.run(run())
    finally:
        silent.stop()
    assert any("0.5 s" in p for p in problems), problems


def test_the_console_says_rosapi_did_not_answer(make_client: MakeClient) -> None:
    """Through the console (its default rosapi timeout, 3 s): unknown, naming rosapi."""
    silent = Rosbridge(POSE_ONLY, rosapi=False).start()
    try:
        client = make_client(target=silent.url, copy_interval_s=0.05)
        link = wait_until(
            lambda: (
                (k := link_of(client))["connected"]
                and any("rosapi" in p and "no answer" in p for p in k["problems"])
                and k
            ),
            timeout_s=10.0,
            what="the rosapi problem",
        )
        assert link["capability"] == "unknown" and link["acknowledges"] is False
        # unknown: commands go out as copies chosen from link_ber, and end sent
        cmd = send(client, "circle", CIRCLE)
        assert cmd["two_way"] is False
        rec = wait_state(client, cmd["id"])
        assert rec["state"] == "sent" and rec["copies_sent"] == rec["copies"], rec
    finally:
        silent.stop()


def test_a_receiver_only_vehicle_acknowledges_only_frames_sent_another_way() -> None:
    """No frame subscriber but rosbridge's: over rosbridge alone the frames reach nothing
    (telemetry only, saying so); a link whose frames go by an ME modem (``frames=False``, the
    hybrid link's telemetry half) gets its acknowledgements."""
    vehicle = Rosbridge(RECEIVER_ONLY).start()

    async def run(frames: bool) -> tuple[Capability, list[str], str | None]:
        link = RosbridgeLink(vehicle.url, frames=frames)
        await link.start()
        try:
            assert await link.wait_connected(5.0)
            why = await link.transmit(encode_frame("surface").frame)
            return link.capability, list(link.capability_problems), why
        finally:
            await link.stop()

    try:
        alone, problems, sent = asyncio.run(run(True))
        hybrid, none, refused = asyncio.run(run(False))
    finally:
        vehicle.stop()
    assert alone is Capability.TELEMETRY_ONLY and sent is None
    assert problems[0].startswith("receiver-only: ") and "/nemesys/frame" in problems[0]
    assert hybrid is Capability.ACKS_AND_TELEMETRY and none == []
    assert refused is not None and "telemetry only" in refused
    assert vehicle.frame_count() == 1  # the first link's frame, to nothing on the vehicle
