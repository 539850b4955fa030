"""Request bodies. pydantic validates every input; errors are 422 naming the field.

Every model is strict: a boolean is not a number, a numeric string is not a number, a float
is not an integer, and NaN and infinity (which Python's JSON parser reads from ``NaN`` and
``Infinity``) are refused in every float field.
"""

from __future__ import annotations

import math
from typing import Annotated

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PlainValidator,
    StrictInt,
)

from backend.api.deps import SQLITE_INT_MAX, SQLITE_INT_MIN
from backend.commands.link_ber import COPIES_FROM, CopiesFrom
from backend.settings import DeliveryTargetIn, LinkBerIn
from codec import MAX_COPIES

#: Longest text parameter value (choices such as ``ccw``, or a number written as text).
MAX_PARAM_TEXT = 32


def check_param(value: object) -> float | int | str:
    """A parameter value: a finite number (an integer within SQLite's signed 64-bit range)
    or a short text; never a boolean. One error at the parameter itself, so ``loc`` ends
    with its name."""
    if isinstance(value, bool):
        raise ValueError(f"must be a number or a text, not {str(value).lower()}")
    if isinstance(value, int):
        if not SQLITE_INT_MIN <= value <= SQLITE_INT_MAX:
            raise ValueError("integer out of range: at most 64-bit signed")
        return value
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"must be a finite number, got {value}")
        return value
    if isinstance(value, str):
        if len(value) > MAX_PARAM_TEXT:
            raise ValueError(f"text values are at most {MAX_PARAM_TEXT} characters")
        return value
    raise ValueError(f"must be a number or a text, got {type(value).__name__}")


ParamIn = Annotated[
    float | int | str,
    PlainValidator(check_param, json_schema_input_type=float | int | str),
]


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)


#: The vehicle a request is for: a fleet's (``NEMESYS_VEHICLES``), checked against it by the
#: command service (422 naming the vehicles); without a fleet absent or ``nemesys``.
VehicleIn = Annotated[
    str | None,
    Field(
        max_length=32,
        description="the vehicle it is for: required with a fleet (one of GET /api/vehicles' "
        'names; "all" for Surface only); without one, omitted or "nemesys"',
    ),
]


class CommandIn(Strict):
    """A pattern and its parameters by name (units as in /api/dictionary), and the vehicle it
    is for (a fleet's)."""

    pattern: Annotated[str, Field(min_length=1, max_length=32)]
    params: dict[Annotated[str, Field(max_length=32)], ParamIn] = Field(
        default_factory=dict, max_length=6
    )
    vehicle: VehicleIn = None


class SurfaceIn(Strict):
    """Surface: to one vehicle of a fleet, or ``"all"`` (one frame to address 0)."""

    vehicle: VehicleIn = None


def check_copies(value: object) -> object:
    """The operator's ``copies``: an integer 1..MAX_COPIES or null; anything else is refused
    with the range (REST and the websocket share this check)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_COPIES:
        raise ValueError(f"copies must be an integer from 1 to {MAX_COPIES}, got {value!r:.40}")
    return value


#: How many copies of a command the operator may ask for. The bounds are the integer's, not
#: the union's: on ``StrictInt | None`` pydantic applies them to null too (a TypeError: 500).
CopiesIn = Annotated[
    Annotated[StrictInt, Field(ge=1, le=MAX_COPIES)] | None,
    BeforeValidator(check_copies),
    Field(
        description=f"copies of the frame, 1-{MAX_COPIES}, spaced copy_interval_s apart; "
        "omitted: chosen from the link's bit-error rate to reach the delivery target "
        "(one on a two-way link)",
    ),
]


class SendIn(CommandIn):
    #: Send although overridable limits are exceeded (never the 100 m rating).
    override: bool = False
    copies: CopiesIn = None


class RetryIn(Strict):
    #: the operator accepts the overridable limits the retry breaks from where it is now
    override: bool = False
    copies: CopiesIn = None
    #: a fleet's vehicle it goes to (named, as every send; it may be another than the one
    #: the retried command was for)
    vehicle: VehicleIn = None


class DecodeIn(Strict):
    frame: Annotated[
        str,
        Field(
            min_length=1,
            max_length=200,
            description="100 bits or 25 hex digits; a fleet's addressed frame: 108 bits or 27 "
            "hex digits",
        ),
    ]


class ChannelIn(Strict):
    """Emulated channel settings; a field left out (or null) keeps its current value, except
    ``range_m``, where null means no range limit."""

    ber: Annotated[float | None, Field(ge=0, le=0.5)] = None
    burst_rate: Annotated[float | None, Field(ge=0, le=1)] = None
    burst_length_bits: Annotated[int | None, Field(ge=1, le=100)] = None
    loss: Annotated[float | None, Field(ge=0, le=1)] = None
    range_m: Annotated[float | None, Field(ge=0, le=100_000)] = 730.0
    delay_s: Annotated[float | None, Field(ge=0, le=60)] = None
    bitrate_bps: Annotated[float | None, Field(gt=0, le=1e7)] = None


class CurrentIn(Strict):
    """Water current (NED); a field left out (or null) keeps its current value."""

    north_mps: Annotated[float | None, Field(ge=-5, le=5)] = None
    east_mps: Annotated[float | None, Field(ge=-5, le=5)] = None
    speed_sigma_mps: Annotated[float | None, Field(ge=0, le=5)] = None
    direction_sigma_deg: Annotated[float | None, Field(ge=0, le=180)] = None


class TimeScaleIn(Strict):
    time_scale: Annotated[float, Field(ge=0, le=50)]


def check_copies_from(value: object) -> object:
    """One of :data:`COPIES_FROM`; the message names the field and what is allowed."""
    if not isinstance(value, str) or value not in COPIES_FROM:
        allowed = " or ".join(f'"{c}"' for c in COPIES_FROM)
        raise ValueError(f"copies_from must be {allowed}, got {value!r:.40}")
    return value


CopiesFromIn = Annotated[CopiesFrom, BeforeValidator(check_copies_from)]


class ReplayAtIn(Strict):
    """A time of a dive, for the replay's slider."""

    dive: Annotated[int, Field(ge=1, le=SQLITE_INT_MAX)]
    #: Seconds on the dive's clock (from its start; within its timeline's range).
    t_s: Annotated[float, Field(ge=-86_400.0, le=864_000.0)]
    #: The fleet's vehicle replayed (required with a fleet: its own timeline's clock).
    vehicle: VehicleIn = None


class LinkIn(Strict):
    """What the station assumes of its link; a field left out keeps its value."""

    #: Bit-error rate of a real link, [0, 0.5) (training uses the emulated channel's).
    link_ber: LinkBerIn | None = None
    #: Delivery probability the number of copies is chosen to reach, (0, 1).
    delivery_target: DeliveryTargetIn | None = None
    #: What the copies follow on a real link: the assumed BER, or the upper end of the 95 %
    #: interval of the BER estimated from the acknowledgements (the assumed BER until there
    #: is one). Logged, naming the operator.
    copies_from: CopiesFromIn | None = None
