"""A ROS 2 vehicle without the NemeSys onboard agent: a rosbridge-like server that behaves like
a real rosbridge_server (rosapi types in ROS 2 spelling, nothing sent back for advertise /
subscribe / publish, NaN floats as ``null``, ROS time stamps far from the station's clock).

The console detects it as ``telemetry_only``: commands go out as copies and end ``sent``,
unknown pose numbers are shown as unknown and counted, the telemetry age is the arrival age,
and a reconnect to a vehicle that does run the agent re-detects the capability."""

from __future__ import annotations

import asyncio
import base64
import contextlib
import json
import math
import threading
import time
from collections.abc import Iterator
from typing import Any, Final

import pytest
from fastapi.testclient import TestClient
from websockets.asyncio.server import Server, ServerConnection, serve
from websockets.exceptions import ConnectionClosed

from backend.link import Capability, RosbridgeLink

from .conftest import CIRCLE, MakeClient, send, wait_state, wait_until

FRAME: Final = "/nemesys/frame"
POSE: Final = "/nemesys/pose"

#: What /rosapi/topics lists on a ROS 2 vehicle without the onboard agent.
POSE_ONLY: Final = {
    POSE: "geometry_msgs/msg/PoseStamped",
    FRAME: "std_msgs/msg/UInt8MultiArray",
    "/rosout": "rcl_interfaces/msg/Log",
    "/client_count": "std_msgs/msg/Int32",
    "/parameter_events": "rcl_interfaces/msg/ParameterEvent",
}
#: ... and on one running it.
WITH_AGENT: Final = {
    **POSE_ONLY,
    "/nemesys/mission": "std_msgs/msg/String",
    "/nemesys/status": "std_msgs/msg/String",
}
#: The vehicle's ROS clock: far from the station's.
ROS_EPOCH_S: Final = 1_000


class Rosbridge:
    """A rosbridge_server stand-in in its own thread and event loop on 127.0.0.1.

    Answers ``call_service`` of ``/rosapi/topics`` (or the relative ``rosapi/topics``) with
    ``topics`` unless ``rosapi`` is False (then never); sends nothing back for any other op;
    records the frames published on ``/nemesys/frame``; publishes a PoseStamped on
    ``/nemesys/pose`` at ``pose_hz`` to each subscriber, every 3rd with ``null`` position.x and
    orientation.w (NaN as rosbridge sends it).
    """

    def __init__(
        self,
        topics: dict[str, str],
        *,
        port: int = 0,
        rosapi: bool = True,
        pose_hz: float = 10.0,
    ) -> None:
        self.topics = topics
        self.port = port
        self.rosapi = rosapi
        self.pose_hz = pose_hz
        self.received: list[dict[str, Any]] = []
        self.frames: list[bytes] = []
        self.poses_sent = 0
        self.connections = 0
        self._lock = threading.Lock()
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, daemon=True)
        self._server: Server | None = None

    @property
    def url(self) -> str:
        return f"ws://127.0.0.1:{self.port}"

    def start(self) -> Rosbridge:
        self._thread.start()
        self.port = asyncio.run_coroutine_threadsafe(self._start(), self._loop).result(5)
        return self

    def stop(self) -> None:
        asyncio.run_coroutine_threadsafe(self._stop(), self._loop).result(5)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(5)
        self._loop.close()

    def ops(self) -> list[str]:
        with self._lock:
            return [str(m.get("op")) for m in self.received]

    def frame_count(self) -> int:
        with self._lock:
            return len(self.frames)

    async def _start(self) -> int:
        self._server = await serve(self._handler, "127.0.0.1", self.port)
        port: int = self._server.sockets[0].getsockname()[1]
        return port

    async def _stop(self) -> None:
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()

    async def _handler(self, ws: ServerConnection) -> None:
        with self._lock:
            self.connections += 1
        poses: asyncio.Task[None] | None = None
        try:
            async for text in ws:
                message: dict[str, Any] = json.loads(text)
                with self._lock:
                    self.received.append(message)
                op = message.get("op")
                if op == "call_service" and message.get("service") in (
                    "/rosapi/topics",
                    "rosapi/topics",
                ):
                    if self.rosapi:
                        await ws.send(json.dumps(self._topics_answer(message)))
                elif op == "subscribe" and message.get("topic") == POSE and poses is None:
                    poses = asyncio.create_task(self._publish_poses(ws))
                elif op == "publish" and message.get("topic") == FRAME:
                    data = message.get("msg", {}).get("data")
                    frame = base64.b64decode(data) if isinstance(data, str) else bytes(data)
                    with self._lock:
                        self.frames.append(frame)
                # advertise, unsubscribe, unadvertise, anything else: nothing back
        except ConnectionClosed:
            pass
        finally:
            if poses is not None:
                poses.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await poses

    def _topics_answer(self, request: dict[str, Any]) -> dict[str, Any]:
        return {
            "op": "service_response",
            "id": request.get("id"),
            "service": request.get("service"),
            "values": {"topics": list(self.topics), "types": list(self.topics.values())},
            "result": True,
        }

    async def _publish_poses(self, ws: ServerConnection) -> None:
        n = 0
        with contextlib.suppress(ConnectionClosed):
            while True:
                n += 1
                await ws.send(json.dumps({"op": "publish", "topic": POSE, "msg": pose_msg(n)}))
                with self._lock:
                    self.poses_sent += 1
                await asyncio.sleep(1.0 / self.pose_hz)


def pose_msg(n: int) -> dict[str, Any]:
    """The n-th PoseStamped as rosbridge_server sends it (ROS 2 stamp; NaN -> null)."""
    heading = math.radians(30.0)
    unknown = n % 3 == 0
    return {
        "header": {
            "stamp": {"sec": ROS_EPOCH_S + n // 10, "nanosec": (n % 10) * 100_000_000},
            "frame_id": "map_ned",
        },
        "pose": {
            "position": {"x": None if unknown else 1.0 + 0.01 * n, "y": 2.0, "z": 3.0},
            "orientation": {
                "x": 0.0,
                "y": 0.0,
                "z": math.sin(heading / 2),
                "w": None if unknown else math.cos(heading / 2),
            },
        },
    }


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
    agent = [p for p in link["problems"] if "no /nemesys/mission topic" in p]
    assert agent and "onboard agent" in agent[0], link["problems"]
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

        agent.stop()
        bridges.remove(agent)
        again = Rosbridge(POSE_ONLY, port=port).start()
        bridges.append(again)
        wait_capability(client, "telemetry_only")
        assert link_of(client)["acknowledges"] is False
    finally:
        for bridge in bridges:
            bridge.stop()


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
