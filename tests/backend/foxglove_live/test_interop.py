"""The live Foxglove view through Foxglove's own client: npm ``@foxglove/ws-protocol``'s
FoxgloveClient in Node (``tests/node/foxglove_live.mjs``), decoding the protobuf messages with
``protobufjs`` from the schemas the server advertises, against the training console.

The client sees ``serverInfo`` (the ``time`` capability only), every channel of
docs/foxglove.md with its schema, cannot publish (its advertise is refused), and receives the
vehicle's poses as it moves after a command: each one the pose a page got over ``/ws``, in
the scene frame, stamped on the dive's clock. `make test` installs the npm packages (``npm ci
--prefix tests/node``); without them this test fails and says so.
"""

from __future__ import annotations

import json
import queue
import shutil
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.app import create_app
from backend.foxglove_live.clock import to_ns
from backend.foxglove_live.frames import attitude_xyzw, enu
from tests.backend.conftest import clear_nemesys_env, console_of, send, settings_for
from tests.backend.foxglove_live.test_channels import documented_channels

#: Foxglove's client through node: the interop tier; the training console (a vehicle that
#: moves).
pytestmark = [pytest.mark.interop, pytest.mark.training]

NODE_DIR = Path(__file__).resolve().parents[2] / "node"
SCRIPT = NODE_DIR / "foxglove_live.mjs"
#: The decoded poses move this far (m) before the client is done.
MOVE_M = 3.0
Event = dict[str, Any]


def _node() -> str:
    node = shutil.which("node")
    if node is None:
        pytest.fail("node (>= 20) is not installed: the Foxglove interop test needs it")
    for package in ("@foxglove/ws-protocol", "protobufjs", "ws"):
        if not (NODE_DIR / "node_modules" / package / "package.json").is_file():
            pytest.fail(
                f"npm package {package!r} missing in {NODE_DIR}/node_modules: "
                "run `make node-deps` (or `npm ci --prefix tests/node`); `make test` does it"
            )
    return node


def _lines(proc: subprocess.Popen[str], out: queue.Queue[Event | None]) -> None:
    assert proc.stdout is not None
    for line in proc.stdout:
        if line.startswith("{"):
            out.put(json.loads(line))
    out.put(None)  # the script ended


def _next(
    events: queue.Queue[Event | None], kind: str, seen: list[Event], timeout_s: float = 20.0
) -> None:
    """Read events into ``seen`` up to the first of ``kind``."""
    deadline = time.monotonic() + timeout_s
    while not seen or seen[-1]["event"] != kind:
        try:
            event = events.get(timeout=max(0.0, deadline - time.monotonic()))
        except queue.Empty:
            raise AssertionError(f"no {kind!r} from foxglove_live.mjs in {timeout_s} s") from None
        if event is None:
            raise AssertionError(f"foxglove_live.mjs ended before {kind!r}")
        seen.append(event)


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """The training console with the live view (telemetry at 50 Hz, so a page and the view
    both get nearly every pose), Foxglove's client on it, and a page on ``/ws``: what each
    saw (once for the module: a console start is seconds)."""
    node = _node()
    db = tmp_path_factory.mktemp("foxglove") / "missions.sqlite3"
    with pytest.MonkeyPatch.context() as env:
        clear_nemesys_env(env)
        settings = settings_for(db, foxglove_port=0, telemetry_hz=50)
        with TestClient(create_app(settings, viewer=False)) as client:
            yield _watch(node, client)


def _watch(node: str, client: TestClient) -> dict[str, Any]:
    console = console_of(client)
    assert console.foxglove is not None
    port = console.foxglove.port
    proc = subprocess.Popen(
        [node, str(SCRIPT), f"ws://127.0.0.1:{port}", str(MOVE_M)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=NODE_DIR,
    )
    events: queue.Queue[Event | None] = queue.Queue()
    reader = threading.Thread(target=_lines, args=(proc, events), daemon=True)
    reader.start()
    seen: list[Event] = []
    page: list[dict[str, Any]] = []
    try:
        _next(events, "refused", seen)
        _next(events, "ready", seen)
        with client.websocket_connect("/ws") as ws:
            command = send(client, "circle")
            deadline = time.monotonic() + 60.0
            while not any(e["event"] == "done" for e in seen):
                assert time.monotonic() < deadline, "the client did not see the vehicle move"
                message = ws.receive_json()
                if message["type"] == "telemetry" and message["pose"] is not None:
                    page.append(message["pose"])
                while not events.empty():
                    event = events.get()
                    if event is None:  # the script ended: after "done", or failing
                        assert seen[-1]["event"] == "done", f"foxglove_live.mjs: {seen[-3:]}"
                        break
                    seen.append(event)
        assert proc.wait(timeout=20) == 0, proc.stderr.read() if proc.stderr else ""
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    reader.join(timeout=5)
    while not events.empty():
        event = events.get()
        if event is not None:
            seen.append(event)
    start_t_s = console.dives.start_t_s if console.dives is not None else None
    return {"events": seen, "page": page, "command": command, "start_t_s": start_t_s}


def _all(run: dict[str, Any], kind: str) -> list[Event]:
    return [e for e in run["events"] if e["event"] == kind]


def test_the_client_sees_the_server_and_its_channels_with_their_schemas(
    run: dict[str, Any],
) -> None:
    (refused,) = _all(run, "refused")
    assert refused == {"event": "refused", "status": 400}  # only the old name: HTTP 400
    (ready,) = _all(run, "ready")
    assert ready["protocol"] == "foxglove.sdk.v1"
    assert ready["serverInfo"]["name"] == "NemeSys Console"
    assert ready["serverInfo"]["capabilities"] == ["time"]
    channels = {c["topic"]: c for c in ready["channels"]}
    assert {t: c["schemaName"] for t, c in channels.items()} == documented_channels()
    for topic, channel in channels.items():
        if channel["encoding"] == "protobuf":
            assert channel["schemaEncoding"] == "protobuf" and channel["decodes"], topic
        else:
            assert (channel["encoding"], channel["schemaEncoding"]) == ("json", "jsonschema")
            schema = json.loads(channel["schema"])
            assert schema["type"] == "object" and schema["title"] == channel["schemaName"]


def test_the_client_cannot_publish(run: dict[str, Any]) -> None:
    (ready,) = _all(run, "ready")
    refusal = ready["refusal"]
    assert refusal["level"] == 2 and "clientPublish" in refusal["message"]  # 2: error
    (done,) = _all(run, "done")
    assert all(s["level"] == 2 for s in done["statuses"])


def test_poses_are_the_pages_in_the_scene_frame_on_the_dives_clock(run: dict[str, Any]) -> None:
    poses = _all(run, "pose")
    assert len(poses) >= 5
    times = [int(p["logTime"]) for p in poses]
    assert times == sorted(times)
    for p in poses:
        assert p["frameId"] == "map"
        assert int(p["stamp"]["seconds"]) * 10**9 + p["stamp"]["nanos"] == int(p["logTime"])
    start = run["start_t_s"]
    assert start is not None
    # the page's poses by their time on the dive's clock
    by_time = {to_ns(p["t_s"] - start): p for p in run["page"] if p["x_m"] is not None}
    matched = 0
    for p in poses:
        heard = by_time.get(int(p["logTime"]))
        if heard is None:
            continue  # a pose the page's 50 Hz did not catch (latest value wins)
        matched += 1
        e, n, u = enu(heard["x_m"], heard["y_m"], heard["z_m"])
        position = p["position"]
        assert (position["x"], position["y"], position["z"]) == pytest.approx((e, n, u), abs=1e-9)
        q = p["orientation"]
        expected = attitude_xyzw(heard["heading_deg"], heard["roll_deg"] or 0.0)
        assert (q["x"], q["y"], q["z"], q["w"]) == pytest.approx(expected, abs=1e-9)
    assert matched >= 3, (matched, len(poses), len(by_time))


def test_commands_and_their_log_lines_on_the_dives_clock(run: dict[str, Any]) -> None:
    command_id = run["command"]["id"]
    records = [e["record"] for e in _all(run, "command") if e["record"]["id"] == command_id]
    assert records and records[0]["pattern"] == "circle"
    assert records[0]["state"] in ("queued", "transmitted")
    lines = [e["text"] for e in _all(run, "log")]
    assert f"command {command_id} circle: {records[0]['state']}" in lines
    # the transmitter stays drawn: a subscriber got it on subscribing
    scenes = _all(run, "scene")
    assert any(e["topic"] == "/station" and e["entities"] == ["station"] for e in scenes)
    assert _all(run, "time")  # the server's time, the dive's clock
