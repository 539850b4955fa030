"""Request bodies. pydantic validates every input; errors are 422 naming the field."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, StrictFloat, StrictInt, StrictStr

ParamIn = StrictFloat | StrictInt | StrictStr


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class CommandIn(Strict):
    """A pattern and its parameters by name (units as in /api/dictionary)."""

    pattern: Annotated[str, Field(min_length=1, max_length=32)]
    params: dict[Annotated[str, Field(max_length=32)], ParamIn] = Field(
        default_factory=dict, max_length=6
    )


class SendIn(CommandIn):
    #: Send although overridable limits are exceeded (never the 100 m rating).
    override: bool = False


class DecodeIn(Strict):
    frame: Annotated[str, Field(min_length=1, max_length=200, description="100 bits or 25 hex")]


class ChannelIn(Strict):
    ber: Annotated[float, Field(ge=0, le=0.5)] = 0.0
    burst_rate: Annotated[float, Field(ge=0, le=1)] = 0.0
    burst_length_bits: Annotated[int, Field(ge=1, le=100)] = 8
    loss: Annotated[float, Field(ge=0, le=1)] = 0.0
    range_m: Annotated[float, Field(ge=0, le=100_000)] = 730.0
    delay_s: Annotated[float, Field(ge=0, le=60)] = 0.0
    bitrate_bps: Annotated[float, Field(gt=0, le=1e7)] = 36000.0


class CurrentIn(Strict):
    north_mps: Annotated[float, Field(ge=-5, le=5)] = 0.0
    east_mps: Annotated[float, Field(ge=-5, le=5)] = 0.0
    speed_sigma_mps: Annotated[float, Field(ge=0, le=5)] = 0.0
    direction_sigma_deg: Annotated[float, Field(ge=0, le=180)] = 0.0


class TimeScaleIn(Strict):
    time_scale: Annotated[float, Field(ge=0, le=50)]
