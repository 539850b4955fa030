"""A dive read back from the mission log: its telemetry series (the plots)."""

from __future__ import annotations

from pydantic import BaseModel, Field


class DiveSeries(BaseModel):
    """The current (or a chosen) dive's telemetry as the log keeps it: a sample a second of
    the vehicle's clock, on the dive's own clock (s since its start), oldest first. Columns
    of equal length; a value the vehicle did not report is null."""

    dive: int | None = Field(description="the dive; null: none has started yet (no samples)")
    started_at: str | None = Field(description="when the dive started (station clock, ISO 8601)")
    start_t_s: float | None = Field(
        description="the vehicle's clock at the dive's start, its first sample (s); "
        "null: no sample yet"
    )
    interval_s: float | None = Field(
        description="the samples' mean spacing (s): 1, more when thinned to `limit`"
    )
    t_s: list[float] = Field(description="seconds since the dive's start")
    depth_m: list[float | None] = Field(description="depth (m, down): the sensor, else the pose")
    commanded_depth_m: list[float | None] = Field(
        description="the depth of the command the vehicle reported running (m)"
    )
    battery_pct: list[float | None]
    speed_mps: list[float | None] = Field(description="speed through the water (m/s)")
