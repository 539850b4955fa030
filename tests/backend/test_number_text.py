"""Numbers the console reads from text outside a request are ASCII digits too: settings
(environment, settings file), command-line options, parameters given on the command line,
and the serial baud rates of the GPS and the modem. Python's ``int()`` and ``float()`` read
Arabic-Indic and fullwidth digits; each of these refuses them saying the rule."""

from __future__ import annotations

import io

import pytest
from pydantic import ValidationError

from backend.chart.gps import parse_gps
from backend.settings import Settings
from cli.common import EXIT_USAGE
from cli.main import main
from codec import ASCII_DIGITS
from station.transmit import open_transmitter
from tests.backend.conftest import clear_nemesys_env

TEN = "\u0661\u0660"  # ARABIC-INDIC ONE, ZERO: int() reads 10
FULLWIDTH_TEN = "\uff11\uff10"


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    status = main(argv, out=io.StringIO())
    return status, capsys.readouterr().err


@pytest.mark.parametrize(
    ("name", "value"),
    [("NEMESYS_LINK_BER", "\u0660"), ("NEMESYS_DELIVERY_TARGET", "\u0660.9")],
)
def test_a_number_setting_in_other_digits_is_refused_saying_so(
    monkeypatch: pytest.MonkeyPatch, name: str, value: str
) -> None:
    clear_nemesys_env(monkeypatch)
    monkeypatch.setenv(name, value)
    with pytest.raises(ValidationError) as err:
        Settings()
    assert ASCII_DIGITS in str(err.value)


def test_the_console_names_the_setting_and_the_rule(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """pydantic reads the integer settings (it refuses other digits, saying only "unable to
    parse"); ``nemesys console`` says the rule before starting anything."""
    clear_nemesys_env(monkeypatch)
    monkeypatch.setenv("NEMESYS_PORT", "8" + TEN)
    monkeypatch.setenv("NEMESYS_TARGET", "nowhere")  # were the port taken: no console starts
    status, err = run(["console"], capsys)
    assert status == EXIT_USAGE
    assert err.startswith("nemesys console: setting port:") and ASCII_DIGITS in err


@pytest.mark.parametrize(
    "argv",
    [
        ["console", "--port", TEN],
        ["console", "--time-scale", FULLWIDTH_TEN],
        ["sim", "--ber", "\u0660"],
        ["sim", "--port", TEN],
        ["scenario", "wreck", "--seed", TEN],
        ["encode", "square", "speed=0.5", "depth=2", "side_span=5", "--bitrate", TEN],
        ["send", "surface", "--timeout", TEN],
        ["vehicle-check", "--timeout", TEN],
    ],
)
def test_options_take_ascii_digits_only(
    argv: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    # were the number taken, argparse would refuse the unknown option: nothing would run
    status, err = run([*argv, "--no-such-option"], capsys)
    assert status == EXIT_USAGE
    assert ASCII_DIGITS in err, err


def test_a_parameter_on_the_command_line_in_other_digits_is_refused(
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = ["encode", "square", "speed=0.5", f"depth={TEN}", "side_span=5", "direction=cw"]
    status, err = run(argv, capsys)
    assert status == EXIT_USAGE
    assert "depth" in err and ASCII_DIGITS in err


def test_baud_rates_are_ascii_digits() -> None:
    with pytest.raises(ValueError, match="ASCII digits"):
        parse_gps(f"serial:///dev/ttyUSB1?baud=4{TEN}0")
    with pytest.raises(ValueError, match="ASCII digits"):
        open_transmitter(f"serial:///dev/ttyUSB0?baud=96{TEN}")
    gps = parse_gps("serial:///dev/ttyUSB1?baud=4800")
    assert gps is not None and gps.baud == 4800
