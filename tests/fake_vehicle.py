"""A ROS 2 vehicle as the stock rosbridge_server shows it, for the console's and
``nemesys vehicle-check``'s tests: :class:`Rosbridge`, a rosbridge-like server on 127.0.0.1
that behaves like a real rosbridge_server in front of a ROS 2 graph (rosapi types in ROS 2
spelling, nothing sent back for advertise / subscribe / publish, NaN floats as ``null``, ROS
time stamps far from the station's clock).

The graph follows ROS 2's rule, as read from RobotWebTools/rosbridge_suite (ros2 branch): a
topic exists while any node publishes or subscribes to it; the bridge's own node
(``/rosbridge_websocket``) subscribes to what its clients subscribe to, publishes what they
advertise or publish (kept :data:`UNREGISTER_TIMEOUT_S` after the last one leaves), and
publishes ``client_count`` and ``connected_clients``; ``/rosapi/topics``,
``/rosapi/publishers`` and ``/rosapi/subscribers`` answer from that graph (node names sorted).
The bridge's subscription to a topic is shared by its clients and gets its reliability when
the first client subscribes: BEST_EFFORT if a best-effort publisher is there then, else
RELIABLE, and a RELIABLE subscription does not hear a BEST_EFFORT publisher (so a pose
publisher that starts after the subscription is not heard until it is made again). Written
apart from the project's own bridge (:mod:`rosbridge.graph`) so the tests check one against
the other's rule.

The vehicle is its nodes (:class:`GraphNode`): :data:`POSE_ONLY` is a vehicle without the
NemeSys onboard agent, :data:`WITH_AGENT` one running it, :data:`RECEIVER_ONLY` one that takes
its frames over its own ME receiver. :func:`observer` is another rosbridge client (a
Foxglove-like viewer) that subscribes to topics and stays connected.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import json
import math
import threading
import time
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any, Final

from websockets.asyncio.server import Server, ServerConnection, serve
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect as sync_connect

FRAME: Final = "/nemesys/frame"
POSE: Final = "/nemesys/pose"
MISSION: Final = "/nemesys/mission"
STATUS: Final = "/nemesys/status"

FRAME_TYPE: Final = "std_msgs/msg/UInt8MultiArray"
POSE_TYPE: Final = "geometry_msgs/msg/PoseStamped"
STRING_TYPE: Final = "std_msgs/msg/String"
#: The bridge's node, as rosbridge_websocket_launch.xml names it.
BRIDGE_NODE: Final = "/rosbridge_websocket"
ROSAPI_NODE: Final = "/rosapi"
#: Seconds a publisher the bridge made for its clients outlives the last of them.
UNREGISTER_TIMEOUT_S: Final = 10.0

RELIABLE: Final = "reliable"
BEST_EFFORT: Final = "best_effort"


@dataclass(frozen=True)
class GraphNode:
    """A node of the vehicle: the topics it publishes and subscribes to (``{name: type}``),
    and which of its publishers are BEST_EFFORT (the contract's pose is)."""

    name: str
    publishes: Mapping[str, str] = field(default_factory=dict)
    subscribes: Mapping[str, str] = field(default_factory=dict)
    best_effort: frozenset[str] = frozenset()


#: A ROS 2 vehicle without the onboard agent: a navigation node publishes the pose.
POSE_ONLY: Final = (GraphNode("/navigation", {POSE: POSE_TYPE}, best_effort=frozenset({POSE})),)
#: A vehicle running the onboard agent (the reference node's topics and QoS).
AGENT: Final = GraphNode(
    "/nemesys_vehicle",
    {POSE: POSE_TYPE, MISSION: STRING_TYPE, STATUS: STRING_TYPE},
    {FRAME: FRAME_TYPE},
    best_effort=frozenset({POSE}),
)
WITH_AGENT: Final = (AGENT,)
#: The agent taking its frames over its own ME receiver: nothing subscribes to the frame topic.
RECEIVER_ONLY: Final = (
    GraphNode("/nemesys_vehicle", AGENT.publishes, best_effort=frozenset({POSE})),
)
#: The vehicle's ROS clock: far from the station's.
ROS_EPOCH_S: Final = 1_000


def ros2_type(name: str) -> str:
    """``pkg/Name`` -> ``pkg/msg/Name`` (rosapi's spelling); other shapes unchanged."""
    parts = name.split("/")
    return f"{parts[0]}/msg/{parts[1]}" if len(parts) == 2 else name


@dataclass
class _Client:
    """One connection: its subscriptions (topic -> subscription ids) and advertisements."""

    ws: ServerConnection
    subs: dict[str, set[object]] = field(default_factory=dict)
    advertised: set[str] = field(default_factory=set)


@dataclass
class _BridgeSub:
    type: str
    reliability: str
    clients: set[int] = field(default_factory=set)


@dataclass
class _BridgePub:
    type: str
    clients: set[int] = field(default_factory=set)
    linger_until: float = 0.0


class Rosbridge:
    """A rosbridge_server stand-in in its own thread and event loop on 127.0.0.1, in front of
    the vehicle's ``nodes`` (change them while it runs: :meth:`set_nodes`).

    Answers ``/rosapi/topics``, ``/rosapi/publishers`` and ``/rosapi/subscribers`` (absolute
    or relative names) from the graph unless ``rosapi`` is False (then no call is ever
    answered); any other service fails as a missing one does. Sends nothing back for any other
    op; records the frames published on ``/nemesys/frame``; publishes a PoseStamped on
    ``/nemesys/pose`` at ``pose_hz`` to each client subscribed to it while a node publishes
    the pose and the bridge's subscription hears it (module doc), every 3rd with ``null``
    position.x and orientation.w (NaN as rosbridge sends it). ``bridge_node`` names the
    bridge's node (a launch may rename it).
    """

    def __init__(
        self,
        nodes: Iterable[GraphNode],
        *,
        port: int = 0,
        rosapi: bool = True,
        pose_hz: float = 10.0,
        bridge_node: str = BRIDGE_NODE,
    ) -> None:
        self.port = port
        self.rosapi = rosapi
        self.pose_hz = pose_hz
        self.bridge_node = bridge_node
        self.received: list[dict[str, Any]] = []
        self.frames: list[bytes] = []
        self.poses_sent = 0
        self.connections = 0
        self._nodes: tuple[GraphNode, ...] = tuple(nodes)
        self._clients: dict[int, _Client] = {}
        self._subs: dict[str, _BridgeSub] = {}
        self._pubs: dict[str, _BridgePub] = {}
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

    def set_nodes(self, nodes: Iterable[GraphNode]) -> None:
        """The vehicle's nodes from now on (a node starting or stopping)."""
        with self._lock:
            self._nodes = tuple(nodes)

    def publish(self, topic: str, msg: dict[str, Any]) -> int:
        """A vehicle node publishes ``msg`` on ``topic``: sent to every client subscribed to it
        whose bridge subscription hears it (module doc). Returns how many got it."""

        async def send() -> int:
            with self._lock:
                heard = self._hears(topic)
                clients = [c.ws for c in self._clients.values() if topic in c.subs]
            text = json.dumps({"op": "publish", "topic": topic, "msg": msg})
            for ws in clients if heard else []:
                with contextlib.suppress(ConnectionClosed):
                    await ws.send(text)
            return len(clients) if heard else 0

        return asyncio.run_coroutine_threadsafe(send(), self._loop).result(5)

    def ops(self) -> list[str]:
        with self._lock:
            return [str(m.get("op")) for m in self.received]

    def frame_count(self) -> int:
        with self._lock:
            return len(self.frames)

    def subscriptions(self, topic: str) -> int:
        """How many times a client subscribed to ``topic`` so far."""
        with self._lock:
            return sum(
                m.get("op") == "subscribe" and m.get("topic") == topic for m in self.received
            )

    # --- the graph (called with the lock held) ------------------------------------------------

    def _static(self) -> list[tuple[str, dict[str, str], dict[str, str]]]:
        """(node, publishes, subscribes) of every node but the bridge's client endpoints."""
        ns = self.bridge_node.rsplit("/", 1)[0]
        own = {
            "/rosout": "rcl_interfaces/msg/Log",
            "/parameter_events": "rcl_interfaces/msg/ParameterEvent",
        }
        bridge = {
            **own,
            f"{ns}/client_count": "std_msgs/msg/Int32",
            f"{ns}/connected_clients": "rosbridge_msgs/msg/ConnectedClients",
        }
        out: list[tuple[str, dict[str, str], dict[str, str]]] = [
            (self.bridge_node, bridge, {}),
            (ROSAPI_NODE, dict(own), {}),
        ]
        out += [(n.name, {**own, **n.publishes}, dict(n.subscribes)) for n in self._nodes]
        return out

    def _endpoints(self, publishers: bool) -> dict[str, dict[str, str]]:
        """topic -> {node: type} of every publisher (or subscriber)."""
        table: dict[str, dict[str, str]] = {}
        for node, pubs, subs in self._static():
            for topic, kind in (pubs if publishers else subs).items():
                table.setdefault(topic, {})[node] = kind
        now = time.monotonic()
        if publishers:
            live = {t: p.type for t, p in self._pubs.items() if p.clients or p.linger_until > now}
        else:
            live = {t: s.type for t, s in self._subs.items()}
        for topic, kind in live.items():
            table.setdefault(topic, {})[self.bridge_node] = kind
        return table

    def _topics(self) -> dict[str, str]:
        merged: dict[str, str] = {}
        for table in (self._endpoints(True), self._endpoints(False)):
            for topic, nodes in table.items():
                merged.setdefault(topic, next(iter(nodes.values())))
        return dict(sorted(merged.items()))

    def _best_effort_publisher(self, topic: str) -> bool:
        return any(topic in n.best_effort and topic in n.publishes for n in self._nodes)

    def _hears(self, topic: str) -> bool:
        """A node publishes ``topic`` and the bridge's subscription to it hears it."""
        sub = self._subs.get(topic)
        publishers = [n for n in self._nodes if topic in n.publishes]
        if sub is None or not publishers:
            return False
        if sub.reliability == BEST_EFFORT:
            return True
        return any(topic not in n.best_effort for n in publishers)

    def _subscribe(self, key: int, message: dict[str, Any]) -> None:
        topic, kind = message.get("topic"), message.get("type")
        if not isinstance(topic, str):
            return
        established = self._topics().get(topic)
        if kind is None and established is None:
            return  # TopicNotEstablishedException: logged on the server, nothing sent
        resolved = ros2_type(str(kind)) if kind is not None else str(established)
        if topic not in self._subs:
            reliability = BEST_EFFORT if self._best_effort_publisher(topic) else RELIABLE
            self._subs[topic] = _BridgeSub(resolved, reliability)
        self._subs[topic].clients.add(key)
        self._clients[key].subs.setdefault(topic, set()).add(message.get("id"))

    def _unsubscribe(self, key: int, topic: str, sid: object, everything: bool) -> None:
        ids = self._clients[key].subs.get(topic)
        if ids is None:
            return
        if everything:
            ids.clear()
        else:
            ids.discard(sid)
        if ids:
            return
        del self._clients[key].subs[topic]
        sub = self._subs.get(topic)
        if sub is not None:
            sub.clients.discard(key)
            if not sub.clients:
                del self._subs[topic]

    def _advertise(self, key: int, topic: str, kind: object) -> None:
        established = self._topics().get(topic)
        if kind is None and established is None:
            return
        resolved = ros2_type(str(kind)) if kind is not None else str(established)
        pub = self._pubs.setdefault(topic, _BridgePub(resolved))
        pub.clients.add(key)
        self._clients[key].advertised.add(topic)

    def _unadvertise(self, key: int, topic: str) -> None:
        pub = self._pubs.get(topic)
        if pub is not None and key in pub.clients:
            pub.clients.discard(key)
            if not pub.clients:
                pub.linger_until = time.monotonic() + UNREGISTER_TIMEOUT_S
        self._clients[key].advertised.discard(topic)

    def _leave(self, key: int) -> None:
        for topic in list(self._clients[key].subs):
            self._unsubscribe(key, topic, None, True)
        for topic in list(self._clients[key].advertised):
            self._unadvertise(key, topic)
        del self._clients[key]

    def _answer(self, request: dict[str, Any]) -> dict[str, Any]:
        service = str(request.get("service"))
        name = service if service.startswith("/") else "/" + service
        args = request.get("args")
        topic = args.get("topic") if isinstance(args, dict) else None
        answer = {"op": "service_response", "id": request.get("id"), "service": service}
        if name == "/rosapi/topics":
            topics = self._topics()
            values: Any = {"topics": list(topics), "types": list(topics.values())}
        elif name in ("/rosapi/publishers", "/rosapi/subscribers"):
            table = self._endpoints(name == "/rosapi/publishers")
            key = name.rsplit("/", 1)[1]
            values = {key: sorted(table.get(str(topic), {}))}
        else:
            return {**answer, "values": f"Service {name} does not exist", "result": False}
        return {**answer, "values": values, "result": True}

    # --- the server -----------------------------------------------------------------------------

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
            key = self.connections
            self._clients[key] = _Client(ws)
        poses = asyncio.create_task(self._publish_poses(key, ws))
        try:
            async for text in ws:
                message: dict[str, Any] = json.loads(text)
                reply = self._on_message(key, message)
                if reply is not None:
                    await ws.send(json.dumps(reply))
        except ConnectionClosed:
            pass
        finally:
            poses.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await poses
            with self._lock:
                self._leave(key)

    def _on_message(self, key: int, message: dict[str, Any]) -> dict[str, Any] | None:
        op, topic = message.get("op"), message.get("topic")
        with self._lock:
            self.received.append(message)
            if op == "call_service":
                return self._answer(message) if self.rosapi else None
            if op == "subscribe":
                self._subscribe(key, message)
            elif op == "unsubscribe" and isinstance(topic, str):
                self._unsubscribe(key, topic, message.get("id"), "id" not in message)
            elif op == "advertise" and isinstance(topic, str):
                self._advertise(key, topic, message.get("type"))
            elif op == "unadvertise" and isinstance(topic, str):
                self._unadvertise(key, topic)
            elif op == "publish" and isinstance(topic, str):
                if topic not in self._clients[key].advertised:
                    self._advertise(key, topic, None)  # registers once the topic exists
                if topic == FRAME:
                    data = message.get("msg", {}).get("data")
                    frame = base64.b64decode(data) if isinstance(data, str) else bytes(data)
                    self.frames.append(frame)
        return None

    async def _publish_poses(self, key: int, ws: ServerConnection) -> None:
        n = 0
        with contextlib.suppress(ConnectionClosed):
            while True:
                await asyncio.sleep(1.0 / self.pose_hz)
                with self._lock:
                    heard = POSE in self._clients[key].subs and self._hears(POSE)
                if not heard:
                    continue
                n += 1
                await ws.send(json.dumps({"op": "publish", "topic": POSE, "msg": pose_msg(n)}))
                with self._lock:
                    self.poses_sent += 1


@contextlib.contextmanager
def observer(url: str, topics: Mapping[str, str]) -> Iterator[None]:
    """Another rosbridge client, subscribed to ``topics`` (``{name: type}``) while inside:
    its subscriptions make rosbridge's node a subscriber of each (and the topic exist)."""
    with sync_connect(url, open_timeout=3) as ws:
        for i, (topic, kind) in enumerate(topics.items()):
            subscribe = {"op": "subscribe", "id": f"observer:{i}", "topic": topic, "type": kind}
            ws.send(json.dumps(subscribe))
        # the server takes a connection's messages in order: once rosapi answers, it subscribed
        ws.send(json.dumps({"op": "call_service", "id": "observer", "service": "/rosapi/topics"}))
        while json.loads(ws.recv(timeout=3)).get("id") != "observer":
            pass
        yield


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
