"""The predicted track (``POST /api/predict``)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field


class Prediction(BaseModel):
    """What the twin does with the command from the vehicle's state now: its track (NED m,
    s from now; lat/lon deg), decimated to at most 600 points, against the planned path."""

    x_m: list[float]
    y_m: list[float]
    z_m: list[float]
    t_s: list[float] = Field(description="simulated seconds from the submission")
    lat_deg: list[float] | None = Field(description="from the datum; null without one")
    lon_deg: list[float] | None
    duration_s: float | None = Field(
        description="predicted duration (s) from the command taking effect until the pattern "
        "is done: a finite one at its end and depth, a repeating one (repeats) after the join "
        "and one lap, as the estimate's; null: not within the horizon"
    )
    planned_duration_s: float = Field(
        description="duration by the plan's own clock (s, the preview's planned_duration_s; "
        "a repeating pattern: the join and one lap)"
    )
    estimate_duration_s: float = Field(
        description="the estimated duration (s, the preview's estimate.duration_s): the same "
        "command as the vehicle's profile flies it"
    )
    repeats: bool = Field(description="the pattern repeats until retasked")
    duration_notes: list[str] = Field(
        description="why the predicted duration differs from the estimate, in words, where it "
        "differs by more than 20 % (empty otherwise)"
    )
    max_deviation_m: float = Field(
        description="largest 3D distance of the predicted track from the planned path (m)"
    )
    horizon_s: float = Field(description="simulated time covered (s)")
    completes: bool = Field(
        description="the pattern is done within the horizon (a repeating one: its join and "
        "first lap): duration_s is not null"
    )
    outcome: Literal["accepted", "duplicate", "rejected", "lost"] = Field(
        description="the onboard agent's answer to the frame; lost: out of the link's range"
    )
    reason: str | None = Field(description="why the vehicle would reject it; null otherwise")
    assumptions: list[str] = Field(description="what the prediction takes for granted")
