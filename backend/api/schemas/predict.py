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
        description="predicted time from the command taking effect to the pattern's "
        "completion (s); null: it repeats, or does not finish within the horizon"
    )
    planned_duration_s: float | None = Field(
        description="the plan's own duration (s, the preview's planned_duration_s); null for "
        "a repeating pattern"
    )
    max_deviation_m: float = Field(
        description="largest 3D distance of the predicted track from the planned path (m)"
    )
    horizon_s: float = Field(description="simulated time covered (s)")
    completes: bool = Field(description="the pattern completes within the horizon")
    outcome: Literal["accepted", "duplicate", "rejected", "lost"] = Field(
        description="the onboard agent's answer to the frame; lost: out of the link's range"
    )
    reason: str | None = Field(description="why the vehicle would reject it; null otherwise")
    assumptions: list[str] = Field(description="what the prediction takes for granted")
