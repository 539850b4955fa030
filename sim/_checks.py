"""Validation helpers shared by the simulator's config records and steps: errors name the
field and the allowed range."""

from __future__ import annotations

import math


def check_dt(dt_s: float) -> None:
    """A simulation step ``dt_s`` in [0, inf) (s). No type check: it runs at every step."""
    if not 0.0 <= dt_s < math.inf:
        raise ValueError(f"dt_s must be in [0, inf), got {dt_s!r}")


def number(name: str, value: object) -> float:
    """``value`` as a float; bools and non-numbers are refused."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{name} must be a number, got {value!r}")
    return float(value)


def in_range(name: str, value: object, lo: float, hi: float, allowed: str) -> None:
    """``lo <= value <= hi`` (NaN refused); ``allowed`` is the range as the message shows it."""
    x = number(name, value)
    if not lo <= x <= hi:
        raise ValueError(f"{name} must be in {allowed}, got {value!r}")


def positive(name: str, value: object) -> None:
    """``value`` in (0, inf): finite and above zero."""
    if not 0.0 < number(name, value) < math.inf:
        raise ValueError(f"{name} must be in (0, inf), got {value!r}")


def non_negative(name: str, value: object) -> None:
    """``value`` in [0, inf): finite and not below zero."""
    if not 0.0 <= number(name, value) < math.inf:
        raise ValueError(f"{name} must be in [0, inf), got {value!r}")
