"""``nemesys vehicle-check``: against the simulated vehicle's own rosbridge server it passes,
probing the acknowledgement path with a malformed frame on a fresh vehicle too (rejected,
nothing changed) and, while a command runs, with a repeat of it (a duplicate, nothing
replanned); through a modem path when asked. Against a ROS 2 vehicle serving a pose only, with
an observer subscribed to the frame and mission topics, it fails naming the missing agent;
against a receiver-only vehicle it says the probe needs the modem path. Loopback only."""

from __future__ import annotations

import asyncio
import contextlib
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
from station.vehicle_report import PROBE_FRAME, probe_frame
from tests.fake_vehicle import (
    FRAME,
    FRAME_TYPE,
    MISSION,
    POSE_ONLY,
    RECEIVER_ONLY,
    STRING_TYPE,
    Rosbridge,
    observer,
)
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
def test_the_simulator_passes_and_the_probe_runs_on_a_fresh_vehicle(
    served: Served, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run(["vehicle-check", served.url, *FAST], capsys)
    assert status == 0, out
    assert err == ""
    table = rows(out)
    result, reason = table["ack path (probe)"]
    assert result == "pass", reason
    assert reason.startswith(
        f"a malformed frame ({PROBE_FRAME.hex}: codeword beyond correction) published on "
        "/nemesys/frame: rejected as uncorrectable in "
    )
    assert reason.endswith("(the contract's deadline 1 s); nothing changed")
    assert table["ack path (duplicate)"] == (
        "skipped",
        "the vehicle reports no active command; nothing was sent",
    )
    assert table["ack schema"] == ("pass", "1 valid")
    for name in (
        "connect",
        "rosapi",
        "topic /nemesys/frame",
        "topic /nemesys/pose",
        "topic /nemesys/mission",
        "topic /nemesys/status",
        "onboard agent",
        "pose rate",
        "pose frame_id",
        "pose age",
        "status rate",
        "status schema",
    ):
        assert table[name][0] == "pass", (name, table[name])
    assert (
        table["topic /nemesys/mission"][1] == "std_msgs/msg/String, published by /nemesys_vehicle"
    )
    assert table["topic /nemesys/frame"][1].endswith("subscribed by /nemesys_vehicle")
    assert table["onboard agent"][1].endswith("the console: acks_and_telemetry")
    assert "information only" in table["pose age"][1]
    assert out.splitlines()[0] == f"vehicle-check {served.url} (contract {CONTRACT_VERSION})"
    assert out.splitlines()[-1] == "PASS: 14 pass, 1 skipped"
    # the probe reached the agent, which rejected it and changed nothing
    agent = served.sim.agent
    assert served.sim.frames_in == 1 and agent.rejected == 1 and agent.accepted == 0
    assert agent.active is None
    ack = served.sim.acks[-1]
    assert ack["frame_hex"] == PROBE_FRAME.hex and ack["reason"] == "uncorrectable"


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
    assert table["ack path (probe)"][0] == "pass"  # rejected, the circle still active
    result, reason = table["ack path (duplicate)"]
    assert result == "pass", reason
    assert reason.startswith(
        "re-sent the active command (circle speed=0.18 m/s depth=3 m radius=5 m direction=cw) "
        "published on /nemesys/frame: a duplicate in "
    )
    assert table["ack schema"] == ("pass", "2 valid")
    assert served.sim.frames_in == 3  # the command, the malformed probe, the repeat
    probe, last = served.sim.acks[-2:]
    assert probe["outcome"] == "rejected" and probe["active"] == last["active"]
    assert last["duplicate"] is True and last["frame_hex"] == CIRCLE.frame.hex
    assert agent.active is plan and len(plan.path) == waypoints  # not replanned
    assert served.sim.guidance.plan is plan
    assert agent.accepted == accepted + 1


class Modem:
    """A TCP gateway in front of the simulated vehicle's own ME receiver: every 13 bytes that
    arrive go to the vehicle as a frame (the modem path of a receiver-only vehicle)."""

    def __init__(self, served: Served) -> None:
        self.served = served
        self.received = b""
        self.port = 0

    async def start(self) -> None:
        async def gateway(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
            with contextlib.suppress(asyncio.IncompleteReadError, ConnectionError):
                while True:
                    data = await reader.readexactly(13)
                    self.received += data
                    self.served.sim.submit_frame(data)
            writer.close()

        self.server = await asyncio.start_server(gateway, "127.0.0.1", 0)
        self.port = self.server.sockets[0].getsockname()[1]

    async def stop(self) -> None:
        self.server.close()
        await self.server.wait_closed()


@pytest.mark.slow  # a probe's real listening window
def test_the_probe_goes_through_the_modem_path_when_asked(
    served: Served, capsys: pytest.CaptureFixture[str]
) -> None:
    modem = Modem(served)
    served.loop.run(modem.start())
    target = f"tcp://127.0.0.1:{modem.port}"
    try:
        status, out, _ = run(["vehicle-check", served.url, "--modem", target, *FAST], capsys)
    finally:
        served.loop.run(modem.stop())
    assert status == 0, out
    result, reason = rows(out)["ack path (probe)"]
    assert result == "pass", reason
    assert f"sent through the modem path ({target}): rejected as uncorrectable" in reason
    assert modem.received == PROBE_FRAME.to_bytes()  # the only frame, and through the modem
    assert served.sim.frames_in == 1


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
def test_a_pose_only_vehicle_fails_naming_the_missing_agent_despite_an_observer(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The frame and mission topics exist (rosbridge subscribes to them for the observer): the
    listing alone would make the vehicle look complete."""
    vehicle = Rosbridge(POSE_ONLY, pose_hz=20).start()
    try:
        with observer(vehicle.url, {FRAME: FRAME_TYPE, MISSION: STRING_TYPE}):
            status, out, _ = run(
                ["vehicle-check", vehicle.url, "--window", "1.5", "--timeout", "1"], capsys
            )
        assert vehicle.frame_count() == 0  # nobody to answer: nothing sent
    finally:
        vehicle.stop()
    assert status == 1
    table = rows(out)
    result, reason = table["onboard agent"]
    assert result == "fail" and reason.startswith("no onboard agent (")
    assert reason.endswith("the console: telemetry_only")
    for missing in ("/nemesys/mission", "/nemesys/status"):
        result, reason = table[f"topic {missing}"]
        assert result == "fail" and reason.startswith(f"missing: no node publishes {missing}")
    assert table["topic /nemesys/frame"] == (
        "fail",
        "missing: /nemesys/frame has no subscriber but rosbridge's own node "
        "(/rosbridge_websocket), there for its clients: the topic exists only because a "
        "client uses it",
    )
    assert table["topic /nemesys/pose"] == (
        "pass",
        "geometry_msgs/msg/PoseStamped, published by /navigation",
    )
    assert table["pose rate"][0] == "pass"
    assert table["status rate"][0] == "fail"
    assert table["ack path (probe)"] == (
        "skipped",
        "no onboard agent to answer it; nothing was sent",
    )
    summary = out.splitlines()[-1]
    assert summary.startswith("FAIL: ") and "onboard agent" in summary


@pytest.mark.slow  # a probe's real listening window
def test_a_bridge_under_another_name_is_still_not_the_vehicle(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Launched as /vehicle/bridge, rosbridge is known by its connected_clients topic."""
    vehicle = Rosbridge(POSE_ONLY, pose_hz=20, bridge_node="/vehicle/bridge").start()
    try:
        with observer(vehicle.url, {FRAME: FRAME_TYPE, MISSION: STRING_TYPE}):
            status, out, _ = run(
                ["vehicle-check", vehicle.url, "--window", "1", "--timeout", "1"], capsys
            )
    finally:
        vehicle.stop()
    assert status == 1
    table = rows(out)
    assert table["onboard agent"][0] == "fail"
    result, reason = table["topic /nemesys/frame"]
    assert result == "fail" and "rosbridge's own node (/vehicle/bridge)" in reason


@pytest.mark.slow  # a probe's real listening window
def test_a_receiver_only_vehicle_is_not_passed_over_rosbridge(
    capsys: pytest.CaptureFixture[str],
) -> None:
    vehicle = Rosbridge(RECEIVER_ONLY, pose_hz=20).start()
    try:
        status, out, _ = run(
            ["vehicle-check", vehicle.url, "--window", "1", "--timeout", "1"], capsys
        )
        assert vehicle.frame_count() == 0
    finally:
        vehicle.stop()
    assert status == 1
    table = rows(out)
    assert table["onboard agent"][0] == "pass"
    result, reason = table["ack path (probe)"]
    assert result == "fail" and reason.startswith(
        "receiver-only: frames cannot be probed over rosbridge"
    )
    assert "check through the modem path: nemesys vehicle-check URL --modem tcp://" in reason


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
    assert table["rosapi"] == (
        "fail",
        "no answer from /rosapi/topics in 0.5 s (is rosapi running?)",
    )
    assert table["topic /nemesys/mission"][0] == "skipped"
    assert table["onboard agent"][0] == "skipped"
    # rosapi cannot tell: the probe is sent all the same, and nothing answers it
    result, reason = table["ack path (probe)"]
    # (the probe waits at least the contract's deadline, whatever --timeout says)
    assert result == "fail" and reason.endswith(
        "no acknowledgement within 1 s (the contract's deadline 1 s)"
    )


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


@pytest.mark.parametrize(
    ("modem", "why"),
    [
        ("ws://127.0.0.1:9090", "--modem takes an ME modem"),
        ("127.0.0.1:4001", "no scheme"),
        ("tcp://127.0.0.1", "no port"),
    ],
)
def test_a_modem_that_is_not_one_is_bad_usage(
    modem: str, why: str, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run(["vehicle-check", "ws://127.0.0.1:1", "--modem", modem], capsys)
    assert status == 2 and out == ""
    assert err.startswith("nemesys vehicle-check: ") and why in err, err


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
