"""A dive read back from the mission log: its telemetry series (the plots) and its timeline
(the replay's time slider)."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field


class DiveSeries(BaseModel):
    """The current (or a chosen) dive's telemetry as the log keeps it: a sample a second of
    the vehicle's clock, on the dive's own clock (s since its start), oldest first. Columns
    of equal length; a value the vehicle did not report is null. With a fleet, one
    vehicle's (``vehicle``)."""

    dive: int | None = Field(description="the dive; null: none has started yet (no samples)")
    vehicle: str | None = Field(
        None,
        description="the fleet's vehicle whose series it is (absent without a fleet: the one "
        "vehicle's)",
    )
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
        description="the depth of the command the vehicle reported running (m): its depth, or "
        "a helix's end depth"
    )
    battery_pct: list[float | None]
    speed_mps: list[float | None] = Field(description="speed through the water (m/s)")
    heading_deg: list[float | None] = Field(description="degrees clockwise from north")
    mode: list[str | None] = Field(description="what guidance was doing, as the vehicle said")
    nav_valid: list[bool | None] = Field(
        description="the vehicle's navigation was valid; false: no position then (nav fault); "
        "null: not said (a 1.x vehicle, taken as true)"
    )
    nav_age_s: list[float | None] = Field(
        description="age of the vehicle's latest navigation solution (s)"
    )


class TimelineSample(BaseModel):
    """The vehicle at one second of the dive (a track point)."""

    t_s: float = Field(description="seconds since the dive's start")
    x_m: float
    y_m: float
    z_m: float = Field(description="depth (m, down)")
    heading_deg: float
    lat_deg: float | None = Field(description="from the current datum; null without one")
    lon_deg: float | None
    mode: str | None = Field(description="what guidance was doing, as the vehicle said")
    pattern: str | None = Field(description="the pattern it reported running (null: none)")
    command_id: int | None = Field(
        description="the logged command that is (null: none, or not sent by this console)"
    )


class TimelineCommand(BaseModel):
    """One of the dive's commands."""

    id: int
    pattern: str
    kind: str | None
    params: dict[str, Any]
    state: str
    text: str = Field(description="the command in words: id, pattern, parameters")
    sent_t_s: float | None = Field(description="its first copy left (s on the dive's clock)")


class TimelineEvent(BaseModel):
    """A link event: a copy sent, an acknowledgement, a rejection, a timeout, a logged event."""

    t_s: float = Field(description="seconds since the dive's start (negative: before it)")
    kind: str = Field(description="sent, acknowledged, rejected, timed_out, ..., echo_mismatch")
    text: str
    command_id: int | None


class DiveTimeline(BaseModel):
    """A dive on its own clock: every sample of the vehicle, the commands, the link events
    (time order). The replay's slider runs from ``from_t_s`` to ``duration_s``."""

    dive: int
    vehicle: str | None = Field(
        None,
        description="the fleet's vehicle whose timeline it is (absent without a fleet: the "
        "one vehicle's)",
    )
    started_at: str
    start_t_s: float | None = Field(
        description="the vehicle's clock at the dive's start (null: no track; the dive's clock "
        "is then the station's, from started_at)"
    )
    from_t_s: float = Field(description="the earliest time on the dive's clock (<= 0)")
    duration_s: float = Field(description="the latest time on the dive's clock")
    samples: list[TimelineSample]
    commands: list[TimelineCommand]
    events: list[TimelineEvent]
    unplaced_events: int = Field(description="link events the log holds no time for")


class ReplayAt(BaseModel):
    """The replayed vehicle at ``t_s`` (drawn as a marker in the caller's 3D view)."""

    dive: int
    vehicle: str | None = Field(
        None, description="the fleet's vehicle replayed (absent without a fleet)"
    )
    t_s: float
    position: TimelineSample | None = Field(
        description="where it was, between the samples around t_s; null: the dive has no track"
    )
    drawn: bool = Field(description="a marker was drawn in the caller's 3D view")
