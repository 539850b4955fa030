"""Numbers written as text: ASCII decimal digits only, for every number the console reads from
a string (a parameter given as text, a setting, a command-line option).

Python's ``float()`` and ``int()`` are too lax for input: they take any Unicode decimal digit
(Arabic-Indic U+0661 U+0660, fullwidth U+FF11 U+FF10 read as 10), ``_`` between digits,
Unicode spaces around the number, and ``nan``/``inf``. What a console shows and logs must be
what was sent, so only the plain decimal form is a number here: an optional sign, ASCII
digits 0-9, an optional point and an optional exponent (``-1.5e3``), with ASCII spaces or
tabs around it.
"""

from __future__ import annotations

import re
from argparse import ArgumentTypeError

_DECIMAL = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_INTEGER = re.compile(r"[+-]?[0-9]+")
#: Longest text quoted back in an error message (characters).
_QUOTE_CHARS = 40
#: The one rule, in the words every error message uses.
ASCII_DIGITS = "only ASCII digits 0-9 are allowed"


class NumberTextError(ValueError, ArgumentTypeError):
    """Text that is not a number. Also an ``ArgumentTypeError``: as the ``type`` of a
    command-line option, :func:`number_from_text` and :func:`int_from_text` have argparse
    print this message (it prints only "invalid value" for a plain ``ValueError``)."""


def _refuse(text: str, what: str) -> NumberTextError:
    shown = text if len(text) <= _QUOTE_CHARS else text[: _QUOTE_CHARS - 1] + "…"
    if not text.isascii():
        # ascii() so the message itself is plain text whatever was given (even a lone
        # surrogate, which no encoder writes)
        return NumberTextError(f"{ASCII_DIGITS} in {what}, got {shown!a}")
    return NumberTextError(f"expected {what}, got {shown!r}")


def number_from_text(text: str) -> float:
    """``text`` as a float: a decimal number in ASCII digits (``12``, ``-0.5``, ``1e3``).
    The result may be infinite (``1e400``): the caller checks its range.

    Raises:
        NumberTextError: (a ``ValueError``) anything else, the message saying what is
            allowed (non-ASCII digits: :data:`ASCII_DIGITS`).
    """
    core = text.strip(" \t")
    if not _DECIMAL.fullmatch(core):
        raise _refuse(text, "a decimal number")
    return float(core)


def int_from_text(text: str) -> int:
    """``text`` as an int: ASCII digits with an optional sign (``8000``, ``-1``), at most 20
    digits (no integer the console reads is longer; ``int()`` of a long text is slow).

    Raises:
        NumberTextError: (a ``ValueError``) anything else, the message saying what is
            allowed.
    """
    core = text.strip(" \t")
    if not _INTEGER.fullmatch(core) or len(core.lstrip("+-")) > 20:
        raise _refuse(text, "a whole number")
    return int(core)
