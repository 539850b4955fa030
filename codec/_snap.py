"""The encode side of the field quantizations: snapping a requested value to a code, the
:class:`Snap` report, and the scales' texts for listings and error messages (:func:`fmt`, a
value's short text, is the console's too).

The methods of :class:`codec._scales.NumericScale` and :class:`codec._scales.ChoiceScale`
that encode or describe call into this module, loaded on first use: the vehicle only decodes
(``value_of``, ``is_valid_code``) and never loads it (``nemesys bench reconfig``).
"""

from __future__ import annotations

import math
from bisect import bisect_left

from codec._errors import EncodeError
from codec._number_text import number_from_text
from codec._record import Record, init

TYPE_CHECKING = False
if TYPE_CHECKING:
    from codec._scales import ChoiceScale, NumericScale, ParamValue


def fmt(value: float) -> str:
    """Short, exact-looking text for a value (``12.5``, ``0.025``, ``3210``)."""
    return format(value, ".10g")


class Snap(Record):
    """What happened to one requested value: ``requested 12.34 m, sent 12.5 m``."""

    __slots__ = ("field", "requested", "sent", "unit")
    field: str
    unit: str
    requested: ParamValue
    sent: ParamValue

    def __init__(self, field: str, unit: str, requested: ParamValue, sent: ParamValue) -> None:
        init(self, "field", field)
        init(self, "unit", unit)
        init(self, "requested", requested)
        init(self, "sent", sent)

    @property
    def changed(self) -> bool:
        if isinstance(self.sent, str):
            return (
                not isinstance(self.requested, str) or self.requested.strip().lower() != self.sent
            )
        try:
            return float(self.requested) != float(self.sent)
        except (TypeError, ValueError):
            return True

    def __str__(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        req = self.requested if isinstance(self.sent, str) else fmt(float(self.requested))
        sent = self.sent if isinstance(self.sent, str) else fmt(self.sent)
        return f"{self.field}: requested {req}{unit}, sent {sent}{unit}"


def max_abs_error(scale: NumericScale) -> float:
    """Largest snapping error anywhere in the range (half the largest step)."""
    return max((b - a for a, b in zip(scale.values, scale.values[1:], strict=False)), default=0) / 2


def max_rel_error(scale: NumericScale) -> float | None:
    """Largest relative snapping error for values >= :attr:`rel_error_from`, or ``None``.

    Between neighbours a < b the worst input is the midpoint, whose relative error is
    (b - a) / (a + b).
    """
    if scale.rel_error_from is None:
        return None
    lo = scale.rel_error_from
    return max(
        (b - a) / (a + b) for a, b in zip(scale.values, scale.values[1:], strict=False) if b > lo
    )


def error_text(scale: NumericScale, unit: str) -> str:
    """The worst-case snapping error, for listings: ``<= 2.44 % from 0.5 m``."""
    u = f" {unit}" if unit else ""
    if scale.integer:
        return "exact (whole numbers)"
    rel = max_rel_error(scale)
    if rel is not None:
        return (
            f"<= {rel * 100:.2f} % from {fmt(scale.rel_error_from or 0)}{u} "
            f"(<= {fmt(max_abs_error(scale))}{u} absolute)"
        )
    halves = [fmt(b / (2 * d)) for _, b, d in (seg.exact() for seg in scale.segments)]
    if len(halves) == 1:
        return f"<= {halves[0]}{u}"
    bounds = [fmt(float(seg.start)) for seg in scale.segments[1:]]
    parts = [f"<= {h}{u} below {b}{u}" for h, b in zip(halves, bounds, strict=False)]
    return ", ".join([*parts, f"<= {halves[-1]}{u} above"])


def range_text(scale: NumericScale, unit: str) -> str:
    """``0 to 107.5 m``."""
    u = f" {unit}" if unit else ""
    if scale.period is not None:
        return (
            f"{fmt(scale.minimum)} to {fmt(scale.maximum)}{u} "
            f"(inputs -{fmt(scale.period)} to {fmt(scale.period)} are wrapped)"
        )
    return f"{fmt(scale.minimum)} to {fmt(scale.maximum)}{u}"


def describe(scale: NumericScale) -> str:
    """Range and steps in one line, e.g. ``0..2.55 step 0.01``."""
    parts = []
    for seg in scale.segments:
        a, b, d = seg.exact()
        last = (a + (seg.count - 1) * b) / d
        parts.append(f"{fmt(float(seg.start))}..{fmt(last)} step {seg.step}")
    text = ", ".join(parts)
    if scale.period is not None:
        text += f" (wraps at {fmt(scale.period)})"
    return text


def snap_numeric(
    scale: NumericScale, name: str, unit: str, requested: ParamValue
) -> tuple[int, float | int]:
    """Code and value nearest to ``requested``; ties go to the larger value.

    Raises:
        EncodeError: not a finite number, out of range, or not whole for a count.
    """
    u = f" {unit}" if unit else ""
    number = _as_number(name, unit, requested, range_text(scale, unit))
    if scale.period is not None:
        if not -scale.period <= number <= scale.period:
            raise EncodeError(
                f"{name} = {fmt(number)}{u} is out of range: allowed "
                f"{fmt(-scale.period)} to {fmt(scale.period)}{u} (wrapped into "
                f"{describe(scale)})",
                field=name,
            )
        number %= scale.period
    elif not scale.minimum <= number <= scale.maximum:
        raise EncodeError(
            f"{name} = {fmt(number)}{u} is out of range: allowed "
            f"{fmt(scale.minimum)} to {fmt(scale.maximum)}{u} ({describe(scale)})",
            field=name,
        )
    if scale.integer and number != int(number):
        raise EncodeError(
            f"{name} = {fmt(number)} is not a whole number: allowed whole numbers "
            f"{fmt(scale.minimum)} to {fmt(scale.maximum)}",
            field=name,
        )
    values = scale.values
    i = bisect_left(values, number)
    if i == len(values):
        # Only reachable for a circular scale, between the last value and the period.
        period = scale.period or 0.0
        i = 0 if period - number <= number - values[-1] else len(values) - 1
    elif i > 0 and number - values[i - 1] < values[i] - number:
        i -= 1
    value = values[i]
    return scale.first_code + i, int(value) if scale.integer else value


def snap_choice(scale: ChoiceScale, name: str, requested: ParamValue) -> tuple[int, str]:
    text = requested.strip().lower() if isinstance(requested, str) else None
    if text not in scale.choices:
        raise EncodeError(
            f"{name} = {requested!r} is not allowed: choose one of {', '.join(scale.choices)}",
            field=name,
        )
    return scale.choices.index(text), text


#: Words float() reads as a number that is not finite.
_NON_FINITE = frozenset({"nan", "inf", "infinity"})


def _as_number(name: str, unit: str, requested: ParamValue, allowed: str) -> float:
    """``requested`` as a finite float, or an :class:`EncodeError` saying what is allowed."""
    unit_text = f" in {unit}" if unit else ""
    problem = f"{name} must be a number{unit_text} ({allowed})"
    if isinstance(requested, bool) or not isinstance(requested, str | int | float):
        raise EncodeError(f"{problem}, got {type(requested).__name__}", field=name)
    try:
        # text: ASCII decimal only (float() would take Arabic-Indic digits and "1_0")
        number = number_from_text(requested) if isinstance(requested, str) else float(requested)
    except ValueError as err:
        if str(requested).strip(" \t").lstrip("+-").lower() in _NON_FINITE:
            number = math.nan  # said below as what it is: not finite
        else:
            raise EncodeError(f"{problem}: {err}", field=name) from None
    except OverflowError:  # an int too large for a float is far out of every range
        raise EncodeError(f"{name} is out of range: allowed {allowed}", field=name) from None
    if not math.isfinite(number):
        raise EncodeError(
            f"{name} must be a finite number ({allowed}), got {requested!r}", field=name
        )
    return number
