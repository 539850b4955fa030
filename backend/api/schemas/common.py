"""Shapes shared by several responses: parameter values, a command, a vehicle state, a
limit violation, a check's line."""

from __future__ import annotations

from pydantic import BaseModel, Field

from backend.commands.checks import CheckName, CheckStatus, ViolationKind

# the shapes of the mission log's records, named here too
from backend.mission_log.records import (
    CommandJson,
    Number,
    Params,
    ParamValue,
    VehicleStateOut,
)


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


__all__ = [
    "CheckLineDoc",
    "CommandJson",
    "LimitViolation",
    "Number",
    "ParamValue",
    "Params",
    "VehicleStateOut",
]
