"""A mission script's vehicle: with a fleet every step names it, the same one throughout (a
run drives one vehicle), checked against the console's fleet; without one, the steps name none
(or the single vehicle) and everything is as it always was."""

from __future__ import annotations

from typing import TYPE_CHECKING

from fastapi.exceptions import RequestValidationError

from backend.commands.service import VehicleRefused
from backend.scripts.model import MissionScript
from planner import Plan

if TYPE_CHECKING:
    from backend.console import Console

__all__ = ["address_of", "mirror_of", "script_vehicle"]


def script_vehicle(
    console: Console, script: MissionScript, where: tuple[str, ...] = ("body",)
) -> str | None:
    """The vehicle a script drives: the one its steps name (a fleet's, the same in every
    step); None without a fleet (its steps name none, or the single vehicle).

    Raises:
        RequestValidationError: 422 at the first step that names no vehicle of the fleet,
            or another than the first step's.
    """
    first: str | None = None
    for i, step in enumerate(script.steps):
        loc: tuple[str | int, ...] = (*where, "steps", i, "vehicle")
        try:
            name = console.checked_vehicle(step.vehicle)
        except VehicleRefused as err:
            raise _step_error(loc, err.message, step.vehicle) from None
        if i == 0:
            first = name
        elif name != first:
            raise _step_error(
                loc,
                f"a script drives one vehicle: step 1 names {first}, step {i + 1} {name}",
                step.vehicle,
            )
    return first


def _step_error(loc: tuple[str | int, ...], msg: str, value: object) -> RequestValidationError:
    return RequestValidationError([{"loc": loc, "msg": msg, "type": "vehicle", "input": value}])


def mirror_of(console: Console, vehicle: str | None) -> Plan | None:
    """The plan the script's vehicle flies, as mirrored."""
    cm = console.commands
    return None if cm is None else cm.addressee(vehicle).mirror.plan


def address_of(console: Console, vehicle: str | None) -> int | None:
    """The address the script's vehicle's frames carry (None: the single vehicle's)."""
    return None if vehicle is None else console.fleet.get(vehicle).address
