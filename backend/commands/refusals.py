"""The command service's refusals: what every path reports, with the HTTP status REST gives
it (nothing was written or transmitted), and the check of the vehicle a request names.
:mod:`backend.commands.service` raises them (and re-exports them: import them from there)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from backend.commands.checks import SendViolation
from backend.commands.vehicles import ALL_VEHICLES, SINGLE_VEHICLE

__all__ = [
    "LimitRefused",
    "NotRetryableCommand",
    "OverrideNeeded",
    "SendRefused",
    "UnknownCommand",
    "VehicleRefused",
    "check_vehicle",
    "refusal_detail",
]


class SendRefused(Exception):
    """A send the policy refused; nothing was written or transmitted. ``status``: the HTTP
    status every path reports it with."""

    status = 422

    def __init__(self, message: str, violations: Sequence[SendViolation] = ()) -> None:
        super().__init__(message)
        self.message = message
        self.violations = tuple(violations)

    def __str__(self) -> str:
        return "; ".join([self.message, *(v.message for v in self.violations)])

    def as_json(self) -> dict[str, Any]:
        return {"message": self.message, "violations": [v.as_json() for v in self.violations]}


def refusal_detail(err: SendRefused) -> dict[str, Any] | str:
    """The ``detail`` of a refusal: the violations when the checks refused, else the words."""
    return err.as_json() if err.violations else err.message


class LimitRefused(SendRefused):
    """Limits no operator can override (the depth rating): refused on every path."""

    status = 422


class OverrideNeeded(SendRefused):
    """Limits an operator may override, sent without ``override``."""

    status = 409


class UnknownCommand(SendRefused):
    """A retry of a command the log does not hold."""

    status = 404


class NotRetryableCommand(SendRefused):
    """A retry of a command that is not in a retryable state."""

    status = 409


class VehicleRefused(SendRefused):
    """A request that names no vehicle of the console's (or none, with a fleet), or ``"all"``
    for anything but Surface; the message names the vehicles. ``field``: ``vehicle``."""

    status = 422
    field = "vehicle"


def check_vehicle(name: str | None, fleet: Sequence[str], *, surface: bool = False) -> str | None:
    """The vehicle a request names, checked against the ``fleet``'s names (empty: no fleet):
    a fleet's name, or ``"all"`` for a ``surface``; None without a fleet, where only the
    single vehicle's name (or none) is taken.

    Raises:
        VehicleRefused: naming what is allowed.
    """
    if not fleet:
        if name is None or name == SINGLE_VEHICLE:
            return None
        raise VehicleRefused(
            f"vehicle {name!r:.40}: this console drives one vehicle, {SINGLE_VEHICLE!r} (no "
            "fleet is configured): leave vehicle out or name it"
        )
    known = ", ".join(fleet)
    also = f", or {ALL_VEHICLES!r}" if surface else ""
    if name is None:
        raise VehicleRefused(
            f"vehicle is required: a fleet is configured, and every command names the vehicle "
            f"it is for ({known}{also})"
        )
    if name == ALL_VEHICLES:
        if surface:
            return name
        raise VehicleRefused(f"vehicle {ALL_VEHICLES!r} is for Surface only: name one of {known}")
    if name not in fleet:
        raise VehicleRefused(f"no vehicle {name!r:.40}: the fleet's vehicles are {known}{also}")
    return name
