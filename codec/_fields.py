"""Field quantizations: how one physical parameter maps to an 8-bit code and back.

Every quantization is a table of representable values. Numeric tables are built from linear
segments written as decimal strings, so that 0.5 m or 0.01 m/s are the exact nearest floats
and snapping is idempotent (a representable value snaps to itself). Encoding is strict: a
value outside the table's range is an :class:`EncodeError` naming the field, its unit and the
allowed range; the only change the codec makes to an in-range value is the snap to the
nearest representable value, which it reports as a :class:`Snap`.
"""

from __future__ import annotations

import math
from bisect import bisect_left
from dataclasses import dataclass, field
from decimal import Decimal

from codec._errors import EncodeError

#: Width of every parameter field on the wire (bits).
FIELD_BITS = 8
#: Number of codes a field can hold.
FIELD_CODES = 1 << FIELD_BITS

ParamValue = float | int | str


def fmt(value: float) -> str:
    """Short, exact-looking text for a value (``12.5``, ``0.025``, ``3210``)."""
    return format(value, ".10g")


@dataclass(frozen=True, slots=True)
class Segment:
    """``count`` values ``start, start + step, ...`` (decimal strings, exact)."""

    start: str
    step: str
    count: int


@dataclass(frozen=True)
class NumericScale:
    """A numeric quantization: code ``first_code + i`` stands for ``values[i]``.

    Attributes:
        segments: the linear pieces, in increasing order and contiguous in code.
        first_code: code of the first value (counts start at code 1, so code = count).
        integer: only whole numbers are accepted (counts); nothing is rounded.
        period: for angles, the period (360 deg): inputs in ``[-period, period]`` are
            wrapped into ``[0, period)`` and the wrap is reported like a snap.
        rel_error_from: lower end of the range over which :attr:`max_rel_error` is stated.
    """

    segments: tuple[Segment, ...]
    name: str = ""
    first_code: int = 0
    integer: bool = False
    period: float | None = None
    rel_error_from: float | None = None
    values: tuple[float, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        values: list[float] = []
        for seg in self.segments:
            start, step = Decimal(seg.start), Decimal(seg.step)
            if values and float(start) <= values[-1]:
                raise ValueError(f"segment starting at {seg.start} overlaps the previous one")
            values.extend(float(start + i * step) for i in range(seg.count))
        if self.first_code + len(values) > FIELD_CODES:
            raise ValueError(f"{len(values)} values do not fit in {FIELD_BITS} bits")
        object.__setattr__(self, "values", tuple(values))

    @property
    def minimum(self) -> float:
        return self.values[0]

    @property
    def maximum(self) -> float:
        return self.values[-1]

    @property
    def is_linear(self) -> bool:
        return len(self.segments) == 1

    @property
    def max_abs_error(self) -> float:
        """Largest snapping error anywhere in the range (half the largest step)."""
        return (
            max((b - a for a, b in zip(self.values, self.values[1:], strict=False)), default=0) / 2
        )

    @property
    def max_rel_error(self) -> float | None:
        """Largest relative snapping error for values >= :attr:`rel_error_from`, or ``None``.

        Between neighbours a < b the worst input is the midpoint, whose relative error is
        (b - a) / (a + b).
        """
        if self.rel_error_from is None:
            return None
        lo = self.rel_error_from
        return max(
            (b - a) / (a + b) for a, b in zip(self.values, self.values[1:], strict=False) if b > lo
        )

    def error_text(self, unit: str) -> str:
        """The worst-case snapping error, for listings: ``<= 2.44 % from 0.5 m``."""
        u = f" {unit}" if unit else ""
        if self.integer:
            return "exact (whole numbers)"
        rel = self.max_rel_error
        if rel is not None:
            return (
                f"<= {rel * 100:.2f} % from {fmt(self.rel_error_from or 0)}{u} "
                f"(<= {fmt(self.max_abs_error)}{u} absolute)"
            )
        halves = [fmt(float(Decimal(seg.step) / 2)) for seg in self.segments]
        if len(halves) == 1:
            return f"<= {halves[0]}{u}"
        bounds = [fmt(float(seg.start)) for seg in self.segments[1:]]
        parts = [f"<= {h}{u} below {b}{u}" for h, b in zip(halves, bounds, strict=False)]
        return ", ".join([*parts, f"<= {halves[-1]}{u} above"])

    def is_valid_code(self, code: int) -> bool:
        return self.first_code <= code < self.first_code + len(self.values)

    def value_of(self, code: int) -> float | int:
        """The value a (valid) code stands for."""
        value = self.values[code - self.first_code]
        return int(value) if self.integer else value

    def range_text(self, unit: str) -> str:
        """``0 to 107.5 m``."""
        u = f" {unit}" if unit else ""
        if self.period is not None:
            return (
                f"{fmt(self.minimum)} to {fmt(self.maximum)}{u} "
                f"(inputs -{fmt(self.period)} to {fmt(self.period)} are wrapped)"
            )
        return f"{fmt(self.minimum)} to {fmt(self.maximum)}{u}"

    def describe(self) -> str:
        """Range and steps in one line, e.g. ``0..2.55 step 0.01``."""
        parts = []
        for seg in self.segments:
            last = float(Decimal(seg.start) + (seg.count - 1) * Decimal(seg.step))
            parts.append(f"{fmt(float(seg.start))}..{fmt(last)} step {seg.step}")
        text = ", ".join(parts)
        if self.period is not None:
            text += f" (wraps at {fmt(self.period)})"
        return text

    def snap(self, name: str, unit: str, requested: ParamValue) -> tuple[int, float | int]:
        """Code and value nearest to ``requested``; ties go to the larger value.

        Raises:
            EncodeError: not a finite number, out of range, or not whole for a count.
        """
        u = f" {unit}" if unit else ""
        number = _as_number(name, unit, requested, self.range_text(unit))
        if self.period is not None:
            if not -self.period <= number <= self.period:
                raise EncodeError(
                    f"{name} = {fmt(number)}{u} is out of range: allowed "
                    f"{fmt(-self.period)} to {fmt(self.period)}{u} (wrapped into "
                    f"{self.describe()})",
                    field=name,
                )
            number %= self.period
        elif not self.minimum <= number <= self.maximum:
            raise EncodeError(
                f"{name} = {fmt(number)}{u} is out of range: allowed "
                f"{fmt(self.minimum)} to {fmt(self.maximum)}{u} ({self.describe()})",
                field=name,
            )
        if self.integer and number != int(number):
            raise EncodeError(
                f"{name} = {fmt(number)} is not a whole number: allowed whole numbers "
                f"{fmt(self.minimum)} to {fmt(self.maximum)}",
                field=name,
            )
        values = self.values
        i = bisect_left(values, number)
        if i == len(values):
            # Only reachable for a circular scale, between the last value and the period.
            period = self.period or 0.0
            i = 0 if period - number <= number - values[-1] else len(values) - 1
        elif i > 0 and number - values[i - 1] < values[i] - number:
            i -= 1
        return self.first_code + i, self.value_of(self.first_code + i)


def _as_number(name: str, unit: str, requested: ParamValue, allowed: str) -> float:
    """``requested`` as a finite float, or an :class:`EncodeError` saying what is allowed."""
    unit_text = f" in {unit}" if unit else ""
    problem = f"{name} must be a number{unit_text} ({allowed})"
    if isinstance(requested, bool) or not isinstance(requested, str | int | float):
        raise EncodeError(f"{problem}, got {type(requested).__name__}", field=name)
    try:
        number = float(requested.strip() if isinstance(requested, str) else requested)
    except ValueError:
        raise EncodeError(f"{problem}, got {requested!r}", field=name) from None
    except OverflowError:  # an int too large for a float is far out of every range
        raise EncodeError(f"{name} is out of range: allowed {allowed}", field=name) from None
    if not math.isfinite(number):
        raise EncodeError(
            f"{name} must be a finite number ({allowed}), got {requested!r}", field=name
        )
    return number


@dataclass(frozen=True)
class ChoiceScale:
    """An enumerated field: code ``i`` stands for ``choices[i]`` (case-insensitive input)."""

    choices: tuple[str, ...]
    name: str = ""

    def __post_init__(self) -> None:
        if not 0 < len(self.choices) <= FIELD_CODES:
            raise ValueError("a choice field needs 1 to 256 choices")

    @property
    def integer(self) -> bool:
        return False

    def is_valid_code(self, code: int) -> bool:
        return 0 <= code < len(self.choices)

    def value_of(self, code: int) -> str:
        return self.choices[code]

    def range_text(self, unit: str) -> str:
        return " or ".join(self.choices)

    def error_text(self, unit: str) -> str:
        return "exact"

    def describe(self) -> str:
        return ", ".join(f"{c} = {i}" for i, c in enumerate(self.choices))

    def snap(self, name: str, unit: str, requested: ParamValue) -> tuple[int, str]:
        text = requested.strip().lower() if isinstance(requested, str) else None
        if text not in self.choices:
            raise EncodeError(
                f"{name} = {requested!r} is not allowed: choose one of {', '.join(self.choices)}",
                field=name,
            )
        return self.choices.index(text), text


Scale = NumericScale | ChoiceScale


@dataclass(frozen=True)
class Field:
    """One parameter of a pattern.

    Attributes:
        name: identifier used by the API and the CLI (``lane_spacing``).
        label: the paper's wording (``lane spacing``).
        unit: SI unit symbol (``m``, ``m/s``, ``s``, ``deg``) or ``""`` for counts and choices.
        scale: the 8-bit quantization.
        default: a sensible value for forms and benchmarks (representable).
        doc: the parameter's meaning for the operator.
    """

    name: str
    label: str
    unit: str
    scale: Scale
    default: ParamValue
    doc: str

    def __post_init__(self) -> None:
        _, snapped = self.scale.snap(self.name, self.unit, self.default)
        if snapped != self.default:
            raise ValueError(f"default of {self.name} ({self.default!r}) is not representable")

    def snap(self, requested: ParamValue) -> tuple[int, ParamValue]:
        """``(code, sent value)`` for a requested value; see the scale's ``snap``."""
        return self.scale.snap(self.name, self.unit, requested)

    def value_of(self, code: int) -> ParamValue:
        return self.scale.value_of(code)


@dataclass(frozen=True, slots=True)
class Snap:
    """What happened to one requested value: ``requested 12.34 m, sent 12.5 m``."""

    field: str
    unit: str
    requested: ParamValue
    sent: ParamValue

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


# --- The shared quantizations ---------------------------------------------------------------

#: Cruise speed: 0 to 2.55 m/s in 0.01 m/s steps.
SPEED = NumericScale((Segment("0", "0.01", 256),), name="speed")

#: Depth: 0.1 m steps to 4.9 m (tank, springs), then 0.5 m steps to 107.5 m (the vehicle's
#: 100 m rating plus margin; the planner enforces the rating). 0.5 m and 1.0 m are exact.
DEPTH = NumericScale((Segment("0", "0.1", 50), Segment("5", "0.5", 206)), name="depth")

#: Lengths, radii and spacings: 1-2.5-5 steps, each segment starting where its half-step is
#: 2.5 % of the value, so the relative error stays below 2.5 % from 0.5 m to 750 m and every
#: whole metre to 50 m and every multiple of 5 m to 200 m is exact.
LENGTH = NumericScale(
    (
        Segment("0", "0.025", 40),
        Segment("1", "0.05", 20),
        Segment("2", "0.1", 30),
        Segment("5", "0.25", 20),
        Segment("10", "0.5", 20),
        Segment("20", "1", 30),
        Segment("50", "2.5", 20),
        Segment("100", "5", 20),
        Segment("200", "10", 56),
    ),
    name="length",
    rel_error_from=0.5,
)

#: Heading: the full circle in 1.5 deg steps (every multiple of 7.5 deg is exact); codes
#: 240-255 are invalid and rejected on decode.
HEADING = NumericScale((Segment("0", "1.5", 240),), name="heading", period=360.0)

#: Duration: 1 s steps to 59 s, 5 s steps to 595 s, 30 s steps to 3210 s (53.5 min).
DURATION = NumericScale(
    (Segment("0", "1", 60), Segment("60", "5", 108), Segment("600", "30", 88)),
    name="duration",
)

#: Counts (laps, loops, turns): the code is the count, 1-255; code 0 is invalid.
COUNT = NumericScale((Segment("1", "1", 255),), name="count", first_code=1, integer=True)

#: Turning direction seen from above (NED, looking down +z): cw = north -> east -> south.
DIRECTION = ChoiceScale(("cw", "ccw"), name="direction")
