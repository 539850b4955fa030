"""Numbers written as text: ASCII decimal digits only (the codec's parameters, and every
setting and option the console reads from a string)."""

from __future__ import annotations

import pytest

from codec import EncodeError, ParamValue, encode_frame, int_from_text, number_from_text
from codec._number_text import ASCII_DIGITS

CIRCLE: dict[str, ParamValue] = {"speed": 0.18, "depth": 3, "direction": "cw"}


@pytest.mark.parametrize(
    ("text", "value"),
    [("10", 10.0), (" 2.5\t", 2.5), ("-1.5e-3", -1.5e-3), ("+3", 3.0), (".5", 0.5), ("12.", 12.0)],
)
def test_decimal_text_is_a_number(text: str, value: float) -> None:
    assert number_from_text(text) == value


@pytest.mark.parametrize(
    "text",
    [
        "\u0661\u0660",  # ARABIC-INDIC ONE ZERO: float() reads 10.0
        "\uff11\uff10",  # FULLWIDTH ONE ZERO: float() reads 10.0
        "1\u0660",  # an ASCII digit then an Arabic-Indic one
        "\u00b2",  # SUPERSCRIPT TWO
        "\u20031",  # an EM SPACE before the digit: float() strips it
        "\ud800",  # a lone surrogate
    ],
)
def test_non_ascii_digits_are_refused_saying_so(text: str) -> None:
    with pytest.raises(ValueError, match=ASCII_DIGITS):
        number_from_text(text)
    with pytest.raises(ValueError, match=ASCII_DIGITS):
        int_from_text(text)


@pytest.mark.parametrize("text", ["", "nan", "inf", "-Infinity", "1_0", "0x10", "1e", "1.2.3"])
def test_other_forms_python_reads_are_refused(text: str) -> None:
    with pytest.raises(ValueError, match="expected a decimal number"):
        number_from_text(text)


@pytest.mark.parametrize("text", ["1.0", "1e3", "1_0", "9" * 21, ""])
def test_whole_numbers_are_ascii_digits_only(text: str) -> None:
    with pytest.raises(ValueError, match="expected a whole number"):
        int_from_text(text)
    assert int_from_text(" -42 ") == -42


@pytest.mark.parametrize("text", ["\u0661\u0660", "\uff11\uff10"])
def test_a_parameter_in_non_ascii_digits_is_an_encode_error_naming_it(text: str) -> None:
    assert float("\u0661\u0660") == 10.0  # what the codec used to send
    with pytest.raises(EncodeError) as err:
        encode_frame("circle", {**CIRCLE, "radius": text})
    assert err.value.field == "radius"
    assert ASCII_DIGITS in str(err.value)
    assert encode_frame("circle", {**CIRCLE, "radius": "10"}).command.params["radius"] == 10
