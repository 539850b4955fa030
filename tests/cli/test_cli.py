"""The ``nemesys`` CLI: output contracts and every bad-input path (exit status, one-line
message naming what was wrong, never a traceback)."""

from __future__ import annotations

import io
import json
import subprocess
import sys
from typing import Any

import pytest

from cli.common import EXIT_OK, EXIT_REJECTED, EXIT_USAGE
from cli.main import main
from codec import DICTIONARY, FRAME_BITS, decode_frame, encode_frame, markdown_tables

SQUARE = ["square", "speed=0.5", "depth=2", "side_span=12.34", "direction=cw"]


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    out = io.StringIO()
    status = main(argv, out=out)
    return status, out.getvalue(), capsys.readouterr().err


def encode_json(args: list[str], capsys: pytest.CaptureFixture[str]) -> dict[str, Any]:
    status, out, err = run(["encode", *args, "--json"], capsys)
    assert status == EXIT_OK, err
    doc: dict[str, Any] = json.loads(out)
    return doc


# --- patterns -----------------------------------------------------------------------------


def test_patterns_text_lists_every_field_with_range_step_and_error(
    capsys: pytest.CaptureFixture[str],
) -> None:
    status, out, _ = run(["patterns"], capsys)
    assert status == EXIT_OK
    for pattern in DICTIONARY.values():
        assert f"{pattern.id:>2} {pattern.name}" in out
        block = out.split(f"{pattern.id:>2} {pattern.name}", 1)[1].splitlines()
        for j, f in enumerate(pattern.fields, start=1):
            line = next(ln for ln in block if ln.startswith(f"     j{j} {f.name} "))
            assert f.scale.range_text(f.unit) in line
            assert f.scale.describe() in line
            assert f.scale.error_text(f.unit) in line


def test_patterns_json_and_markdown(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, _ = run(["patterns", "--json"], capsys)
    assert status == EXIT_OK
    doc = json.loads(out)
    assert [p["name"] for p in doc] == [
        "straight", "square", "lawnmower", "circle", "spiral", "helix", "hover", "box_orbit",
        "surface",
    ]  # fmt: skip
    radius = doc[3]["fields"][2]
    assert radius["name"] == "radius" and radius["unit"] == "m"
    assert radius["min"] <= 0.5 and radius["max"] >= 200 and radius["max_rel_error"] < 0.025
    status, out, _ = run(["patterns", "--markdown"], capsys)
    assert out == markdown_tables() + "\n"


# --- encode -------------------------------------------------------------------------------


def test_encode_text_shows_snaps_sections_hex_and_airtime(
    capsys: pytest.CaptureFixture[str],
) -> None:
    status, out, _ = run(["encode", *SQUARE], capsys)
    assert status == EXIT_OK
    enc = encode_frame("square", speed=0.5, depth=2, side_span=12.34, direction="cw")
    assert "side_span       12.5 m   (requested 12.34 m)" in out
    assert enc.frame.grouped(enc.command.pattern) in out
    assert f"hex      {enc.frame.hex}" in out
    assert "airtime  2.778 ms at 36000 b/s" in out
    assert "parity          bits 80-95" in out


def test_encode_json_contract(capsys: pytest.CaptureFixture[str]) -> None:
    doc = encode_json(SQUARE, capsys)
    assert doc["pattern"] == "square"
    assert doc["params"] == {"speed": 0.5, "depth": 2.0, "side_span": 12.5, "direction": "cw"}
    assert doc["requested"]["side_span"] == 12.34
    assert doc["snapped"] == ["side_span: requested 12.34 m, sent 12.5 m"]
    assert len(doc["bits"]) == FRAME_BITS and set(doc["bits"]) <= {"0", "1"}
    assert int(doc["hex"], 16) == int(doc["bits"], 2)
    assert doc["airtime_ms"] == pytest.approx(100 / 36_000 * 1e3)
    assert "".join(s["bits"] for s in doc["sections"]) == doc["bits"]
    assert decode_frame(doc["bits"]).command.params == doc["params"]


def test_encode_bitrate_changes_airtime(capsys: pytest.CaptureFixture[str]) -> None:
    doc = encode_json([*SQUARE, "--bitrate", "9600"], capsys)
    assert doc["airtime_ms"] == pytest.approx(100 / 9600 * 1e3)


def test_surface_takes_no_parameters(capsys: pytest.CaptureFixture[str]) -> None:
    doc = encode_json(["surface"], capsys)
    assert doc["params"] == {} and doc["bits"][24:28] == "1111"


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["encode", "triangle"], ["unknown pattern 'triangle'", "square (1)"]),
        (["encode", "square", "speed=0.5"], ["square needs depth (0 to 107.5 m)", "direction"]),
        ([*["encode", *SQUARE], "radius=3"], ["no parameter 'radius'", "side_span"]),
        (
            ["encode", "square", "speed=3", "depth=2", "side_span=5", "direction=cw"],
            ["speed = 3 m/s is out of range", "0 to 2.55 m/s"],
        ),
        (
            ["encode", "square", "speed=fast", "depth=2", "side_span=5", "direction=cw"],
            ["speed must be a number in m/s", "'fast'"],
        ),
        (
            ["encode", "square", "speed=nan", "depth=2", "side_span=5", "direction=cw"],
            ["speed must be a finite number"],
        ),
        (
            ["encode", "square", "speed=1", "depth=2", "side_span=5", "direction=up"],
            ["direction = 'up' is not allowed", "cw, ccw"],
        ),
        (
            [
                "encode",
                "lawnmower",
                "speed=1",
                "depth=2",
                "sweep_length=5",
                "lane_spacing=1",
                "laps=2.5",
            ],
            ["laps = 2.5 is not a whole number", "1 to 255"],
        ),
        (["encode", "square", "speed"], ["parameters are name=value, got 'speed'"]),
        (["encode", "square", "speed=1", "speed=2"], ["parameter 'speed' given twice"]),
    ],
)
def test_encode_bad_input_exits_2_with_a_clear_message(
    argv: list[str], expected: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run(argv, capsys)
    assert status == EXIT_USAGE
    assert out == ""
    assert err.count("\n") == 1 and "Traceback" not in err
    for text in expected:
        assert text in err


@pytest.mark.parametrize("rate", ["0", "-9600", "abc", "inf"])
def test_encode_bad_bitrate(rate: str, capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run(["encode", *SQUARE, "--bitrate", rate], capsys)
    assert status == EXIT_USAGE and out == ""
    assert "bit rate must be" in err


def test_usage_errors(capsys: pytest.CaptureFixture[str]) -> None:
    assert run([], capsys)[0] == EXIT_USAGE
    assert run(["frobnicate"], capsys)[0] == EXIT_USAGE
    assert run(["bench", "nothing"], capsys)[0] == EXIT_USAGE
    assert run(["patterns", "--json", "--markdown"], capsys)[0] == EXIT_USAGE


# --- decode -------------------------------------------------------------------------------


def _flip(bits: str, *positions: int) -> str:
    chars = list(bits)
    for p in positions:
        chars[p] = "1" if chars[p] == "0" else "0"
    return "".join(chars)


def test_decode_bits_hex_and_grouped_tokens(capsys: pytest.CaptureFixture[str]) -> None:
    enc = encode_frame("circle", speed=1, depth=3, radius=7, direction="ccw")
    expected = "circle speed=1 m/s depth=3 m radius=7 m direction=ccw  (corrected 0 bits)\n"
    assert run(["decode", enc.frame.bits], capsys)[:2] == (EXIT_OK, expected)
    assert run(["decode", enc.frame.hex], capsys)[:2] == (EXIT_OK, expected)
    tokens = enc.frame.grouped(enc.command.pattern).split()
    assert run(["decode", *tokens], capsys)[:2] == (EXIT_OK, expected)
    status, out, _ = run(["decode", _flip(enc.frame.bits, 30, 90), "--json"], capsys)
    assert status == EXIT_OK
    doc = json.loads(out)
    assert doc["pattern"] == "circle" and doc["corrected"] == 2
    assert doc["params"] == {"speed": 1.0, "depth": 3.0, "radius": 7.0, "direction": "ccw"}


@pytest.mark.parametrize(
    ("frame", "reason"),
    [
        ("0101", "expected 100 binary digits or 25 hex digits, got 4 characters"),
        ("2" * 100, "may hold only 0 and 1, found '2'"),
        ("g" * 25, "is not 25 hex digits"),
        ("", "got 0 characters"),
    ],
)
def test_decode_malformed_exits_1_with_reason(
    frame: str, reason: str, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run(["decode", frame], capsys)
    assert status == EXIT_REJECTED and out == ""
    assert err.startswith("nemesys decode: rejected: malformed frame") and reason in err


def test_decode_uncorrectable_frame_exits_1(capsys: pytest.CaptureFixture[str]) -> None:
    bits = encode_frame("surface").frame.bits
    status, out, err = run(["decode", _flip(bits, 30, 40, 50)], capsys)
    assert status == EXIT_REJECTED and out == ""
    assert "rejected:" in err and "Traceback" not in err


def test_decode_stdin_prints_one_result_per_line(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    good = encode_frame("hover", duration=30, depth=1, heading=90).frame.bits
    lines = [good, "", "# a comment", "zz", _flip(good, 40), _flip(good, 30, 40, 50, 60)]
    monkeypatch.setattr(sys, "stdin", io.StringIO("\n".join(lines) + "\n"))
    status, out, _ = run(["decode", "-", "--json"], capsys)
    assert status == EXIT_REJECTED  # at least one frame was rejected
    results = [json.loads(line) for line in out.splitlines()]
    assert [r["line"] for r in results] == [1, 4, 5, 6]
    assert results[0]["pattern"] == "hover" and results[0]["corrected"] == 0
    assert results[1]["reason"] == "malformed" and "error" in results[1]
    assert results[2]["corrected"] == 1
    assert "error" in results[3]
    monkeypatch.setattr(sys, "stdin", io.StringIO(good + "\n" + good + "\n"))
    status, out, _ = run(["decode", "-"], capsys)
    assert status == EXIT_OK and out.count("line ") == 2


def test_console_script_runs_without_traceback() -> None:
    """The real entry point, in a subprocess, including a rejected frame from stdin."""
    cmd = [sys.executable, "-m", "cli.main"]
    ok = subprocess.run(
        [*cmd, "encode", *SQUARE, "--json"], check=False, capture_output=True, text=True
    )
    assert ok.returncode == 0
    bits = json.loads(ok.stdout)["bits"]
    bad = subprocess.run(
        [*cmd, "decode", "-"],
        input=f"{bits}\nnot-a-frame\n",
        check=False,
        capture_output=True,
        text=True,
    )
    assert bad.returncode == EXIT_REJECTED
    assert bad.stdout.splitlines()[0].startswith("line 1: square")
    assert bad.stdout.splitlines()[1].startswith("line 2: rejected: malformed frame")
    assert "Traceback" not in bad.stderr
