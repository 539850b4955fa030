"""The patterns' parameters: :class:`Field` (a name, a unit and an 8-bit quantization) and
the quantizations the dictionary's fields share (speed, depth, length, heading, duration,
count, direction).

The quantizations themselves are :mod:`codec._scales`; their names are importable from here
too, and :func:`fmt` (the console's, in :mod:`codec._snap`) on first use.
"""

from __future__ import annotations

from codec._record import Record, init
from codec._scales import (
    FIELD_BITS,
    FIELD_CODES,
    ChoiceScale,
    NumericScale,
    ParamValue,
    Scale,
    Segment,
    exact_decimal,
)

TYPE_CHECKING = False
if TYPE_CHECKING:
    from codec._snap import fmt

__all__ = [
    "COUNT",
    "DEPTH",
    "DIRECTION",
    "DURATION",
    "FIELD_BITS",
    "FIELD_CODES",
    "HEADING",
    "LENGTH",
    "SPEED",
    "ChoiceScale",
    "Field",
    "NumericScale",
    "ParamValue",
    "Scale",
    "Segment",
    "exact_decimal",
    "fmt",
]


class Field(Record):
    """One parameter of a pattern.

    Attributes:
        name: identifier used by the API and the CLI (``lane_spacing``).
        label: the paper's wording (``lane spacing``).
        unit: SI unit symbol (``m``, ``m/s``, ``s``, ``deg``) or ``""`` for counts and choices.
        scale: the 8-bit quantization.
        default: a sensible value for forms and benchmarks (representable).
        doc: the parameter's meaning for the operator.
    """

    __slots__ = ("default", "doc", "label", "name", "scale", "unit")
    name: str
    label: str
    unit: str
    scale: Scale
    default: ParamValue
    doc: str

    def __init__(
        self, name: str, label: str, unit: str, scale: Scale, default: ParamValue, doc: str
    ) -> None:
        if not scale.represents(default):
            raise ValueError(f"default of {name} ({default!r}) is not representable")
        init(self, "name", name)
        init(self, "label", label)
        init(self, "unit", unit)
        init(self, "scale", scale)
        init(self, "default", default)
        init(self, "doc", doc)

    def snap(self, requested: ParamValue) -> tuple[int, ParamValue]:
        """``(code, sent value)`` for a requested value; see the scale's ``snap``."""
        return self.scale.snap(self.name, self.unit, requested)

    def value_of(self, code: int) -> ParamValue:
        return self.scale.value_of(code)


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


# ``fmt`` (the values' short text, :mod:`codec._snap`) is still importable from here, loaded on
# first use: the vehicle never formats a value.
if not TYPE_CHECKING:

    def __getattr__(name: str) -> object:
        if name != "fmt":
            raise AttributeError(f"module 'codec._fields' has no attribute {name!r}")
        from codec._snap import fmt

        return fmt
