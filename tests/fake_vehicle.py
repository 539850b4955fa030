"""A ROS 2 vehicle as the stock rosbridge_server shows it, for the console's and
``nemesys vehicle-check``'s tests: :class:`Rosbridge`, a rosbridge-like server on 127.0.0.1
that behaves like a real rosbridge_server (rosapi types in ROS 2 spelling, nothing sent back
for advertise / subscribe / publish, NaN floats as ``null``, ROS time stamps far from the
station's clock). With :data:`POSE_ONLY` it is a vehicle without the NemeSys onboard agent."""

from __future__ import annotations

import asyncio
import base64
import contextlib
import json
import math
import threading
from typing import Any, Final

from websockets.asyncio.server import Server, ServerConnection, serve
from websockets.exceptions import ConnectionClosed

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
