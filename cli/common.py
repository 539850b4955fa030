"""What the ``nemesys`` subcommands share: exit statuses, the usage error, parameters given
as ``name=value``, and how an encoded command is printed."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import Any, TextIO

from codec import Encoded, Snap, number_from_text
from codec._fields import fmt
from onboard.agent import command_json

EXIT_OK = 0
EXIT_REJECTED = 1
EXIT_USAGE = 2
EXIT_INTERNAL = 70  # EX_SOFTWARE


class UsageError(Exception):
    """Bad command-line input; reported on stderr with exit status 2."""


def parse_assignments(items: Sequence[str]) -> dict[str, str]:
    params: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise UsageError(f"parameters are name=value, got {item!r}")
        if name in params:
            raise UsageError(f"parameter {name!r} given twice")
        params[name] = value
    return params


def positive_rate(text: str) -> float:
    try:
        rate = number_from_text(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(f"bit rate must be a number in b/s: {err}") from None
    if not rate > 0 or rate == float("inf"):
        raise argparse.ArgumentTypeError(f"bit rate must be a positive number in b/s, got {text}")
    return rate


def _number_or_text(value: object) -> object:
    if isinstance(value, str):
        try:
            return number_from_text(value)
        except ValueError:
            return value
    return value


def write_snaps(out: TextIO, snaps: Sequence[Snap]) -> None:
    """One line per parameter: the value sent, and what was asked for if it was snapped."""
    for snap in snaps:
        sent = snap.sent if isinstance(snap.sent, str) else fmt(snap.sent)
        unit = f" {snap.unit}" if snap.unit else ""
        note = f"   (requested {snap.requested}{unit})" if snap.changed else ""
        out.write(f"  {snap.field:<15} {sent}{unit}{note}\n")


def encoded_json(enc: Encoded) -> dict[str, Any]:
    """The encoded command as JSON: pattern, values sent, values requested, what was snapped."""
    return {
        **command_json(enc.command),
        "requested": {s.field: _number_or_text(s.requested) for s in enc.snaps},
        "snapped": [str(s) for s in enc.snaps if s.changed],
    }
