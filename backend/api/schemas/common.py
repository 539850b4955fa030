"""Shapes shared by several responses: parameter values, a command, a vehicle state, a
limit violation, a check's line."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field, WithJsonSchema

from backend.commands.checks import CheckName, CheckStatus, ViolationKind

#: A number as the source gave it: an integer stays an integer (``3``), a float a float.
Number = Annotated[int | float, WithJsonSchema({"type": "number"})]
#: A parameter's value: a number, or a choice's name (``"cw"``).
ParamValue = Annotated[
    int | float | str, WithJsonSchema({"anyOf": [{"type": "number"}, {"type": "string"}]})
]
#: Parameters by name (units as in ``/api/dictionary``).
Params = dict[str, ParamValue]


class CommandJson(BaseModel):
    """A command: its pattern (name and ID) and its parameters as sent (snapped)."""

    pattern: str
    pattern_id: int
    params: Params


class VehicleStateOut(BaseModel):
    """The vehicle as the planner saw it (NED m, deg, m/s, mission clock s); ``segment``:
    the active path's segment guidance tracked, when known."""

    x_m: float
    y_m: float
    z_m: float
    heading_deg: float
    speed_mps: float
    t_s: float
    segment: int | None


class LimitViolation(BaseModel):
    """One broken rule (``backend/commands/checks.py``): ``kind`` hard (the depth rating) is refused
    on every path; soft needs an explicit override. ``overridable``: the kind is soft."""

    check: CheckName = Field(description="the check that found it")
    param: str = Field(description="the command parameter at fault")
    kind: ViolationKind = Field(description="hard: never sent; soft: sent only with override")
    value: float
    limit: float | None = Field(description="null for a polygon geofence (see message)")
    unit: str
    allowed: str = Field(description='the allowed range in words ("0 to 100 m")')
    message: str
    overridable: bool
    step: int | None = Field(None, description="a mission script's step (0-based), if any")


class CheckLineDoc(BaseModel):
    """One check of a plan before a send: it passed (``ok``), found a violation
    (``violated``), or could not run (``skipped``: ``detail`` says why)."""

    check: CheckName
    status: CheckStatus
    detail: str = Field(description="what the check found, or why it could not run")
