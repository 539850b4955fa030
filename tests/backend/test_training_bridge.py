"""The training simulator's rosbridge takes frames only from the console: a local process may
watch the vehicle but not retask it behind the operator's back."""

from __future__ import annotations

import json
import time

import pytest
from fastapi.testclient import TestClient
from websockets.sync.client import connect

from codec import encode_frame
from rosbridge.protocol import TOPICS_SERVICE
from tests.backend.conftest import console_of, send, wait_state
from vehicle_contract.contract import FRAME_TOPIC, MISSION_TOPIC, POSE_TOPIC


@pytest.mark.training
def test_a_stranger_can_watch_but_not_publish_a_frame(client: TestClient) -> None:
    console = console_of(client)
    sim, bridge = console.sim, console.bridge
    assert sim is not None and bridge is not None
    port = bridge.port
    frames_before = sim.frames_in
    frame = list(encode_frame("hover", {"duration": 60, "depth": 1, "heading": 0}).frame.to_bytes())
    with connect(f"ws://127.0.0.1:{port}", proxy=None, open_timeout=5) as ws:
        for topic in (POSE_TOPIC, MISSION_TOPIC):
            ws.send(json.dumps({"op": "subscribe", "topic": topic}))
        ws.send(
            json.dumps(
                {"op": "advertise", "topic": FRAME_TOPIC, "type": "std_msgs/msg/UInt8MultiArray"}
            )
        )
        ws.send(json.dumps({"op": "publish", "topic": FRAME_TOPIC, "msg": {"data": frame}}))
        forged = {
            "op": "auth",
            "mac": "0" * 64,
            "client": "x",
            "dest": "y",
            "rand": "z",
            "t": time.time(),
            "level": "operator",
            "end": time.time() + 60,
        }
        ws.send(json.dumps(forged))
        ws.send(json.dumps({"op": "publish", "topic": FRAME_TOPIC, "msg": {"data": frame}}))
        # the bridge takes a connection's messages in order: once it answered this call, it
        # has dealt with both publishes (the simulator counts a frame as it takes it)
        ws.send(json.dumps({"op": "call_service", "service": TOPICS_SERVICE, "id": "after"}))
        # watching works: poses arrive
        topics: set[str] = set()
        answered = False
        deadline = time.monotonic() + 5
        while not (POSE_TOPIC in topics and answered) and time.monotonic() < deadline:
            message = json.loads(ws.recv(timeout=5))
            topics.add(message.get("topic", ""))
            answered = answered or message.get("id") == "after"
        assert POSE_TOPIC in topics and answered
        assert sim.frames_in == frames_before  # neither publish reached the vehicle
        # the console's own command still goes through, and is the only frame the vehicle saw
        cmd = wait_state(client, send(client)["id"])
        assert cmd["state"] == "acknowledged", cmd
        assert sim.frames_in == frames_before + 1
        active = sim.agent.active
        assert active is not None and active.pattern == "circle"
