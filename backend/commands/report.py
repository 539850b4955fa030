"""The check report's vocabulary: what a check of a plan says (:class:`CheckLine`), what a
broken rule is (:class:`SendViolation`, hard or soft) and the report of every check
(:class:`CheckReport`). The checks themselves are :mod:`backend.commands.checks`; the preview,
the confirm dialog, the command service and the API's schemas read the report.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

ViolationKind = Literal["hard", "soft"]
CheckStatus = Literal["ok", "violated", "skipped"]
CheckName = Literal[
    "depth_rating",
    "depth_limit",
    "speed_limit",
    "turn_radius",
    "top_speed",
    "endurance",
    "geofence",
    "reach",
    "onboard_limit",
]


@dataclass(frozen=True, slots=True)
class SendViolation:
    """One broken rule.

    Attributes:
        check: which check found it.
        param: the command parameter at fault (``depth``, ``speed``, ``radius``...).
        kind: ``hard``: refused on every path; ``soft``: sent only with an explicit override.
        message: a sentence for the operator.
        value: the plan's figure (in ``unit``).
        limit: the limit it breaks (same unit); None for a polygon geofence (see message).
        unit: the unit of ``value`` and ``limit``.
        allowed: the allowed range as text (``0 to 100 m``).
        step: a mission script's step (0-based), when a script was checked.
    """

    check: CheckName
    param: str
    kind: ViolationKind
    message: str
    value: float
    limit: float | None
    unit: str
    allowed: str
    #: The mission script's step it belongs to (0-based), when a script was checked.
    step: int | None = None

    @property
    def overridable(self) -> bool:
        return self.kind == "soft"

    def as_json(self) -> dict[str, Any]:
        """The violation as every document and error body gives it (``LimitViolation``)."""
        return {
            "check": self.check,
            "param": self.param,
            "kind": self.kind,
            "value": self.value,
            "limit": self.limit,
            "unit": self.unit,
            "allowed": self.allowed,
            "message": self.message,
            "overridable": self.overridable,
            "step": self.step,
        }


@dataclass(frozen=True, slots=True)
class CheckLine:
    """One check that ran (``ok``, ``violated``) or could not (``skipped``), and in words
    what it found or why it could not run."""

    check: CheckName
    status: CheckStatus
    detail: str


@dataclass(frozen=True, slots=True)
class CheckReport:
    """Every check's line, and every violation found (in the lines' order)."""

    lines: tuple[CheckLine, ...]
    violations: tuple[SendViolation, ...]

    @property
    def hard(self) -> tuple[SendViolation, ...]:
        """Violations no override can pass."""
        return tuple(v for v in self.violations if v.kind == "hard")

    @property
    def soft(self) -> tuple[SendViolation, ...]:
        """Violations the operator may override explicitly."""
        return tuple(v for v in self.violations if v.kind == "soft")
