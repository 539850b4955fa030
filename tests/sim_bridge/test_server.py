"""The rosbridge websocket server against real clients on 127.0.0.1.

roslibpy 2.1 (asyncio transport) is the independent third-party client for the round trips;
raw ``websockets`` clients and raw sockets produce the faults. The vehicle is a fake
:class:`~sim_bridge.endpoint.VehicleEndpoint` that records every frame it is handed.
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
from websockets.exceptions import ConnectionClosed, ConnectionClosedError

from sim_bridge.endpoint import Pose
from sim_bridge.rosbridge import (
    FRAME_TOPIC,
    MISSION_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
    ClientSession,
    Outcome,
)
from sim_bridge.server import BridgeServer, _Client

from .helpers import EXAMPLE, Inbox, LoopThread, ros_client

T = TypeVar("T")

LOGGER = "sim_bridge.server"


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


def dropped_logs(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [
        r.getMessage()
        for r in caplog.records
        if r.name == LOGGER and r.levelno == logging.WARNING and "dropped message" in r.getMessage()
    ]


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


def test_roslibpy_status_and_get_topics() -> None:
    vehicle = FakeVehicle()
    with ThreadedServer(vehicle, status_hz=10.0) as bridge, ros_client(bridge.port) as ros:
        assert ros.get_topics() == [FRAME_TOPIC, POSE_TOPIC, MISSION_TOPIC, STATUS_TOPIC]
        assert ros.get_topic_type(POSE_TOPIC) == "geometry_msgs/PoseStamped"
        statuses = Inbox()
        status = roslibpy.Topic(ros, STATUS_TOPIC, "std_msgs/msg/String")
        status.subscribe(statuses)
        first, second = statuses.wait(2)[:2]
        a, b = json.loads(first["data"]), json.loads(second["data"])
        assert a["mode"] == "running" and a["battery_pct"] == 97.5
        assert b["t_s"] > a["t_s"]
        status.unsubscribe()


def test_roslibpy_bad_frame_is_dropped_and_the_client_sees_no_status(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Default status level 'none': roslibpy gets nothing it cannot handle; the server logs."""
    caplog.set_level(logging.INFO)
    vehicle = FakeVehicle()
    with ThreadedServer(vehicle) as bridge, ros_client(bridge.port) as ros:
        frames = roslibpy.Topic(ros, FRAME_TOPIC, "std_msgs/UInt8MultiArray")
        frames.publish(roslibpy.Message({"data": [1, 2, 300]}))
        frames.publish(roslibpy.Message({"data": "not base64!"}))
        frames.publish(roslibpy.Message({"data": list(EXAMPLE)}))
        assert vehicle.got_frame.wait(2)
        assert ros.get_topics()  # one more round trip, so anything sent back has arrived
        assert vehicle.received() == [EXAMPLE]
        assert bridge.clients() == 1
    drops = dropped_logs(caplog)
    assert any("data[2] = 300" in m for m in drops)
    assert any("base64" in m for m in drops)
    roslibpy_errors = [r for r in caplog.records if r.name == "roslibpy" and r.levelno >= 40]
    assert roslibpy_errors == []


def test_roslibpy_cannot_take_status_messages_so_they_are_opt_in(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Why status is opt-in: roslibpy 2.1 logs an exception for every status it receives."""
    vehicle = FakeVehicle()
    with ThreadedServer(vehicle) as bridge, ros_client(bridge.port) as ros:
        ros.set_status_level("error", "level-1")
        frames = roslibpy.Topic(ros, FRAME_TOPIC, "std_msgs/UInt8MultiArray")
        frames.publish(roslibpy.Message({"data": [999]}))
        assert ros.get_topics()
        deadline = time.monotonic() + 1.5
        while time.monotonic() < deadline and not any(
            r.name == "roslibpy" and r.exc_info for r in caplog.records
        ):
            time.sleep(0.01)
        assert vehicle.received() == []
    errors = [r for r in caplog.records if r.name == "roslibpy" and r.exc_info]
    assert errors, "roslibpy now handles status: revisit DEFAULT_STATUS_LEVEL"
    assert "status" in str(errors[0].exc_info[1] if errors[0].exc_info else "")


# ------------------------------------------------------------------------------------------
# Raw clients: protocol details
# ------------------------------------------------------------------------------------------


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
    """An observer subscribed to /nemesys/frame sees what the console sent."""

    async def main() -> None:
        async with (
            serving(FakeVehicle()) as server,
            client(server) as console,
            client(server) as observer,
        ):
            await send(observer, {"op": "subscribe", "topic": FRAME_TOPIC})
            await ping_pong(observer, "o")
            await send(console, frame_publish(base64.b64encode(EXAMPLE).decode()))
            echo = await receive(observer, topic(FRAME_TOPIC))
            assert bytes(echo["msg"]["data"]) == EXAMPLE

    run(main())


def test_status_messages_after_set_level_echo_the_id() -> None:
    async def main() -> None:
        async with serving(FakeVehicle()) as server, client(server) as ws:
            await send(ws, {"op": "fly", "id": "silent"})
            await send(ws, {"op": "set_level", "level": "error"})
            await send(ws, {"op": "fly", "id": "loud"})
            status = await receive(ws, lambda m: m.get("op") in {"status", "service_response"})
            assert status["op"] == "status", "no status before set_level"
            assert status["id"] == "loud" and status["level"] == "error"
            assert "unknown op 'fly'" in status["msg"]
            await send(ws, {"op": "set_level", "level": "none"})
            await send(ws, {"op": "fly", "id": "quiet-again"})
            await send(ws, {"op": "call_service", "id": "c", "service": "/nope"})
            reply = await receive(ws, lambda m: m.get("op") in {"status", "service_response"})
            assert reply["op"] == "service_response" and reply["result"] is False
            assert isinstance(reply["values"], str) and "/nope" in reply["values"]

    run(main())


# ------------------------------------------------------------------------------------------
# Faults: dropped with a logged reason, status when asked, connection and vehicle unaffected
# ------------------------------------------------------------------------------------------

FAULTS: list[tuple[str, str, str]] = [
    ("not json at all", "MalformedMessage", "not valid JSON"),
    ('{"op": "publish", "topic": ', "MalformedMessage", "not valid JSON"),
    ('[{"op": "publish"}]', "MalformedMessage", "an array"),
    ('"just a string"', "MalformedMessage", "a string"),
    ('{"id": "x1", "topic": "/nemesys/frame"}', "UnknownOp", "no 'op'"),
    ('{"op": "takeoff", "id": "x1"}', "UnknownOp", "unknown op 'takeoff'"),
    (
        '{"op": "advertise", "id": "x1", "topic": "/nemesys/frame", "type": "std_msgs/String"}',
        "TypeMismatch",
        "'std_msgs/String' is not std_msgs/UInt8MultiArray",
    ),
    (
        '{"op": "publish", "id": "x1", "topic": "/nemesys/frame", "msg": {"data": "hello there"}}',
        "InvalidData",
        "base64",
    ),
    (
        '{"op": "publish", "id": "x1", "topic": "/nemesys/frame", "msg": {"data": [1, 2.5]}}',
        "InvalidData",
        "data[1] = 2.5",
    ),
    (
        '{"op": "publish", "id": "x1", "topic": "/nemesys/frame", '
        '"msg": {"header": {}, "pose": {"position": {"x": 1}}}}',
        "TypeMismatch",
        "header, pose",
    ),
    (
        '{"op": "publish", "id": "x1", "topic": "/nemesys/pose", "msg": {"data": [1]}}',
        "ReadOnlyTopic",
        "only the vehicle",
    ),
    (
        '{"op": "subscribe", "id": "x1", "topic": "/nemesys/pose", "compression": "cbor"}',
        "UnsupportedOp",
        "'cbor'",
    ),
    ('{"op": "subscribe", "id": "x1", "topic": "/camera"}', "UnknownTopic", "'/camera'"),
    ('{"op": "publish", "id": "x1", "pad": "' + "x" * 1100 + '"}', "OversizedMessage", "exceeds"),
]


@pytest.mark.parametrize(("text", "error", "words"), FAULTS, ids=[f[1] for f in FAULTS])
def test_fault_is_dropped_logged_and_answered(
    text: str, error: str, words: str, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.INFO, logger=LOGGER)
    vehicle = FakeVehicle()

    async def main() -> None:
        async with (
            serving(vehicle, max_message_bytes=1024) as server,
            client(server) as ws,
            client(server) as bystander,
        ):
            await send(bystander, {"op": "subscribe", "topic": POSE_TOPIC})
            await send(ws, {"op": "set_level", "level": "error"})
            await send(ws, text)
            status = await receive(ws, op("status"))
            assert status["level"] == "error" and words in status["msg"]
            if '"id": "x1"' in text and error != "OversizedMessage":
                assert status["id"] == "x1"
            else:
                assert "id" not in status
            # Same connection still works, the vehicle only ever saw the good frame.
            await ping_pong(ws, "after")
            advertise = {
                "op": "advertise",
                "topic": FRAME_TOPIC,
                "type": "std_msgs/UInt8MultiArray",
            }
            await send(ws, advertise)
            await send(ws, frame_publish(list(EXAMPLE)))
            await ping_pong(ws, "after-frame")
            assert vehicle.received() == [EXAMPLE]
            # The bystander kept getting poses throughout.
            assert (await receive(bystander, topic(POSE_TOPIC)))["msg"]["header"]
            assert server.client_count == 2

    run(main())
    drops = dropped_logs(caplog)
    assert len(drops) == 1
    assert error in drops[0] and words in drops[0]
    assert vehicle.advances > 0


def test_binary_frame_is_dropped(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger=LOGGER)
    vehicle = FakeVehicle()

    async def main() -> None:
        async with serving(vehicle) as server, client(server) as ws:
            await send(ws, {"op": "set_level", "level": "error"})
            await ws.send(json.dumps(frame_publish(list(EXAMPLE))).encode())
            status = await receive(ws, op("status"))
            assert "binary frame" in status["msg"]
            await ws.send(EXAMPLE)
            await ping_pong(ws, "still-up")
            assert vehicle.received() == []

    run(main())
    drops = dropped_logs(caplog)
    assert len(drops) == 2 and all("BinaryMessage" in m for m in drops)


def test_message_above_hard_limit_closes_only_that_connection(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.INFO, logger=LOGGER)
    vehicle = FakeVehicle()

    async def main() -> None:
        async with serving(vehicle, max_message_bytes=1000) as server:
            assert server.hard_max_bytes == 4000
            async with client(server) as big, client(server) as other:
                await send(other, {"op": "subscribe", "topic": POSE_TOPIC})
                await send(big, frame_publish(list(range(256)) * 10))  # > 4000 bytes
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
    assert any("above the hard limit of 4000 bytes" in r.getMessage() for r in caplog.records)


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
        outbox = _Client(cast(Any, ws), ClientSession(), "t", send_timeout_s=5, max_queue=10)
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
        outbox = _Client(cast(Any, ws), ClientSession(), "t", send_timeout_s=5, max_queue=3)
        writer = asyncio.create_task(outbox.run_writer())
        for i in range(4):
            outbox.enqueue(f"ack-{i}")
            await asyncio.sleep(0)
        assert not ws.aborted  # one in flight, three queued
        outbox.enqueue("ack-4")
        assert ws.aborted
        writer.cancel()

        stalled = GatedConnection()
        slow = _Client(cast(Any, stalled), ClientSession(), "s", send_timeout_s=0.05, max_queue=3)
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
            await asyncio.sleep(0.1)
            vehicle.fail_advance = False
            await asyncio.sleep(0.1)
            assert vehicle.t_s > 0.0

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
    original = ClientSession.receive_text

    def flaky(self: ClientSession, text: str) -> Outcome:
        if text == "boom":
            raise RuntimeError("bug")
        return original(self, text)

    monkeypatch.setattr(ClientSession, "receive_text", flaky)
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
        async with connect(f"ws://127.0.0.1:{port}/rosbridge") as ws:
            await ping_pong(ws, "path ignored")
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
