"""Shapes shared by several responses: parameter values, a command, a vehicle state, a
limit violation."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, Field, WithJsonSchema

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
    """One broken limit: ``kind`` hard (refused on every path: the depth rating) or soft
    (needs the operator's override; ``overridable`` says the same)."""

    check: str = Field("", description="which check found it (depth_rating, reach, ...)")
    param: str
    kind: Literal["hard", "soft"] = "soft"
    value: float | None
    limit: float | None = Field(description="null for a polygon geofence (see message)")
    unit: str
    message: str
    overridable: bool
    allowed: str = Field("", description="what is allowed, in words")
    step: int | None = Field(None, description="a mission script's step (0-based), if any")
