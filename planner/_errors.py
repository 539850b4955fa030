"""Planner errors: a command the vehicle cannot turn into a path."""

from __future__ import annotations


class PlanError(ValueError):
    """The decoded command has no flyable path (e.g. a circle of radius 0).

    Attributes:
        field: the parameter at fault, when one is (``radius``), else ``None``.
    """

    def __init__(self, message: str, field: str | None = None) -> None:
        super().__init__(message)
        self.field = field
