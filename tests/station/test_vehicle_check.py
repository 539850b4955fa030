"""``nemesys vehicle-check``: against the simulated vehicle's own rosbridge server it passes,
probing the acknowledgement path with a repeat of the active command (a duplicate, nothing
replanned) or sending nothing when there is none; against a ROS 2 vehicle serving a pose only
it fails naming the missing topics. Loopback only."""

from __future__ import annotations

import io
import json
import time
from collections.abc import Iterator
from typing import Any

import pytest

from cli.main import main
from codec import encode_frame
from rosbridge.server import BridgeServer
from sim.simulation import Simulation
from station.vehicle_check import url_problem
from station.vehicle_report import probe_frame
from tests.fake_vehicle import POSE_ONLY, Rosbridge
from tests.rosbridge.helpers import LoopThread, free_port
from vehicle_contract.contract import CONTRACT_VERSION

CIRCLE = encode_frame("circle", speed=0.18, depth=3, radius=5, direction="cw")
#: Short windows and timeouts: the rates hold over 1.5 s, and loopback answers at once.
FAST = ["--window", "1.5", "--timeout", "2"]


class Served:
    """The simulated vehicle behind its rosbridge server, on an event loop thread."""

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        self.loop = LoopThread()
        self.server = BridgeServer(sim, "127.0.0.1", 0)

    @property
    def url(self) -> str:
        return f"ws://127.0.0.1:{self.server.port}"

    def submit(self, data: bytes) -> None:
        async def go() -> None:
            self.sim.submit_frame(data)

        self.loop.run(go())


@pytest.fixture
def served() -> Iterator[Served]:
    vehicle = Served(Simulation())
    vehicle.loop.start()
    vehicle.loop.run(vehicle.server.start())
    try:
        yield vehicle
    finally:
        vehicle.loop.run(vehicle.server.stop())
        vehicle.loop.stop()


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    out = io.StringIO()
    status = main(argv, out=out)
    return status, out.getvalue(), capsys.readouterr().err


def rows(table: str) -> dict[str, tuple[str, str]]:
    """check -> (result, reason), from the printed table."""
    lines = table.splitlines()
    width = lines[2].index("  ")
    found = {}
    for line in lines[3:-1]:
        name, rest = line[:width].strip(), line[width:].strip()
        result, _, reason = rest.partition("  ")
        found[name] = (result, reason.strip())
    return found


@pytest.mark.slow  # a probe's real listening window
def test_the_simulator_passes_and_nothing_is_sent_without_an_active_command(
    served: Served, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run(["vehicle-check", served.url, *FAST], capsys)
    assert status == 0, out
    assert err == ""
    table = rows(out)
    assert table["ack path (probe)"] == (
        "skipped",
        "the vehicle reports no active command; nothing was sent",
    )
    assert table["ack schema"][0] == "skipped"
    for name in (
        "connect",
        "rosapi /rosapi/topics",
        "topic /nemesys/frame",
        "topic /nemesys/pose",
        "topic /nemesys/mission",
        "topic /nemesys/status",
        "pose rate",
        "pose frame_id",
        "pose age",
        "status rate",
        "status schema",
    ):
        assert table[name][0] == "pass", (name, table[name])
    assert "information only" in table["pose age"][1]
    assert out.splitlines()[0] == f"vehicle-check {served.url} (contract {CONTRACT_VERSION})"
    assert out.splitlines()[-1].startswith("PASS: ")
    assert served.sim.frames_in == 0  # the server got no frame


@pytest.mark.slow  # a probe's real listening window
def test_the_probe_repeats_the_active_command_and_the_vehicle_does_not_replan(
    served: Served, capsys: pytest.CaptureFixture[str]
) -> None:
    served.submit(CIRCLE.frame.to_bytes())
    deadline = time.monotonic() + 5
    while served.sim.agent.active is None:
        assert time.monotonic() < deadline, "the command did not become active"
        time.sleep(0.02)
    agent = served.sim.agent
    plan = agent.active
    assert plan is not None
    waypoints, accepted = len(plan.path), agent.accepted

    status, out, _ = run(["vehicle-check", served.url, *FAST], capsys)

    assert status == 0, out
    table = rows(out)
    result, reason = table["ack path (probe)"]
    assert result == "pass", reason
    assert reason.startswith(
        "re-sent the active command (circle speed=0.18 m/s depth=3 m radius=5 m direction=cw): "
        "a duplicate in "
    )
    assert table["ack schema"] == ("pass", "1 valid")
    assert served.sim.frames_in == 2  # the command, then the probe: nothing else
    last = served.sim.acks[-1]
    assert last["duplicate"] is True and last["frame_hex"] == CIRCLE.frame.hex
    assert agent.active is plan and len(plan.path) == waypoints  # not replanned
    assert served.sim.guidance.plan is plan
    assert agent.accepted == accepted + 1


@pytest.mark.slow  # a probe's real listening window
def test_json_output_has_the_rows(served: Served, capsys: pytest.CaptureFixture[str]) -> None:
    status, out, _ = run(["vehicle-check", served.url, "--json", *FAST], capsys)
    assert status == 0
    doc = json.loads(out)
    assert doc["ok"] is True and doc["url"] == served.url
    assert doc["contract_version"] == CONTRACT_VERSION
    checks: list[dict[str, Any]] = doc["checks"]
    assert all(set(c) == {"check", "result", "reason"} for c in checks)
    assert all(c["result"] in ("pass", "fail", "skipped") for c in checks)
    names = [c["check"] for c in checks]
    assert names[0] == "connect" and "ack path (probe)" in names and "pose rate" in names


@pytest.mark.slow  # a probe's real listening window
def test_a_vehicle_serving_a_pose_only_fails_naming_the_missing_topics(
    capsys: pytest.CaptureFixture[str],
) -> None:
    vehicle = Rosbridge(POSE_ONLY, pose_hz=20).start()
    try:
        status, out, _ = run(
            ["vehicle-check", vehicle.url, "--window", "1.5", "--timeout", "1"], capsys
        )
        assert vehicle.frame_count() == 0  # no status, no active command: nothing sent
    finally:
        vehicle.stop()
    assert status == 1
    table = rows(out)
    for missing in ("/nemesys/mission", "/nemesys/status"):
        result, reason = table[f"topic {missing}"]
        assert result == "fail" and reason.startswith("missing: "), (missing, reason)
    assert "onboard agent" in table["topic /nemesys/mission"][1]
    assert table["topic /nemesys/pose"] == ("pass", "geometry_msgs/msg/PoseStamped")
    assert table["topic /nemesys/frame"] == ("pass", "std_msgs/msg/UInt8MultiArray")
    assert table["pose rate"][0] == "pass"
    assert table["status rate"][0] == "fail"
    assert table["ack path (probe)"][0] == "skipped"
    summary = out.splitlines()[-1]
    assert summary.startswith("FAIL: ")
    assert "topic /nemesys/mission" in summary and "topic /nemesys/status" in summary


@pytest.mark.slow  # the probe's real rosapi timeout
def test_rosapi_that_does_not_answer_fails_with_the_reason(
    capsys: pytest.CaptureFixture[str],
) -> None:
    vehicle = Rosbridge(POSE_ONLY, rosapi=False, pose_hz=20).start()
    try:
        status, out, _ = run(
            ["vehicle-check", vehicle.url, "--window", "1", "--timeout", "0.5"], capsys
        )
    finally:
        vehicle.stop()
    assert status == 1
    table = rows(out)
    assert table["rosapi /rosapi/topics"] == (
        "fail",
        "no answer in 0.5 s (is rosapi running?)",
    )
    assert table["topic /nemesys/mission"][0] == "skipped"


@pytest.mark.slow  # a probe's real listening window
def test_a_status_missing_a_field_fails_naming_it(capsys: pytest.CaptureFixture[str]) -> None:
    class NoBattery(Simulation):
        def status(self) -> dict[str, Any]:
            status = super().status()
            del status["battery_pct"]
            return status

    vehicle = Served(NoBattery())
    vehicle.loop.start()
    vehicle.loop.run(vehicle.server.start())
    try:
        status, out, _ = run(["vehicle-check", vehicle.url, *FAST], capsys)
    finally:
        vehicle.loop.run(vehicle.server.stop())
        vehicle.loop.stop()
    assert status == 1
    result, reason = rows(out)["status schema"]
    assert result == "fail" and "'battery_pct' is a required property" in reason


def test_nothing_listening_fails_the_connection(capsys: pytest.CaptureFixture[str]) -> None:
    url = f"ws://127.0.0.1:{free_port()}"
    status, out, _ = run(["vehicle-check", url, "--timeout", "1"], capsys)
    assert status == 1
    assert rows(out)["connect"] == ("fail", f"connection refused: {url}")


@pytest.mark.parametrize("url", ["http://127.0.0.1:9090", "127.0.0.1:9090", "ws://:9090"])
def test_a_url_that_is_not_a_websocket_is_bad_usage(
    url: str, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run(["vehicle-check", url], capsys)
    assert status == 2 and out == ""
    assert len(err.splitlines()) == 1 and err.startswith("nemesys vehicle-check: ")
    assert url_problem(url) is not None
    assert url_problem("wss://vehicle.local:9090/rosbridge") is None


@pytest.mark.parametrize("option", ["--timeout", "--window"])
def test_a_bad_duration_is_bad_usage(option: str, capsys: pytest.CaptureFixture[str]) -> None:
    status, out, _ = run(["vehicle-check", "ws://127.0.0.1:1", option, "0"], capsys)
    assert status == 2 and out == ""


def test_the_probe_never_sends_a_command_that_would_change() -> None:
    exact = probe_frame(
        {"pattern": "circle", "pattern_id": 3, "params": dict(CIRCLE.command.params)}
    )
    assert exact[0] is not None and exact[0].frame == CIRCLE.frame and exact[1] is None
    off_grid = {**dict(CIRCLE.command.params), "speed": 0.183}
    enc, why = probe_frame({"pattern": "circle", "pattern_id": 3, "params": off_grid})
    assert enc is None and why is not None and "speed" in why
    assert (
        probe_frame({"pattern": "circle", "pattern_id": 4, "params": dict(CIRCLE.command.params)})[
            0
        ]
        is None
    )
    assert probe_frame({"pattern": "orbit", "params": {}})[0] is None
    assert probe_frame("circle")[0] is None
