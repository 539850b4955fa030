"""Field quantizations: how one physical parameter maps to an 8-bit code and back.

Every quantization is a table of representable values. Numeric tables are built from linear
segments written as decimal strings, so that 0.5 m or 0.01 m/s are the exact nearest floats
and snapping is idempotent (a representable value snaps to itself). Encoding is strict: a
value outside the table's range is an :class:`EncodeError` naming the field, its unit and the
allowed range; the only change the codec makes to an in-range value is the snap to the
nearest representable value, which it reports as a :class:`Snap`.

Snapping and the scales' texts live in :mod:`codec._snap`, loaded on first use: the vehicle
decodes codes to values and never encodes. The parameters that use these scales, and the
scales the dictionary shares, are :mod:`codec._fields`.
"""

from __future__ import annotations

from codec._record import Record, init

#: Width of every parameter field on the wire (bits).
FIELD_BITS = 8
#: Number of codes a field can hold.
FIELD_CODES = 1 << FIELD_BITS

ParamValue = float | int | str


def exact_decimal(text: str) -> tuple[int, int]:
    """A decimal string as ``(numerator, denominator)``, the denominator a power of ten.

    ``"0.025"`` is ``(25, 1000)``. A sign and an exponent (``"-1.5e-3"``) are accepted;
    ``"-0"`` is plain zero. ``numerator / denominator`` is then the correctly rounded float:
    int true division is correctly rounded, like ``float(Decimal(text))``.

    Raises:
        ValueError: not a decimal number.
    """
    mantissa, has_exp, exp = text.strip().lower().partition("e")
    sign = mantissa[:1] if mantissa[:1] in ("+", "-") else ""
    whole, _, frac = mantissa[len(sign) :].partition(".")
    exp_digits = exp[1:] if exp[:1] in ("+", "-") else exp
    if not _is_digits(whole + frac) or (has_exp and not _is_digits(exp_digits)):
        raise ValueError(f"{text!r} is not a decimal number")
    shift = len(frac) - (int(exp) if has_exp else 0)
    numerator = int(sign + whole + frac)
    if shift < 0:
        return numerator * 10**-shift, 1
    return numerator, 10**shift


def _is_digits(text: str) -> bool:
    return text.isascii() and text.isdigit()


class Segment(Record):
    """``count`` values ``start, start + step, ...`` (decimal strings, exact)."""

    __slots__ = ("count", "start", "step")
    start: str
    step: str
    count: int

    def __init__(self, start: str, step: str, count: int) -> None:
        init(self, "start", start)
        init(self, "step", step)
        init(self, "count", count)

    def exact(self) -> tuple[int, int, int]:
        """``(a, b, d)`` with value ``i`` equal to ``(a + i * b) / d`` exactly."""
        a, da = exact_decimal(self.start)
        b, db = exact_decimal(self.step)
        d = max(da, db)  # both powers of ten
        return a * (d // da), b * (d // db), d


class NumericScale(Record):
    """A numeric quantization: code ``first_code + i`` stands for ``values[i]``.

    Attributes:
        segments: the linear pieces, in increasing order and contiguous in code.
        first_code: code of the first value (counts start at code 1, so code = count).
        integer: only whole numbers are accepted (counts); nothing is rounded.
        period: for angles, the period (360 deg): inputs in ``[-period, period]`` are
            wrapped into ``[0, period)`` and the wrap is reported like a snap.
        rel_error_from: lower end of the range over which :attr:`max_rel_error` is stated.
    """

    __slots__ = (
        "_count",
        "_max",
        "_min",
        "_pieces",
        "_table",
        "first_code",
        "integer",
        "name",
        "period",
        "rel_error_from",
        "segments",
    )
    segments: tuple[Segment, ...]
    name: str
    first_code: int
    integer: bool
    period: float | None
    rel_error_from: float | None
    # Private: the segments as exact integers (count, a, b, d), value i = (a + i * b) / d; the
    # number of values, the first and last; the table of values, built on first use (the
    # vehicle decodes without it).
    _pieces: tuple[tuple[int, int, int, int], ...]
    _count: int
    _min: float
    _max: float
    _table: tuple[float, ...] | None

    def __init__(
        self,
        segments: tuple[Segment, ...],
        name: str = "",
        first_code: int = 0,
        integer: bool = False,
        period: float | None = None,
        rel_error_from: float | None = None,
    ) -> None:
        init(self, "segments", segments)
        init(self, "name", name)
        init(self, "first_code", first_code)
        init(self, "integer", integer)
        init(self, "period", period)
        init(self, "rel_error_from", rel_error_from)
        pieces: list[tuple[int, int, int, int]] = []
        count = 0
        first: float | None = None
        last: float | None = None
        for seg in segments:
            a, b, d = seg.exact()
            if last is not None and a / d <= last:
                raise ValueError(f"segment starting at {seg.start} overlaps the previous one")
            if seg.count > 0:
                pieces.append((seg.count, a, b, d))
                count += seg.count
                last = (a + (seg.count - 1) * b) / d
                if first is None:
                    first = a / d
        if first is None or last is None:
            raise ValueError("a numeric scale needs at least one value")
        if first_code + count > FIELD_CODES:
            raise ValueError(f"{count} values do not fit in {FIELD_BITS} bits")
        init(self, "_pieces", tuple(pieces))
        init(self, "_count", count)
        init(self, "_min", first)
        init(self, "_max", last)
        init(self, "_table", None)

    @property
    def values(self) -> tuple[float, ...]:
        """The representable values, in code order (not a field: not compared, not shown).

        Each is the float nearest to its exact decimal value. Built on first use.
        """
        table = self._table
        if table is None:
            table = tuple((a + i * b) / d for count, a, b, d in self._pieces for i in range(count))
            init(self, "_table", table)
        return table

    @property
    def minimum(self) -> float:
        return self._min

    @property
    def maximum(self) -> float:
        return self._max

    @property
    def is_linear(self) -> bool:
        return len(self.segments) == 1

    @property
    def max_abs_error(self) -> float:
        """Largest snapping error anywhere in the range (half the largest step)."""
        from codec._snap import max_abs_error  # listings only: not loaded onboard

        return max_abs_error(self)

    @property
    def max_rel_error(self) -> float | None:
        """Largest relative snapping error for values >= :attr:`rel_error_from`, or ``None``.

        Between neighbours a < b the worst input is the midpoint, whose relative error is
        (b - a) / (a + b).
        """
        from codec._snap import max_rel_error  # listings only: not loaded onboard

        return max_rel_error(self)

    def error_text(self, unit: str) -> str:
        """The worst-case snapping error, for listings: ``<= 2.44 % from 0.5 m``."""
        from codec._snap import error_text  # listings only: not loaded onboard

        return error_text(self, unit)

    def is_valid_code(self, code: int) -> bool:
        return self.first_code <= code < self.first_code + self._count

    def value_of(self, code: int) -> float | int:
        """The value a valid code stands for (the same float as in :attr:`values`).

        Raises:
            IndexError: the code is not valid.
        """
        i = code - self.first_code
        if i >= 0:
            for count, a, b, d in self._pieces:
                if i < count:
                    value = (a + i * b) / d
                    return int(value) if self.integer else value
                i -= count
        raise IndexError(f"code {code} is not valid for {self.name or 'this scale'}")

    def represents(self, value: ParamValue) -> bool:
        """Whether :meth:`snap` sends ``value`` unchanged (it is one of the values).

        Decided from the segments, without building the table of values.
        """
        if isinstance(value, bool) or not isinstance(value, int | float):
            return False
        try:
            x = float(value)
        except OverflowError:
            return False
        if not self._min <= x <= self._max:  # also refuses inf and nan
            return False
        if (self.integer and not x.is_integer()) or (
            self.period is not None and not 0 <= x < self.period
        ):
            return False
        for count, a, b, d in self._pieces:
            near = round((x * d - a) / b) if b else 0
            for i in (near - 1, near, near + 1):
                if 0 <= i < count and (a + i * b) / d == x:
                    return True
        return False

    def range_text(self, unit: str) -> str:
        """``0 to 107.5 m``."""
        from codec._snap import range_text  # encoding and listings only: not loaded onboard

        return range_text(self, unit)

    def describe(self) -> str:
        """Range and steps in one line, e.g. ``0..2.55 step 0.01``."""
        from codec._snap import describe  # encoding and listings only: not loaded onboard

        return describe(self)

    def snap(self, name: str, unit: str, requested: ParamValue) -> tuple[int, float | int]:
        """Code and value nearest to ``requested``; ties go to the larger value.

        Raises:
            EncodeError: not a finite number, out of range, or not whole for a count.
        """
        from codec._snap import snap_numeric  # encoding only: not loaded onboard

        return snap_numeric(self, name, unit, requested)


class ChoiceScale(Record):
    """An enumerated field: code ``i`` stands for ``choices[i]`` (case-insensitive input)."""

    __slots__ = ("choices", "name")
    choices: tuple[str, ...]
    name: str

    def __init__(self, choices: tuple[str, ...], name: str = "") -> None:
        if not 0 < len(choices) <= FIELD_CODES:
            raise ValueError("a choice field needs 1 to 256 choices")
        init(self, "choices", choices)
        init(self, "name", name)

    @property
    def integer(self) -> bool:
        return False

    def is_valid_code(self, code: int) -> bool:
        return 0 <= code < len(self.choices)

    def value_of(self, code: int) -> str:
        return self.choices[code]

    def represents(self, value: ParamValue) -> bool:
        """Whether :meth:`snap` sends ``value`` unchanged (it is one of the choices)."""
        return isinstance(value, str) and value in self.choices and value.strip().lower() == value

    def range_text(self, unit: str) -> str:
        return " or ".join(self.choices)

    def error_text(self, unit: str) -> str:
        return "exact"

    def describe(self) -> str:
        return ", ".join(f"{c} = {i}" for i, c in enumerate(self.choices))

    def snap(self, name: str, unit: str, requested: ParamValue) -> tuple[int, str]:
        """Code and choice of ``requested`` (any case, surrounding spaces ignored).

        Raises:
            EncodeError: not one of the choices.
        """
        from codec._snap import snap_choice  # encoding only: not loaded onboard

        return snap_choice(self, name, requested)


Scale = NumericScale | ChoiceScale
