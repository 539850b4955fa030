"""`nemesys sim` end to end: the real simulated vehicle behind its bridge, in a subprocess.

roslibpy (asyncio transport) publishes frames and watches the acknowledgements, poses and
status; raw websocket clients throw every fault at it; `nemesys send` talks to it. After the
faults the vehicle must still fly the pattern it was given. Loopback only.
"""

from __future__ import annotations

import asyncio
import json
import subprocess
import time
from collections.abc import Iterator
from typing import Any

import pytest
import roslibpy
from websockets.asyncio.client import connect

from codec import encode_frame
from rosbridge.protocol import FRAME_TOPIC, MISSION_TOPIC, POSE_TOPIC, STATUS_TOPIC
from tests.rosbridge.helpers import Inbox, ros_client
from tests.sim.sim_process import NEMESYS, nemesys_sim

#: ``nemesys`` as a subprocess: this interpreter running ``cli.main``.

CIRCLE = encode_frame("circle", speed=0.18, depth=2.5, radius=4, direction="cw").frame
SQUARE = encode_frame("square", speed=0.18, depth=2, side_span=6, direction="ccw").frame


@pytest.fixture(scope="module")
def sim_port() -> Iterator[int]:
    """`nemesys sim` on a free loopback port, ten times faster than real time."""
    with nemesys_sim("--time-scale", "10", "--seed", "5") as port:
        yield port


def _acks(inbox: Inbox, count: int) -> list[dict[str, Any]]:
    return [json.loads(m["data"]) for m in inbox.wait(count, timeout=5)]


def _status(port: int) -> dict[str, Any]:
    with ros_client(port) as ros:
        inbox = Inbox()
        topic = roslibpy.Topic(ros, STATUS_TOPIC, "std_msgs/String")
        topic.subscribe(inbox)
        status: dict[str, Any] = json.loads(inbox.wait(1, timeout=5)[0]["data"])
        topic.unsubscribe()
        return status


@pytest.mark.interop
def test_roslibpy_round_trip_with_the_simulated_vehicle(sim_port: int) -> None:
    with ros_client(sim_port) as ros:
        missions, poses = Inbox(), Inbox()
        roslibpy.Topic(ros, MISSION_TOPIC, "std_msgs/String").subscribe(missions)
        roslibpy.Topic(ros, POSE_TOPIC, "geometry_msgs/PoseStamped").subscribe(poses)
        frames = roslibpy.Topic(ros, FRAME_TOPIC, "std_msgs/UInt8MultiArray")
        frames.advertise()
        frames.publish(roslibpy.Message({"data": list(CIRCLE.to_bytes())}))
        (ack,) = _acks(missions, 1)
        assert ack["outcome"] == "accepted"
        assert ack["frame_hex"] == CIRCLE.hex
        assert ack["command"]["pattern"] == "circle"
        assert ack["command"]["params"]["radius"] == 4.0
        assert ack["active"] == ack["command"]
        assert ack["corrected_bits"] == 0 and ack["decode_latency_ms"] > 0
        assert ack["replan_latency_ms"] > 0 and ack["waypoints"] > 10
        time.sleep(1.0)
        window = poses.wait(10)
        assert len(window) >= 10
        first, last = window[0]["pose"]["position"], window[-1]["pose"]["position"]
        assert (first["x"], first["y"]) != (last["x"], last["y"]), "the vehicle must move"
        assert window[-1]["header"]["frame_id"] == "map_ned"
        frames.unadvertise()
    status = _status(sim_port)
    assert status["pattern"] == "circle" and status["mode"] == "running"
    assert status["link"]["accepted"] >= 1


async def _faults(port: int) -> None:
    url = f"ws://127.0.0.1:{port}"
    async with connect(url, max_size=None) as ws:
        for bad in (
            "this is not json",
            "[1, 2, 3]",
            json.dumps({"op": "launch_torpedo"}),
            json.dumps({"no_op": True}),
            json.dumps({"op": "publish", "topic": FRAME_TOPIC, "msg": {"data": "not base64!"}}),
            json.dumps({"op": "publish", "topic": FRAME_TOPIC, "msg": {"data": [1, 999, 3]}}),
            json.dumps({"op": "publish", "topic": FRAME_TOPIC, "msg": {"text": "hello"}}),
            json.dumps({"op": "advertise", "topic": FRAME_TOPIC, "type": "std_msgs/String"}),
            json.dumps({"op": "publish", "topic": POSE_TOPIC, "msg": {}}),
            "x" * 100_000,  # oversized (above the 64 KiB soft limit)
        ):
            await ws.send(bad)
        await ws.send(b"\x00\x01binary")
    # a client that disconnects in the middle of a message: half a websocket frame, then gone
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    writer.write(
        b"GET / HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        b"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
    )
    await reader.readuntil(b"\r\n\r\n")
    writer.write(b"\x81\xfe\x01\x00" + b"\x00" * 4 + b'{"op": "publ')  # declares 256 bytes
    await writer.drain()
    writer.close()
    # several clients at once keep working
    async with connect(url) as a, connect(url) as b:
        for ws in (a, b):
            await ws.send(json.dumps({"op": "subscribe", "topic": STATUS_TOPIC}))
        for ws in (a, b):
            async with asyncio.timeout(5):
                while json.loads(await ws.recv()).get("topic") != STATUS_TOPIC:
                    pass


@pytest.mark.slow  # a `nemesys sim` subprocess
def test_faults_leave_the_server_up_and_the_vehicle_on_its_pattern(sim_port: int) -> None:
    with ros_client(sim_port) as ros:
        missions = Inbox()
        roslibpy.Topic(ros, MISSION_TOPIC, "std_msgs/String").subscribe(missions)
        frames = roslibpy.Topic(ros, FRAME_TOPIC, "std_msgs/UInt8MultiArray")
        frames.publish(roslibpy.Message({"data": list(SQUARE.to_bytes())}))
        (ack,) = _acks(missions, 1)
        assert ack["outcome"] == "accepted" and ack["active"]["pattern"] == "square"
        asyncio.run(_faults(sim_port))
        # a frame with the wrong length reaches the vehicle and is rejected, changing nothing
        frames.publish(roslibpy.Message({"data": list(CIRCLE.to_bytes()[:12])}))
        # a frame wrecked in transit (every codeword byte inverted) is rejected too
        wrecked = bytes(b ^ 0xFF if 3 <= i < 12 else b for i, b in enumerate(CIRCLE.to_bytes()))
        frames.publish(roslibpy.Message({"data": list(wrecked)}))
        acks = _acks(missions, 3)[1:]
        assert [a["outcome"] for a in acks] == ["rejected", "rejected"]
        assert acks[0]["reason"] == "malformed"
        assert acks[1]["reason"] in {"uncorrectable", "crc_mismatch", "unknown_pattern"}
        assert all(a["active"]["pattern"] == "square" for a in acks)
    # both frames were answered (rejected): nothing of them is pending in the vehicle
    status = _status(sim_port)
    assert status["pattern"] == "square" and status["mode"] == "running"


def _send(port: int, *command: str) -> subprocess.CompletedProcess[str]:
    """``nemesys send --to ws://127.0.0.1:port COMMAND...``."""
    return subprocess.run(
        [*NEMESYS, "send", "--to", f"ws://127.0.0.1:{port}", *command],
        capture_output=True,
        text=True,
        timeout=30,
        check=False,
    )


@pytest.mark.slow  # a `nemesys sim` subprocess
def test_nemesys_send_prints_the_vehicles_acknowledgement(sim_port: int) -> None:
    done = _send(sim_port, "hover", "duration=60", "depth=1.5", "heading=90", "--json")
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    ack = result["ack"]
    assert ack["outcome"] == "accepted" and ack["command"]["pattern"] == "hover"
    args = ("straight", "speed=2.5", "depth=1", "duration=10", "heading=0")
    done = _send(sim_port, *args)  # the console's policy: nothing sent without the override
    assert done.returncode == 2 and "--override accepts it" in done.stderr
    assert _status(sim_port)["pattern"] == "hover"
    done = _send(sim_port, *args, "--override")  # sent: the vehicle's own check refuses it
    assert done.returncode == 1
    assert "limit_violation" in done.stdout + done.stderr
    assert _status(sim_port)["pattern"] == "hover"
