"""Validation helpers shared by the simulator's config records: errors name the field and
the allowed range."""

from __future__ import annotations


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
