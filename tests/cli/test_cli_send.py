"""``nemesys send``: what it prints, what reaches the target (loop://, a pty, a fake
rosbridge), the exit status of every outcome, and one-line errors for bad input. Only
127.0.0.1 is contacted."""

from __future__ import annotations

import io
import json
import os
import select
import subprocess
import sys
import time
from collections.abc import Iterator
from typing import Any

import pytest

from bench._gateway import FrameGateway
from cli.common import EXIT_OK, EXIT_REJECTED, EXIT_USAGE
from cli.main import build_parser, main
from cli.send import DEFAULT_SEND_TIMEOUT_S, DEFAULT_SEND_TO
from codec import FRAME_BYTES, GUARD_BITS, Frame, decode_frame, encode_frame
from station.transmit import DEFAULT_ACK_TIMEOUT_S, DEFAULT_ROSBRIDGE_URL
from tests.rosbridge.fake_rosbridge import FakeRosbridge, ack_for, mission
from tests.rosbridge.helpers import free_port

CIRCLE = ["circle", "speed=0.18", "depth=2", "radius=5.1", "direction=cw"]
SENT = encode_frame("circle", speed=0.18, depth=2, radius=5.1, direction="cw")


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    out = io.StringIO()
    status = main(argv, out=out)
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return status, out.getvalue(), err


def one_line(err: str) -> str:
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("nemesys send: ")
    return lines[0]


def decoded_ack(data: bytes, **fields: Any) -> dict[str, Any]:
    """The onboard agent's acknowledgement shape, with the command decoded from ``data``."""
    command = decode_frame(data).command
    cmd = {"pattern": command.pattern.name, "pattern_id": command.pattern.id}
    return ack_for(data, command={**cmd, "params": dict(command.params)}, **fields)


def accept(data: bytes) -> list[dict[str, Any] | str]:
    return [mission(decoded_ack(data))]


@pytest.fixture
def fake() -> Iterator[FakeRosbridge]:
    with FakeRosbridge(accept) as server:
        yield server


# --- targets without acknowledgements -----------------------------------------------------


def test_send_to_loop_prints_what_was_sent(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run(["send", *CIRCLE, "--to", "loop://"], capsys)
    assert status == EXIT_OK and err == ""
    lines = out.splitlines()
    assert lines[0] == "send     circle (ID 3) to loop://"
    assert "  radius          5 m   (requested 5.1 m)" in lines
    assert "  direction       cw" in lines
    assert f"hex      {SENT.frame.hex}" in lines
    assert "airtime  2.778 ms at 36000 b/s" in lines
    sent = next(ln for ln in lines if ln.startswith("sent     "))
    assert sent.endswith("+00:00 via serial")
    assert lines[-1] == "         wrote 13 bytes; the modem gives no acknowledgement"


def test_send_to_a_pty_writes_the_frame_bytes(capsys: pytest.CaptureFixture[str]) -> None:
    master, slave = os.openpty()
    try:
        target = f"serial://{os.ttyname(slave)}?baud=57600"
        status, out, _ = run(["send", *CIRCLE, "--to", target], capsys)
        ready, _, _ = select.select([master], [], [], 2)
        got = os.read(master, 64) if ready else b""
    finally:
        os.close(master)
        os.close(slave)
    assert status == EXIT_OK
    assert got == SENT.frame.to_bytes() and len(got) == FRAME_BYTES
    assert f"to {target}" in out.splitlines()[0]


def test_send_missing_device_fails_with_the_reason(
    capsys: pytest.CaptureFixture[str], tmp_path: Any
) -> None:
    device = tmp_path / "ttyUSB9"
    status, out, err = run(["send", *CIRCLE, "--to", f"serial://{device}"], capsys)
    assert status == EXIT_REJECTED
    line = one_line(err)
    assert line.startswith("nemesys send: failed: port not found: ") and str(device) in line
    assert "hex      " in out and "sent " not in out


# --- rosbridge ----------------------------------------------------------------------------


def test_send_accepted_prints_the_acknowledgement(
    fake: FakeRosbridge, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run(["send", *CIRCLE, "--to", fake.url, "--timeout", "2"], capsys)
    assert status == EXIT_OK and err == ""
    assert fake.published() == [SENT.frame.to_bytes()]
    lines = out.splitlines()
    assert lines[0] == f"send     circle (ID 3) to {fake.url}"
    assert any(ln.startswith("sent     ") and ln.endswith("via rosbridge") for ln in lines)
    assert "accepted circle speed=0.18 m/s depth=2 m radius=5 m direction=cw  (ack #1)" in lines
    assert "         corrected 0 bits, sync errors 0" in lines
    assert lines[-1] == "         decode 0.25 ms, replan 3.50 ms, 12 waypoints"


def test_send_rejected_exits_1_with_the_reason(capsys: pytest.CaptureFixture[str]) -> None:
    def reject(data: bytes) -> list[dict[str, Any] | str]:
        ack = decoded_ack(data, seq=5, outcome="rejected", reason="limit_violation")
        ack.update(detail="depth 2 m is above the 5 m floor", field="depth", command=None)
        return [mission(ack)]

    with FakeRosbridge(reject) as server:
        status, out, err = run(["send", *CIRCLE, "--to", server.url], capsys)
    assert status == EXIT_REJECTED
    assert (
        "rejected limit_violation (field depth): depth 2 m is above the 5 m floor  (ack #5)"
        in out.splitlines()
    )
    assert one_line(err) == (
        "nemesys send: rejected: limit_violation: depth 2 m is above the 5 m floor"
    )


def test_send_bit_errors_show_the_match(capsys: pytest.CaptureFixture[str]) -> None:
    def corrupt(data: bytes) -> list[dict[str, Any] | str]:
        rx = Frame((int.from_bytes(data, "big") >> 4) ^ (1 << (GUARD_BITS + 7)))
        ack = decoded_ack(data, corrected_bits=1, frame_hex=rx.hex, duplicate=True)
        ack.update(replan_latency_ms=None, waypoints=None)
        return [mission(ack)]

    with FakeRosbridge(corrupt) as server:
        status, out, _ = run(["send", *CIRCLE, "--to", server.url], capsys)
    assert status == EXIT_OK
    lines = out.splitlines()
    assert "(ack #1, already active: not replanned)" in lines[-4]
    assert lines[-3] == "         corrected 1 bit, sync errors 0"
    assert lines[-2] == "         decode 0.25 ms"
    assert lines[-1] == "         acknowledged (the frame arrived with bit errors)"


def test_send_timeout_exits_1(capsys: pytest.CaptureFixture[str]) -> None:
    with FakeRosbridge(respond=None) as server:
        status, out, err = run(["send", *CIRCLE, "--to", server.url, "--timeout", "0.2"], capsys)
        assert len(server.published()) == 1
    assert status == EXIT_REJECTED
    assert any(ln.startswith("sent     ") for ln in out.splitlines())
    assert one_line(err) == (
        "nemesys send: failed: timeout: frame published, no acknowledgement within 0.2 s"
    )


def test_send_without_waiting(capsys: pytest.CaptureFixture[str]) -> None:
    with FakeRosbridge(respond=None) as server:
        status, out, err = run(["send", *CIRCLE, "--to", server.url, "--timeout", "0"], capsys)
    assert status == EXIT_OK and err == ""
    assert out.splitlines()[-1] == "         published; not waiting for an acknowledgement"


def test_send_waits_for_the_vehicles_subscriber_then_publishes_at_once(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with FakeRosbridge(accept) as server:
        start = time.monotonic()
        status, _, err = run(["send", *CIRCLE, "--to", server.url, "--json"], capsys)
        elapsed_s = time.monotonic() - start
        ops = server.ops()
    assert status == EXIT_OK and err == ""
    assert ops.index("call_service") < ops.index("publish")  # asked rosapi first
    assert elapsed_s < 1.0  # the subscriber was there: no waiting for the 1 s bound


@pytest.mark.slow  # the transmitter's real 1 s bound
def test_send_without_a_subscriber_publishes_after_1_s_and_says_so(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with FakeRosbridge(respond=None, subscribers=[]) as server:
        start = time.monotonic()
        status, out, err = run(["send", *CIRCLE, "--to", server.url, "--timeout", "0.2"], capsys)
        elapsed_s = time.monotonic() - start
        assert server.published() == [SENT.frame.to_bytes()]
    assert elapsed_s >= 1.0 + 0.2
    assert status == EXIT_REJECTED
    assert any(ln.startswith("sent     ") for ln in out.splitlines())
    assert one_line(err) == (
        "nemesys send: failed: timeout: frame published, no acknowledgement within 0.2 s; "
        "no subscriber to /nemesys/frame after 1 s: the frame may be lost"
    )


@pytest.mark.slow  # the transmitter's real 1 s bound
def test_send_without_waiting_still_says_the_frame_may_be_lost(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with FakeRosbridge(respond=None, subscribers=[]) as server:
        status, out, err = run(
            ["send", *CIRCLE, "--to", server.url, "--timeout", "0", "--json"], capsys
        )
    assert status == EXIT_OK and err == ""
    doc = json.loads(out)
    assert doc["warning"] == "no subscriber to /nemesys/frame after 1 s: the frame may be lost"
    assert doc["detail"].endswith(doc["warning"])


def test_send_refused_exits_1_naming_the_target(capsys: pytest.CaptureFixture[str]) -> None:
    url = f"ws://127.0.0.1:{free_port()}"
    status, out, err = run(["send", *CIRCLE, "--to", url], capsys)
    assert status == EXIT_REJECTED
    assert one_line(err) == f"nemesys send: failed: connection refused: {url}: Connection refused"
    assert "sent " not in out


def test_send_json(fake: FakeRosbridge, capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run(["send", *CIRCLE, "--to", fake.url, "--json"], capsys)
    assert status == EXIT_OK and err == ""
    doc = json.loads(out)
    assert doc["pattern"] == "circle" and doc["params"]["radius"] == 5
    assert doc["requested"]["radius"] == 5.1
    assert doc["snapped"] == ["radius: requested 5.1 m, sent 5 m"]
    assert doc["hex"] == SENT.frame.hex and doc["to"] == fake.url
    assert doc["ok"] is True and doc["transport"] == "rosbridge" and doc["reason"] is None
    assert isinstance(doc["sent_t"], float)
    assert doc["ack_match"] == "exact" and doc["ack"]["frame_hex"] == SENT.frame.hex
    assert doc["ack"]["outcome"] == "accepted"
    assert doc["warning"] is None


def test_send_json_failure_still_prints_the_document(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run(
        ["send", *CIRCLE, "--to", f"tcp://127.0.0.1:{free_port()}", "--json"], capsys
    )
    assert status == EXIT_REJECTED
    doc = json.loads(out)
    assert doc["ok"] is False and doc["reason"] == "connection refused" and doc["sent_t"] is None
    assert one_line(err).startswith("nemesys send: failed: connection refused")


# --- bad input ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["send", *CIRCLE, "--to", "ftp://x:1"], "--to: bad transmitter target 'ftp://x:1'"),
        (["send", *CIRCLE, "--to", "/dev/ttyUSB0"], "write serial:///dev/ttyUSB0"),
        (["send", *CIRCLE, "--to", "tcp://127.0.0.1"], "no port"),
        (["send", *CIRCLE, "--to", "serial:///dev/x?baud=z"], "baud must be"),
        (["send", "orbit", "speed=1", "--to", "loop://"], "unknown pattern 'orbit'"),
        (["send", "circle", "speed=abc", "depth=2", "radius=5", "direction=cw"], "speed"),
        (["send", "circle", "speed=0.5", "--to", "loop://"], "circle needs depth"),
        (["send", "circle", "speed", "--to", "loop://"], "name=value, got 'speed'"),
    ],
)
def test_bad_input_is_one_line_exit_2(
    argv: list[str], needle: str, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run(argv, capsys)
    assert status == EXIT_USAGE
    assert needle in one_line(err)
    assert out == ""  # nothing claimed as sent


@pytest.mark.parametrize("value", ["-1", "soon", "inf"])
def test_bad_timeout_is_a_usage_error(value: str, capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run(["send", *CIRCLE, "--to", "loop://", "--timeout", value], capsys)
    assert status == EXIT_USAGE and out == ""
    assert "argument --timeout: timeout must be" in err.splitlines()[-1]


def test_defaults_match_the_transmitter_module() -> None:
    args = build_parser().parse_args(["send", "surface"])
    assert args.to == DEFAULT_SEND_TO == DEFAULT_ROSBRIDGE_URL == "ws://127.0.0.1:9090"
    assert args.timeout == DEFAULT_SEND_TIMEOUT_S == DEFAULT_ACK_TIMEOUT_S


def test_console_script_failure_is_one_line() -> None:
    """A real process: no logging noise or traceback besides the one error line."""
    url = f"ws://127.0.0.1:{free_port()}"
    proc = subprocess.run(
        [sys.executable, "-m", "cli.main", "send", *CIRCLE, "--to", url],
        check=False,
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert proc.returncode == EXIT_REJECTED
    assert proc.stderr.splitlines() == [
        f"nemesys send: failed: connection refused: {url}: Connection refused"
    ]
    assert proc.stdout.splitlines()[0] == f"send     circle (ID 3) to {url}"


# --- the console's send policy, run in this process --------------------------------------------


@pytest.fixture
def modem() -> Iterator[FrameGateway]:
    """A one-way TCP modem gateway on loopback that decodes every byte it is given."""
    gateway = FrameGateway()
    try:
        yield gateway
    finally:
        gateway.close()


def test_send_refuses_the_depth_rating_whatever_the_override(
    capsys: pytest.CaptureFixture[str], modem: FrameGateway
) -> None:
    for extra in ([], ["--override"]):
        argv = ["send", "straight", "speed=0.18", "depth=105", "heading=0", "duration=60"]
        status, out, err = run([*argv, "--to", modem.target, "--timeout", "0", *extra], capsys)
        assert status == EXIT_USAGE and "refused, nothing transmitted" in err
        assert "depth" in err and "100 m" in err
        assert out == ""
    assert modem.connections == 0 and modem.count() == 0


def test_send_needs_the_override_for_a_soft_violation(
    capsys: pytest.CaptureFixture[str], modem: FrameGateway
) -> None:
    fast = ["send", "circle", "speed=0.5", "depth=2", "radius=5", "direction=cw"]
    status, _out, err = run([*fast, "--to", modem.target, "--timeout", "0"], capsys)
    assert status == EXIT_USAGE and "--override accepts it" in err and "top speed" in err
    assert modem.count() == 0
    status, out, err = run([*fast, "--to", modem.target, "--timeout", "0", "--override"], capsys)
    assert status == EXIT_OK, err
    assert any(line.startswith("override speed 0.5 m/s exceeds") for line in out.splitlines())
    sent = encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw")
    wait_for(lambda: modem.count(sent.frame.hex) == 1)


def wait_for(probe: Any, timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not probe():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.01)


def test_send_refuses_where_consoles_share_a_mission_log(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """With a shared log only a console may send (it checks who is in control, and logs)."""
    monkeypatch.setenv("NEMESYS_DATABASE_URL", "postgresql://nemesys@127.0.0.1:1/missions")
    status, out, err = run(["send", *CIRCLE, "--to", "loop://"], capsys)
    assert status == EXIT_USAGE and out == ""
    line = one_line(err)
    assert "NEMESYS_DATABASE_URL is set" in line and "POST /api/commands" in line
    assert line.endswith("nothing was transmitted")
