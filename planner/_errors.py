"""What the planner reports as wrong: a command the vehicle cannot turn into a path
(:class:`PlanError`), a limit a plan breaks (:class:`Violation`), a limit that is not a number
above 0 (:func:`finite_positive`).

The limits (:mod:`planner._limits`), the geofences (:mod:`planner._fence`) and the console's
checks (:mod:`planner._checks`) all report :class:`Violation`; it lives here, below all three,
so that none of them imports another to name one.
"""

from __future__ import annotations

import math

from codec._record import Record, init


class PlanError(ValueError):
    """The decoded command has no flyable path (e.g. a circle of radius 0).

    Attributes:
        field: the parameter at fault, when one is (``radius``), else ``None``.
    """

    def __init__(self, message: str, field: str | None = None) -> None:
        super().__init__(message)
        self.field = field


def finite_positive(name: str, value: float) -> float:
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a finite number above 0, got {value!r}")
    return float(value)


class Violation(Record):
    """One broken limit.

    Attributes:
        param: the command parameter at fault (``depth``, ``radius``...).
        value: its value in the command.
        limit: the limit it breaks, in the same unit (``None`` for a polygon geofence, which
            the message describes).
        unit: the unit of ``value`` and ``limit``.
        message: a sentence for the operator.
        overridable: ``False`` for the depth rating, which no operator can override.
    """

    __slots__ = ("limit", "message", "overridable", "param", "unit", "value")
    param: str
    value: float
    limit: float | None
    unit: str
    message: str
    overridable: bool

    def __init__(
        self,
        param: str,
        value: float,
        limit: float | None,
        unit: str,
        message: str,
        overridable: bool = True,
    ) -> None:
        init(self, "param", param)
        init(self, "value", value)
        init(self, "limit", limit)
        init(self, "unit", unit)
        init(self, "message", message)
        init(self, "overridable", overridable)
