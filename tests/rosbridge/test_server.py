"""The rosbridge websocket server against real clients on 127.0.0.1.

roslibpy 2.1 (asyncio transport) is the independent third-party client for the round trips;
raw ``websockets`` clients and raw sockets produce the faults. The vehicle is a fake
:class:`~vehicle_contract.endpoint.VehicleEndpoint` that records every frame it is handed. As the
ROS 2 rosbridge_server, the server sends nothing back for a fault: it logs it and publishes
it on ``/rosout``. (Against `nemesys sim` itself: test_roslibpy_interop.py, test_roslibjs.py.)
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import itertools
import json
import logging
import os
import socket
import threading
import time
from collections.abc import AsyncIterator, Callable, Coroutine
from typing import Any, TypeVar, cast

import pytest
import roslibpy
from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed, ConnectionClosedError, InvalidStatus

from rosbridge.outbox import ClientOutbox
from rosbridge.protocol import (
    FRAME_TOPIC,
    MISSION_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
    ClientSession,
    Outcome,
)
from rosbridge.server import BridgeServer
from tests.rosbridge.helpers import EXAMPLE, Inbox, LoopThread, ros_client
from vehicle_contract.endpoint import Pose

T = TypeVar("T")

LOGGER = "rosbridge.server"


class FakeVehicle:
    """A :class:`VehicleEndpoint` that records frames, acks each one and moves north-east."""

    def __init__(self, status_padding: int = 0) -> None:
        self._t = 0.0
        self._pending: list[dict[str, Any]] = []
        self._lock = threading.Lock()
        self._status_padding = status_padding
        self.frames: list[bytes] = []
        self.got_frame = threading.Event()
        self.fail_advance = False
        self.unserializable_status = False
        self.advances = 0

    @property
    def t_s(self) -> float:
        return self._t

    def submit_frame(self, data: bytes) -> None:
        with self._lock:
            self.frames.append(data)
            ok = len(data) == 13
            self._pending.append(
                {
                    "seq": len(self.frames),
                    "t_s": self._t,
                    "outcome": "accepted" if ok else "rejected",
                    "frame_hex": f"{int.from_bytes(data, 'big') >> 4:025x}" if ok else None,
                    "reason": None if ok else "malformed",
                }
            )
        self.got_frame.set()

    def advance(self, dt_s: float) -> None:
        if self.fail_advance:
            raise RuntimeError("physics blew up")
        self.advances += 1
        self._t += dt_s

    def take_missions(self) -> list[dict[str, Any]]:
        with self._lock:
            out, self._pending = self._pending, []
        return out

    def pose(self) -> Pose:
        return Pose(
            self._t, x_m=1.0 * self._t, y_m=0.5 * self._t, z_m=3.0, roll_deg=0, heading_deg=45
        )

    def status(self) -> dict[str, Any]:
        status: dict[str, Any] = {"t_s": self._t, "mode": "running", "battery_pct": 97.5}
        if self._status_padding:
            status["padding"] = "x" * self._status_padding
        if self.unserializable_status:
            status["thing"] = object()
        return status

    def received(self) -> list[bytes]:
        with self._lock:
            return list(self.frames)


# ------------------------------------------------------------------------------------------
# Helpers: servers and clients
# ------------------------------------------------------------------------------------------


def run(coro: Coroutine[Any, Any, T]) -> T:
    """Run a test coroutine with a hard deadline (no test may hang)."""

    async def bounded() -> T:
        return await asyncio.wait_for(coro, 10.0)

    return asyncio.run(bounded())


@contextlib.asynccontextmanager
async def serving(vehicle: FakeVehicle, **options: Any) -> AsyncIterator[BridgeServer]:
    server = BridgeServer(vehicle, host="127.0.0.1", port=0, **options)
    await server.start()
    try:
        yield server
    finally:
        await server.stop()


@contextlib.asynccontextmanager
async def client(server: BridgeServer, **options: Any) -> AsyncIterator[ClientConnection]:
    async with connect(f"ws://127.0.0.1:{server.port}", **options) as ws:
        yield ws


async def send(ws: ClientConnection, message: dict[str, Any] | str) -> None:
    await ws.send(message if isinstance(message, str) else json.dumps(message))


async def receive(
    ws: ClientConnection, want: Callable[[dict[str, Any]], bool], timeout: float = 1.5
) -> dict[str, Any]:
    """The first message satisfying ``want`` (others are skipped)."""
    async with asyncio.timeout(timeout):
        while True:
            text = await ws.recv()
            assert isinstance(text, str), "the server sends text frames only"
            message: dict[str, Any] = json.loads(text)
            if want(message):
                return message


async def collect(ws: ClientConnection, seconds: float) -> list[dict[str, Any]]:
    """Every message received during ``seconds``."""
    out: list[dict[str, Any]] = []
    with contextlib.suppress(TimeoutError):
        async with asyncio.timeout(seconds):
            while True:
                text = await ws.recv()
                assert isinstance(text, str)
                out.append(json.loads(text))
    return out


def op(name: str, **fields: Any) -> Callable[[dict[str, Any]], bool]:
    return lambda m: m.get("op") == name and all(m.get(k) == v for k, v in fields.items())


def topic(name: str) -> Callable[[dict[str, Any]], bool]:
    return lambda m: m.get("op") == "publish" and m.get("topic") == name


async def ping_pong(ws: ClientConnection, call_id: str) -> None:
    """A service call the server answers: proves the connection and session still work."""
    await send(ws, {"op": "call_service", "id": call_id, "service": "/rosapi/topics", "args": {}})
    reply = await receive(ws, op("service_response", id=call_id))
    assert reply["result"] is True


def frame_publish(data: Any, op_id: str | None = None) -> dict[str, Any]:
    message: dict[str, Any] = {"op": "publish", "topic": FRAME_TOPIC, "msg": {"data": data}}
    if op_id is not None:
        message["id"] = op_id
    return message


def error_logs(caplog: pytest.LogCaptureFixture) -> list[str]:
    """What the server logged as errors about clients' messages (as the real one does)."""
    return [
        r.getMessage() for r in caplog.records if r.name == LOGGER and r.levelno == logging.ERROR
    ]


async def rosout(ws: ClientConnection, level: int = 40) -> dict[str, Any]:
    """The next /rosout line of ``level`` this client receives (it must subscribe first)."""
    message = await receive(ws, lambda m: topic("/rosout")(m) and m["msg"]["level"] == level)
    log: dict[str, Any] = message["msg"]
    return log


async def raw_handshake(
    port: int, rcvbuf: int | None = None
) -> tuple[asyncio.StreamReader, asyncio.StreamWriter]:
    """A websocket connection by hand (no library): for partial frames and non-reading peers."""
    loop = asyncio.get_running_loop()
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    if rcvbuf is not None:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
    sock.setblocking(False)
    await loop.sock_connect(sock, ("127.0.0.1", port))
    reader, writer = await asyncio.open_connection(sock=sock)
    key = base64.b64encode(os.urandom(16)).decode()
    writer.write(
        (
            f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
            f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n"
        ).encode()
    )
    head = await reader.readuntil(b"\r\n\r\n")
    assert head.startswith(b"HTTP/1.1 101")
    return reader, writer


def masked_frame(payload: bytes, opcode: int = 0x1, declared: int | None = None) -> bytes:
    """A client frame (masked, FIN set); ``declared`` overrides the length in the header."""
    length = len(payload) if declared is None else declared
    if length < 126:
        header = bytes([0x80 | opcode, 0x80 | length])
    elif length < 65536:
        header = bytes([0x80 | opcode, 0x80 | 126]) + length.to_bytes(2, "big")
    else:
        header = bytes([0x80 | opcode, 0x80 | 127]) + length.to_bytes(8, "big")
    mask = os.urandom(4)
    return header + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload))


class ThreadedServer:
    """A BridgeServer on its own event loop thread, for blocking clients such as roslibpy."""

    def __init__(self, vehicle: FakeVehicle, **options: Any) -> None:
        self._loop = LoopThread()
        self.server = BridgeServer(vehicle, host="127.0.0.1", port=0, **options)

    def __enter__(self) -> ThreadedServer:
        self._loop.start()
        self._loop.run(self.server.start())
        return self

    def __exit__(self, *exc: object) -> None:
        self._loop.run(self.server.stop())
        self._loop.stop()

    @property
    def port(self) -> int:
        return self.server.port

    def clients(self) -> int:
        async def count() -> int:
            return self.server.client_count

        return self._loop.run(count())


# ------------------------------------------------------------------------------------------
# roslibpy round trips
# ------------------------------------------------------------------------------------------


@pytest.mark.interop
def test_roslibpy_frame_round_trip_and_mission_ack() -> None:
    vehicle = FakeVehicle()
    with ThreadedServer(vehicle) as bridge, ros_client(bridge.port) as ros:
        missions = Inbox()
        mission = roslibpy.Topic(ros, MISSION_TOPIC, "std_msgs/String")
        mission.subscribe(missions)
        frames = roslibpy.Topic(ros, FRAME_TOPIC, "std_msgs/UInt8MultiArray")
        frames.advertise()
        # Subscriptions are sent before the publish on the same ordered connection.
        frames.publish(roslibpy.Message({"data": list(EXAMPLE)}))
        assert vehicle.got_frame.wait(2)
        assert vehicle.received() == [EXAMPLE]
        (ack_msg,) = missions.wait(1)
        ack = json.loads(ack_msg["data"])
        assert ack["seq"] == 1 and ack["outcome"] == "accepted"
        assert ack["frame_hex"] == "aaaa7c1321473000000891560"
        # base64 data too (rosbridge's other uint8[] encoding), and a wrong length passes on.
        frames.publish(roslibpy.Message({"data": base64.b64encode(EXAMPLE[:5]).decode()}))
        acks = missions.wait(2)
        assert vehicle.received() == [EXAMPLE, EXAMPLE[:5]]
        assert json.loads(acks[1]["data"])["outcome"] == "rejected"
        frames.unadvertise()
        mission.unsubscribe()


@pytest.mark.interop
def test_roslibpy_pose_stream_at_least_10_hz() -> None:
    vehicle = FakeVehicle()
    with ThreadedServer(vehicle, pose_hz=20.0) as bridge, ros_client(bridge.port) as ros:
        poses = Inbox()
        pose = roslibpy.Topic(ros, POSE_TOPIC, "geometry_msgs/msg/PoseStamped")
        pose.subscribe(poses)
        poses.wait(1)
        start = len(poses.items())
        time.sleep(1.0)
        window = poses.items()[start:]
        assert len(window) >= 9, f"{len(window)} poses in 1 s"
        xs = [p["pose"]["position"]["x"] for p in window]
        assert all(b > a for a, b in itertools.pairwise(xs)), "positions must keep changing"
        last = window[-1]
        assert last["header"]["frame_id"] == "map_ned"
        assert set(last["header"]["stamp"]) == {"sec", "nanosec"}
        assert last["pose"]["position"]["z"] == 3.0
        q = last["pose"]["orientation"]
        assert q["z"] == pytest.approx(0.38268343, abs=1e-6)  # heading 45 deg
        pose.unsubscribe()


@pytest.mark.interop
def test_roslibpy_status_and_get_topics() -> None:
    vehicle = FakeVehicle()
    with ThreadedServer(vehicle, status_hz=10.0) as bridge, ros_client(bridge.port) as ros:
        assert ros.get_topics() == [
            "/client_count",
            "/connected_clients",
            FRAME_TOPIC,
            MISSION_TOPIC,
            POSE_TOPIC,
            STATUS_TOPIC,
            "/parameter_events",
            "/rosout",
        ]
        assert ros.get_topic_type(POSE_TOPIC) == "geometry_msgs/msg/PoseStamped"
        statuses = Inbox()
        status = roslibpy.Topic(ros, STATUS_TOPIC, "std_msgs/msg/String")
        status.subscribe(statuses)
        first, second = statuses.wait(2)[:2]
        a, b = json.loads(first["data"]), json.loads(second["data"])
        assert a["mode"] == "running" and a["battery_pct"] == 97.5
        assert b["t_s"] > a["t_s"]
        status.unsubscribe()


@pytest.mark.interop
def test_roslibpy_bad_frame_is_dropped_and_nothing_comes_back(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """As the ROS 2 server: roslibpy gets nothing back (not even for set_level); the server
    logs, and /rosout carries the errors to whoever subscribes."""
    caplog.set_level(logging.INFO)
    vehicle = FakeVehicle()
    with ThreadedServer(vehicle) as bridge, ros_client(bridge.port) as ros:
        logs = Inbox()
        roslibpy.Topic(ros, "/rosout", "rcl_interfaces/msg/Log").subscribe(logs)
        ros.set_status_level("error", "level-1")
        frames = roslibpy.Topic(ros, FRAME_TOPIC, "std_msgs/UInt8MultiArray")
        frames.publish(roslibpy.Message({"data": [1, 2, 300]}))
        frames.publish(roslibpy.Message({"data": "not base64!"}))
        frames.publish(roslibpy.Message({"data": list(EXAMPLE)}))
        assert vehicle.got_frame.wait(2)
        assert ros.get_topics()  # one more round trip, so anything sent back has arrived
        assert vehicle.received() == [EXAMPLE]
        assert bridge.clients() == 1
        errors = [m["msg"] for m in logs.wait(3) if m["level"] == 40]
    assert any("Unknown operation: set_level" in m for m in errors)
    assert any("data[2] = 300" in m for m in errors)
    assert all(m.startswith("[Client ") for m in errors)
    drops = error_logs(caplog)
    assert any("data[2] = 300" in m for m in drops)
    assert any("base64" in m for m in drops)
    roslibpy_errors = [r for r in caplog.records if r.name == "roslibpy" and r.levelno >= 40]
    assert roslibpy_errors == []


# ------------------------------------------------------------------------------------------
# Raw clients: protocol details
# ------------------------------------------------------------------------------------------


@pytest.mark.slow  # real streams, ~0.7 s
def test_per_client_subscriptions_and_unsubscribe() -> None:
    async def main() -> None:
        vehicle = FakeVehicle()
        async with (
            serving(vehicle, pose_hz=50.0) as server,
            client(server) as console,
            client(server) as observer,
        ):
            await send(console, {"op": "subscribe", "id": "m", "topic": MISSION_TOPIC})
            await send(observer, {"op": "subscribe", "id": "p", "topic": POSE_TOPIC})
            await ping_pong(console, "c1")
            await ping_pong(observer, "o1")
            await send(console, frame_publish(list(EXAMPLE)))
            ack = await receive(console, topic(MISSION_TOPIC))
            assert json.loads(ack["msg"]["data"])["seq"] == 1
            seen = await collect(observer, 0.3)
            assert {m["topic"] for m in seen} == {POSE_TOPIC}
            assert not any(m.get("topic") == POSE_TOPIC for m in await collect(console, 0.2))
            await send(observer, {"op": "unsubscribe", "id": "p", "topic": POSE_TOPIC})
            await ping_pong(observer, "o2")  # flushes poses sent before the unsubscribe
            assert await collect(observer, 0.2) == []

    run(main())


def test_frame_echo_to_frame_subscribers() -> None:
    """An observer subscribed to /nemesys/frame sees what the console sent, ``data`` in
    base64 as a ROS 2 rosbridge sends a ``uint8[]``."""

    async def main() -> None:
        async with (
            serving(FakeVehicle()) as server,
            client(server) as console,
            client(server) as observer,
        ):
            await send(observer, {"op": "subscribe", "topic": FRAME_TOPIC})
            await ping_pong(observer, "o")
            await send(console, frame_publish(list(EXAMPLE)))
            echo = await receive(observer, topic(FRAME_TOPIC))
            assert echo["msg"] == {
                "layout": {"dim": [], "data_offset": 0},
                "data": base64.b64encode(EXAMPLE).decode(),
            }

    run(main())


def test_unknown_ops_get_nothing_back_and_errors_go_to_rosout() -> None:
    async def main() -> None:
        async with serving(FakeVehicle()) as server, client(server) as ws:
            await send(ws, {"op": "subscribe", "topic": "/rosout"})
            for message in (
                {"op": "set_level", "id": "l1", "level": "error"},
                {"op": "status", "level": "error", "msg": "hello"},
                {"op": "fly", "id": "f1"},
            ):
                await send(ws, message)
            await send(ws, {"op": "call_service", "id": "c", "service": "/nope"})
            seen: list[dict[str, Any]] = []
            async with asyncio.timeout(2):
                while not any(m.get("op") == "service_response" for m in seen):
                    seen.append(json.loads(await ws.recv()))
            assert {m["op"] for m in seen} == {"publish", "service_response"}
            errors = [m["msg"] for m in seen if m.get("topic") == "/rosout"]
            texts = [e["msg"] for e in errors if e["level"] == 40]
            assert "[id: l1] Unknown operation: set_level." in texts[0]
            assert "Unknown operation: status." in texts[1]
            assert "[id: f1] Unknown operation: fly." in texts[2]
            assert all(e["name"] == "rosbridge_websocket" for e in errors)
            reply = seen[-1]
            assert reply["result"] is False and reply["values"] == "Service /nope does not exist"

    run(main())


def test_client_count_and_connected_clients_are_latched() -> None:
    async def main() -> None:
        async with serving(FakeVehicle()) as server, client(server) as ws:
            await send(ws, {"op": "subscribe", "topic": "/client_count"})
            assert (await receive(ws, topic("/client_count")))["msg"] == {"data": 1}
            async with client(server) as other:
                assert (await receive(ws, topic("/client_count")))["msg"] == {"data": 2}
                await send(other, {"op": "subscribe", "topic": "/connected_clients"})
                clients = (await receive(other, topic("/connected_clients")))["msg"]["clients"]
                assert [c["ip_address"] for c in clients] == ["127.0.0.1", "127.0.0.1"]
                assert set(clients[0]["connection_time"]) == {"sec", "nanosec"}
            assert (await receive(ws, topic("/client_count")))["msg"] == {"data": 1}

    run(main())


def test_fragments_over_the_wire() -> None:
    vehicle = FakeVehicle()

    async def main() -> None:
        async with serving(vehicle, status_hz=20.0) as server, client(server) as ws:
            await send(ws, {"op": "subscribe", "topic": STATUS_TOPIC, "fragment_size": 25})
            parts: list[dict[str, Any]] = []
            while not parts or parts[-1]["num"] + 1 < int(parts[-1]["total"]):  # floor: count
                message = await receive(ws, op("fragment"))
                if message["num"] == 0:
                    parts = []
                parts.append(message)
            assert {p["id"] for p in parts} == {0} and isinstance(parts[0]["total"], float)
            whole = json.loads("".join(p["data"] for p in parts))
            assert whole["op"] == "publish" and whole["topic"] == STATUS_TOPIC
            # A client's own fragments are reassembled: a frame in three parts.
            text = json.dumps(frame_publish(list(EXAMPLE)))
            size = len(text) // 3 + 1
            chunks = [text[i : i + size] for i in range(0, len(text), size)]
            for num, chunk in enumerate(chunks):
                fragment = {"op": "fragment", "id": "f", "num": num, "total": 3, "data": chunk}
                await send(ws, fragment)
            assert await asyncio.to_thread(vehicle.got_frame.wait, 2)
            assert vehicle.received() == [EXAMPLE]

    run(main())


FAULTS: list[tuple[str, str]] = [
    ('[{"op": "publish"}]', "Received a message without an op."),
    ('{"id": "x1", "topic": "/nemesys/frame"}', "without an op"),
    ('{"op": "takeoff", "id": "x1"}', "Unknown operation: takeoff."),
    ('{"op": "set_level", "id": "x1", "level": "error"}', "Unknown operation: set_level."),
    (
        '{"op": "advertise", "id": "x1", "topic": "/nemesys/frame", "type": "std_msgs/String"}',
        "advertise: Tried to register topic /nemesys/frame with type std_msgs/msg/String but it "
        "is already established with type std_msgs/msg/UInt8MultiArray",
    ),
    (
        '{"op": "publish", "id": "x1", "topic": "/nemesys/frame", "msg": {"data": "hello there"}}',
        "base64",
    ),
    (
        '{"op": "publish", "id": "x1", "topic": "/nemesys/frame", "msg": {"data": [1, 2.5]}}',
        "data[1] = 2.5",
    ),
    (
        '{"op": "publish", "id": "x1", "topic": "/nemesys/frame", '
        '"msg": {"header": {}, "pose": {"position": {"x": 1}}}}',
        "Message type std_msgs/UInt8MultiArray does not have a field header",
    ),
    (
        '{"op": "publish", "id": "x1", "topic": "/nemesys/pose", "msg": {"data": [1]}}',
        "Message type geometry_msgs/PoseStamped does not have a field data",
    ),
    (
        '{"op": "subscribe", "id": "x1", "topic": "/camera"}',
        "Cannot infer topic type for topic /camera as it is not yet advertised",
    ),
    (
        '{"op": "subscribe", "id": "x1", "topic": "/nemesys/pose", "throttle_rate": 1.5}',
        "Expected field throttle_rate to be one of (<class 'int'>,)",
    ),
    ('{"op": "publish", "id": "x1", "pad": "' + "x" * 1100 + '"}', "exceeds"),
]


@pytest.mark.parametrize(("text", "words"), FAULTS)
def test_fault_is_logged_on_rosout_and_nothing_comes_back(
    text: str, words: str, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.INFO, logger=LOGGER)
    vehicle = FakeVehicle()

    async def main() -> None:
        async with (
            serving(vehicle, max_message_bytes=1024, hard_max_bytes=4096) as server,
            client(server) as ws,
            client(server) as watcher,
            client(server) as bystander,
        ):
            await send(bystander, {"op": "subscribe", "topic": POSE_TOPIC})
            await send(watcher, {"op": "subscribe", "topic": "/rosout"})
            await ping_pong(watcher, "w")
            await send(ws, text)
            log = await rosout(watcher)
            assert words in log["msg"] and log["name"] == "rosbridge_websocket"
            tagged = '"id": "x1"' in text and "pad" not in text
            assert ("[id: x1]" in log["msg"]) == tagged
            # Nothing came back; the same connection still works; the vehicle only ever saw
            # the good frame.
            await send(ws, {"op": "call_service", "id": "after", "service": "/rosapi/topics"})
            reply = await receive(ws, lambda m: True)
            assert reply["op"] == "service_response" and reply["id"] == "after"
            await send(ws, frame_publish(list(EXAMPLE)))
            await ping_pong(ws, "after-frame")
            assert await asyncio.to_thread(vehicle.got_frame.wait, 2)
            assert vehicle.received() == [EXAMPLE]
            # The bystander kept getting poses throughout.
            assert (await receive(bystander, topic(POSE_TOPIC)))["msg"]["header"]
            assert server.client_count == 3

    run(main())
    drops = error_logs(caplog)
    assert len(drops) == 1 and words in drops[0]
    assert vehicle.advances > 0


def test_text_that_is_not_json_is_silently_kept_as_the_real_server_does(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.INFO, logger=LOGGER)

    async def main() -> None:
        async with serving(FakeVehicle()) as server, client(server) as ws:
            await send(ws, "not json at all")
            await send(ws, '{"op": "call_service", "id": "a", ')  # half a message...
            await send(ws, '"service": "/rosapi/topics"}')  # ...and the other half
            reply = await receive(ws, lambda m: True)
            assert reply["op"] == "service_response" and reply["id"] == "a"

    run(main())
    assert error_logs(caplog) == []


def test_binary_frames(caplog: pytest.LogCaptureFixture) -> None:
    """UTF-8 JSON in a binary frame is taken as text (as the real server); anything else
    makes the real server drop the connection, and so does this one."""
    caplog.set_level(logging.INFO, logger=LOGGER)
    vehicle = FakeVehicle()

    async def main() -> None:
        async with serving(vehicle) as server, client(server) as other:
            async with client(server) as ws:
                await ws.send(json.dumps(frame_publish(list(EXAMPLE))).encode())
                assert await asyncio.to_thread(vehicle.got_frame.wait, 2)
                await ws.send(b"\xff\x00binary")
                with pytest.raises(ConnectionClosed):
                    await ws.recv()
            await ping_pong(other, "still-up")
            assert vehicle.received() == [EXAMPLE]

    run(main())
    assert any("is not UTF-8" in m for m in error_logs(caplog))


def test_message_above_hard_limit_closes_only_that_connection(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.INFO, logger=LOGGER)
    vehicle = FakeVehicle()

    async def main() -> None:
        async with serving(vehicle, max_message_bytes=1000) as server:
            assert server.hard_max_bytes == 1000
            async with client(server) as big, client(server) as other:
                await send(other, {"op": "subscribe", "topic": POSE_TOPIC})
                await send(big, frame_publish(list(range(256)) * 2))  # > 1000 bytes
                with pytest.raises(ConnectionClosedError) as closed:
                    await big.recv()
                assert closed.value.rcvd is not None and closed.value.rcvd.code == 1009
                assert (await receive(other, topic(POSE_TOPIC)))["op"] == "publish"
                await ping_pong(other, "fine")
                assert server.client_count == 1
            async with client(server) as again:
                await ping_pong(again, "new connections welcome")
        assert vehicle.received() == []

    run(main())
    assert any("above the limit of 1000 bytes" in r.getMessage() for r in caplog.records)


def test_disconnect_mid_message(caplog: pytest.LogCaptureFixture) -> None:
    """A client that dies halfway through a frame: logged, nothing reaches the vehicle."""
    caplog.set_level(logging.INFO, logger=LOGGER)
    vehicle = FakeVehicle()

    async def main() -> None:
        async with serving(vehicle) as server, client(server) as other:
            await send(other, {"op": "subscribe", "topic": POSE_TOPIC})
            payload = json.dumps(frame_publish(list(EXAMPLE))).encode()
            full = masked_frame(payload)
            header = len(full) - len(payload)
            for cut in (1, 30, len(payload) - 1):
                _, writer = await raw_handshake(server.port)
                writer.write(full[: header + cut])
                await writer.drain()
                writer.transport.abort()
            _, writer = await raw_handshake(server.port)
            writer.write(masked_frame(payload, declared=len(payload) + 500))  # promises more
            await writer.drain()
            writer.transport.abort()
            _, writer = await raw_handshake(server.port)
            writer.write(masked_frame(payload)[:3])  # inside the header
            await writer.drain()
            writer.close()
            async with asyncio.timeout(2):
                while server.client_count != 1:
                    await asyncio.sleep(0.01)
            await ping_pong(other, "unaffected")
            assert (await receive(other, topic(POSE_TOPIC)))["msg"]["pose"]

    run(main())
    assert vehicle.received() == []
    lost = [r.getMessage() for r in caplog.records if "connection lost" in r.getMessage()]
    assert len(lost) == 5


def test_abrupt_disconnects_while_subscribed() -> None:
    vehicle = FakeVehicle()

    async def main() -> None:
        async with serving(vehicle, pose_hz=50.0) as server, client(server) as survivor:
            await send(survivor, {"op": "subscribe", "topic": POSE_TOPIC})
            doomed = [await connect(f"ws://127.0.0.1:{server.port}") for _ in range(5)]
            for ws in doomed:
                await send(ws, {"op": "subscribe", "topic": POSE_TOPIC})
                await send(ws, {"op": "subscribe", "topic": MISSION_TOPIC})
            await ping_pong(doomed[-1], "d")
            for ws in doomed:
                ws.transport.abort()
            await send(survivor, frame_publish(list(EXAMPLE)))
            async with asyncio.timeout(2):
                while server.client_count != 1:
                    await asyncio.sleep(0.01)
            poses = [m for m in await collect(survivor, 0.3) if m.get("topic") == POSE_TOPIC]
            assert len(poses) >= 5
            assert vehicle.received() == [EXAMPLE]

    run(main())


def test_many_clients_at_once() -> None:
    vehicle = FakeVehicle()

    async def main() -> None:
        async with serving(vehicle) as server:
            clients = await asyncio.gather(
                *(connect(f"ws://127.0.0.1:{server.port}") for _ in range(40))
            )
            try:
                for i, ws in enumerate(clients):
                    await send(ws, {"op": "subscribe", "topic": POSE_TOPIC})
                    await send(ws, {"op": "subscribe", "topic": MISSION_TOPIC})
                    await send(ws, frame_publish([i] * 13, f"f{i}"))
                assert server.client_count == 40

                async def acks(ws: ClientConnection) -> set[int]:
                    seqs: set[int] = set()
                    async with asyncio.timeout(3):
                        while len(seqs) < 40:
                            m = await receive(ws, topic(MISSION_TOPIC))
                            seqs.add(json.loads(m["msg"]["data"])["seq"])
                    return seqs

                # Every client sees all 40 acknowledgements (in order) and poses.
                results = await asyncio.gather(*(acks(ws) for ws in clients))
                assert all(r == set(range(1, 41)) for r in results)
                assert sorted(vehicle.received()) == sorted(bytes([i] * 13) for i in range(40))
                for ws in clients[:3]:
                    assert (await receive(ws, topic(POSE_TOPIC)))["msg"]["pose"]
            finally:
                await asyncio.gather(*(ws.close() for ws in clients))

    run(main())


@pytest.mark.slow  # a stalled client for 1 s of real time
def test_slow_client_does_not_hold_up_the_others(caplog: pytest.LogCaptureFixture) -> None:
    """A client that stops reading: others keep >= 9 poses/s, and it is dropped."""
    caplog.set_level(logging.INFO, logger=LOGGER)
    vehicle = FakeVehicle(status_padding=1_000_000)

    async def main() -> None:
        async with (
            serving(vehicle, status_hz=20.0, send_timeout_s=0.3) as server,
            client(server) as healthy,
        ):
            await send(healthy, {"op": "subscribe", "topic": POSE_TOPIC})
            _, writer = await raw_handshake(server.port, rcvbuf=4096)
            subscribe = json.dumps({"op": "subscribe", "topic": STATUS_TOPIC}).encode()
            writer.write(masked_frame(subscribe))
            await writer.drain()
            # 20 MB/s of status for a peer that never reads.
            await receive(healthy, topic(POSE_TOPIC))
            poses = [m for m in await collect(healthy, 1.0) if m.get("topic") == POSE_TOPIC]
            assert len(poses) >= 9, f"{len(poses)} poses in 1 s"
            async with asyncio.timeout(2):
                while server.client_count != 1:
                    await asyncio.sleep(0.02)
            await ping_pong(healthy, "still here")
            writer.transport.abort()

    run(main())
    assert any("send took longer than 0.3 s" in r.getMessage() for r in caplog.records)


class GatedConnection:
    """Stands in for a ServerConnection whose sends complete only when the gate is open."""

    def __init__(self) -> None:
        self.gate = asyncio.Event()
        self.sent: list[str] = []
        self.aborted = False
        self.transport = self

    async def send(self, text: str) -> None:
        await self.gate.wait()
        self.sent.append(text)

    def abort(self) -> None:
        self.aborted = True


def test_outbox_latest_wins_and_order() -> None:
    async def main() -> None:
        ws = GatedConnection()
        outbox = ClientOutbox(cast(Any, ws), ClientSession(), "t", send_timeout_s=5, max_queue=10)
        writer = asyncio.create_task(outbox.run_writer())
        outbox.enqueue("ack-1")
        await asyncio.sleep(0)  # the writer takes ack-1 and waits on the gate
        for i in range(5):
            outbox.offer_latest(POSE_TOPIC, f"pose-{i}")
        outbox.offer_latest(STATUS_TOPIC, "status-0")
        outbox.enqueue("ack-2")
        ws.gate.set()
        async with asyncio.timeout(1):
            while len(ws.sent) < 4:
                await asyncio.sleep(0.001)
        # Ordered messages first, then only the newest pose and status.
        assert ws.sent == ["ack-1", "ack-2", "pose-4", "status-0"]
        writer.cancel()

    run(main())


def test_outbox_overflow_and_stalled_send_drop_the_client(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.INFO, logger=LOGGER)

    async def main() -> None:
        ws = GatedConnection()
        outbox = ClientOutbox(cast(Any, ws), ClientSession(), "t", send_timeout_s=5, max_queue=3)
        writer = asyncio.create_task(outbox.run_writer())
        for i in range(4):
            outbox.enqueue(f"ack-{i}")
            await asyncio.sleep(0)
        assert not ws.aborted  # one in flight, three queued
        outbox.enqueue("ack-4")
        assert ws.aborted
        writer.cancel()

        stalled = GatedConnection()
        slow = ClientOutbox(
            cast(Any, stalled), ClientSession(), "s", send_timeout_s=0.05, max_queue=3
        )
        slow.offer_latest(POSE_TOPIC, "pose")
        await asyncio.wait_for(slow.run_writer(), 1)
        assert stalled.aborted and stalled.sent == []

    run(main())
    messages = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert messages == [
        "client t: disconnected: 3 messages queued, client not reading",
        "client s: disconnected: a send took longer than 0.05 s",
    ]


# ------------------------------------------------------------------------------------------
# Clock, endpoint failures, lifecycle
# ------------------------------------------------------------------------------------------


def test_time_scale() -> None:
    async def main() -> None:
        fast, paused = FakeVehicle(), FakeVehicle()
        async with serving(fast, time_scale=10.0), serving(paused, time_scale=0.0):
            await asyncio.sleep(0.3)
        assert 1.5 < fast.t_s < 6.0
        assert paused.t_s == 0.0

    run(main())


def test_endpoint_failure_is_logged_and_the_server_keeps_going(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.INFO, logger=LOGGER)
    vehicle = FakeVehicle()
    vehicle.fail_advance = True

    async def main() -> None:
        async with serving(vehicle) as server, client(server) as ws:
            await send(ws, {"op": "subscribe", "topic": POSE_TOPIC})
            await receive(ws, topic(POSE_TOPIC))
            async with asyncio.timeout(5):  # the failure is logged; the server goes on
                while not any("advance failed" in r.getMessage() for r in caplog.records):
                    await asyncio.sleep(0.01)
                await receive(ws, topic(POSE_TOPIC))
                vehicle.fail_advance = False
                while vehicle.t_s <= 0.0:  # the clock moves again
                    await asyncio.sleep(0.01)

    run(main())
    failures = [r for r in caplog.records if "endpoint.advance failed" in r.getMessage()]
    assert len(failures) == 1 and failures[0].exc_info is not None
    assert any("endpoint.advance works again" in r.getMessage() for r in caplog.records)


def test_unserializable_status_skips_only_itself(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger=LOGGER)
    vehicle = FakeVehicle()
    vehicle.unserializable_status = True

    async def main() -> None:
        async with serving(vehicle, status_hz=20.0) as server, client(server) as ws:
            await send(ws, {"op": "subscribe", "topic": STATUS_TOPIC})
            await send(ws, {"op": "subscribe", "topic": POSE_TOPIC})
            await receive(ws, topic(POSE_TOPIC))
            await receive(ws, topic(POSE_TOPIC))
            vehicle.unserializable_status = False
            status = await receive(ws, topic(STATUS_TOPIC))
            assert json.loads(status["msg"]["data"])["mode"] == "running"

    run(main())
    failures = [r for r in caplog.records if "status publication failed" in r.getMessage()]
    assert len(failures) == 1
    assert any("status publication works again" in r.getMessage() for r in caplog.records)


def test_internal_error_on_a_message_keeps_the_connection(
    caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    original = ClientSession.receive

    def flaky(self: ClientSession, text: str) -> list[Outcome]:
        if text == "boom":
            raise RuntimeError("bug")
        return original(self, text)

    monkeypatch.setattr(ClientSession, "receive", flaky)
    caplog.set_level(logging.INFO, logger=LOGGER)

    async def main() -> None:
        async with serving(FakeVehicle()) as server, client(server) as ws:
            await send(ws, "boom")
            await ping_pong(ws, "alive")

    run(main())
    assert any("internal error on a message" in r.getMessage() for r in caplog.records)


def test_lifecycle() -> None:
    async def main() -> None:
        server = BridgeServer(FakeVehicle(), port=0)
        with pytest.raises(RuntimeError, match="not started"):
            _ = server.port
        forever = asyncio.create_task(server.serve_forever())
        async with asyncio.timeout(2):
            while True:
                with contextlib.suppress(RuntimeError):
                    port = server.port
                    break
                await asyncio.sleep(0.01)
        with pytest.raises(InvalidStatus, match="404"):  # only "/", as the real server
            await connect(f"ws://127.0.0.1:{port}/rosbridge")
        async with connect(f"ws://127.0.0.1:{port}/?x=1") as ws:
            await ping_pong(ws, "root path")
            await server.stop()
            with pytest.raises(ConnectionClosed):
                await ws.recv()
        await forever
        await server.stop()  # idempotent
        with pytest.raises(OSError):
            await connect(f"ws://127.0.0.1:{port}", open_timeout=1)

    run(main())


@pytest.mark.parametrize(
    ("options", "words"),
    [
        ({"time_scale": -1.0}, "time_scale"),
        ({"pose_hz": 0.0}, "pose_hz"),
        ({"status_hz": -2.0}, "status_hz"),
        ({"max_message_bytes": 0}, "max_message_bytes"),
        ({"max_message_bytes": 100, "hard_max_bytes": 50}, "hard_max_bytes"),
        ({"send_timeout_s": 0.0}, "send_timeout_s"),
    ],
)
def test_arguments_are_checked(options: dict[str, Any], words: str) -> None:
    with pytest.raises(ValueError, match=words):
        BridgeServer(FakeVehicle(), **options)
