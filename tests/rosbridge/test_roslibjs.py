"""roslibjs (npm ``roslib`` 2.x in Node, with ``ws``) against `nemesys sim`.

``tests/node/interop.mjs`` connects, lists the topics and a topic's type through rosapi,
subscribes to the pose throttled to 1 s, publishes a frame, reads the echo and the vehicle's
acknowledgement, makes Foxglove's rosbridge player's calls (``getTopicsAndRawTypes``, a
``cbor-raw`` and a ``cbor`` subscription, decoded by roslibjs), and checks fragments; it
prints its results as JSON. `make test` installs
the npm packages (``npm ci --prefix tests/node``); without them this test fails and says so.
"""

from __future__ import annotations

import base64
import json
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest
from mcap_ros2._dynamic import generate_dynamic

from codec import encode_frame
from tests.sim.sim_process import nemesys_sim
from vehicle_contract.contract import POSE_FRAME_ID, TOPICS

#: roslibjs through node: the interop tier (make test), not make test-fast.
pytestmark = pytest.mark.interop

NODE_DIR = Path(__file__).resolve().parents[1] / "node"
SCRIPT = NODE_DIR / "interop.mjs"
FRAME = encode_frame("circle", speed=0.18, depth=2.5, radius=4, direction="cw").frame


def _node() -> str:
    node = shutil.which("node")
    if node is None:
        pytest.fail("node (>= 20) is not installed: the roslibjs interop test needs it")
    for package in ("roslib", "ws"):
        if not (NODE_DIR / "node_modules" / package / "package.json").is_file():
            pytest.fail(
                f"npm package {package!r} missing in {NODE_DIR}/node_modules: "
                "run `make node-deps` (or `npm ci --prefix tests/node`); `make test` does it"
            )
    return node


@pytest.fixture(scope="module")
def results() -> dict[str, Any]:
    node = _node()
    with nemesys_sim("--time-scale", "5", "--seed", "3") as port:
        proc = subprocess.run(
            [node, str(SCRIPT), f"ws://127.0.0.1:{port}", FRAME.to_bytes().hex()],
            capture_output=True,
            text=True,
            timeout=40,
            cwd=NODE_DIR,
            check=False,
        )
    assert proc.returncode == 0, f"interop.mjs failed:\n{proc.stdout}\n{proc.stderr}"
    out: dict[str, Any] = json.loads(proc.stdout.strip().splitlines()[-1])
    return out


def test_get_topics_and_topic_type_in_ros2_spelling(results: dict[str, Any]) -> None:
    listing = dict(zip(results["topics"], results["types"], strict=True))
    for topic, kind in ((t.name, t.type) for t in TOPICS if t.required):  # the simulator's
        assert listing[topic] == kind
    assert listing["/rosout"] == "rcl_interfaces/msg/Log"
    assert listing["/client_count"] == "std_msgs/msg/Int32"
    assert results["topics"] == sorted(results["topics"])
    assert results["poseType"] == "geometry_msgs/msg/PoseStamped"


def test_throttled_pose_about_one_a_second(results: dict[str, Any]) -> None:
    assert 2 <= results["posesIn3s"] <= 4, results["posesIn3s"]


def test_frame_echo_is_base64_and_the_frame_is_acknowledged(results: dict[str, Any]) -> None:
    assert results["echoDataType"] == "string"
    assert base64.b64decode(results["echoData"], validate=True) == FRAME.to_bytes()
    assert results["ackOutcome"] == "accepted"
    assert results["ackFrameHex"] == FRAME.hex


def test_foxglove_players_calls_through_roslibjs(results: dict[str, Any]) -> None:
    """roslibjs (what Lichtblick's player is built on) reads the definitions and the binary
    CBOR frames; the CDR decodes with the definition the simulator gave (mcap_ros2)."""
    raw = results["rawTypes"]
    assert raw["topics"] == results["topics"] and raw["types"] == results["types"]
    assert "rcl_interfaces/msg/Log" in raw["types"]
    definition = raw["typedefs_full_text"][raw["topics"].index("/nemesys/pose")]
    kind = "geometry_msgs/msg/PoseStamped"
    cbor_raw = results["cborRaw"]
    assert cbor_raw["bytesIsUint8Array"] is True
    assert isinstance(cbor_raw["secs"], int) and isinstance(cbor_raw["nsecs"], int)
    pose = generate_dynamic(kind, definition)[kind](bytes.fromhex(cbor_raw["hex"]))
    assert pose.header.frame_id == POSE_FRAME_ID
    assert abs(pose.header.stamp.sec - cbor_raw["secs"]) <= 1  # both the vehicle's clock
    cbor_pose = results["cborPose"]
    assert cbor_pose["header"]["frame_id"] == POSE_FRAME_ID
    assert set(cbor_pose["pose"]["position"]) == {"x", "y", "z"}


def test_fragments(results: dict[str, Any]) -> None:
    """A fragmented service response (its id) is reassembled by roslibjs; topic messages
    fragmented with id 0, as the real server sends them, are ignored by roslibjs."""
    assert results["fragmentedTopics"] == results["topics"]
    assert results["fragmentedStatusesIn1s"] == 0
