"""A fleet survey's preview (``POST /api/survey/preview``): its request and its document.

The request's bounds only keep numbers finite and of a sane size; what a survey allows (the
lawnmower's scales, 1 to 15 vehicles with two lanes each, the ME link's range) is the
survey's own check (:mod:`backend.authoring.survey`), a 422 naming the field and what is
allowed.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field

from backend.api.models import Strict
from backend.api.schemas.authoring import EncodeDoc
from backend.api.schemas.common import CheckLineDoc, LimitViolation

#: Largest NED coordinate or distance the request takes (m): 1000 km.
_FAR_M = 1e6
#: Most vehicles a request lists (the survey itself allows 1 to 15).
_MOST_VEHICLES = 64

Metres = Annotated[float, Field(ge=-_FAR_M, le=_FAR_M)]
Heading = Annotated[float, Field(ge=-360, le=360, description="deg from north, clockwise")]


class SurveyAreaIn(Strict):
    """One lawnmower box (NED): the lanes start at the origin corner and run along
    ``heading_deg`` for ``length_m``; the area extends ``width_m`` to starboard of that heading
    (heading + 90 deg)."""

    origin_x_m: Metres = Field(description="the corner where the first lane starts, north (m)")
    origin_y_m: Metres = Field(description="the same corner, east (m)")
    heading_deg: Heading = Field(description="the lanes' direction (deg from north)")
    width_m: float = Field(gt=0, le=_FAR_M, description="across the lanes (m)")
    length_m: float = Field(gt=0, le=_FAR_M, description="along the lanes (m): the sweep length")
    lane_spacing_m: float = Field(gt=0, le=_FAR_M, description="between lanes; the swath (m)")
    depth_m: float = Field(ge=0, le=_FAR_M, description="survey depth (m)")
    speed_mps: float = Field(gt=0, le=100, description="survey speed (m/s)")


class SurveyVehicleIn(Strict):
    """A vehicle of the survey and where it is believed to be (NED)."""

    vehicle: str = Field(min_length=1, max_length=32, description="the vehicle's name")
    x_m: Metres
    y_m: Metres
    heading_deg: Heading
    z_m: float = Field(0.0, ge=0, le=_FAR_M, description="its depth (m); 0: at the surface")


class SurveyIn(Strict):
    area: SurveyAreaIn
    vehicles: list[SurveyVehicleIn] = Field(max_length=_MOST_VEHICLES)


class SurveyPosition(BaseModel):
    x_m: float
    y_m: float
    z_m: float
    heading_deg: float


class SurveyBlock(BaseModel):
    """A vehicle's lanes: indices into ``lanes_across_m``, numbered across from the origin."""

    index: int = Field(description="the block's place across, 0 at the origin's side")
    first_lane: int
    last_lane: int
    lane_count: int
    laps: int = Field(description="the lawnmower's laps: out-and-back pairs (2 lanes each)")


class SurveyEntry(BaseModel):
    """Where the vehicle must be, heading how, when its lawnmower takes effect (a lawnmower
    starts where the vehicle is, along its heading)."""

    x_m: float
    y_m: float
    heading_deg: float
    along_m: float = Field(description="in the area's frame: along the lanes from the origin")
    across_m: float = Field(description="in the area's frame: to starboard of the lane axis")
    from_end: bool = Field(description="entered at the lanes' far end, flying back")


class SurveyFootprint(BaseModel):
    """The block as its lawnmower flies it (area frame, m; lanes in flight order)."""

    along_start_m: float
    along_end_m: float
    lanes_across_m: list[float] = Field(description="the lanes flown")
    block_across_m: list[float] = Field(description="the block's lanes they stand for")
    max_lane_shift_m: float
    extra_lanes: int = Field(description="lanes flown outside the area (an odd block: 1)")
    sweep_length_m: float = Field(description="as sent")
    lane_spacing_m: float = Field(description="as sent")
    swath_m2: float = Field(description="its swath inside the area (m^2)")


class SurveyPath(BaseModel):
    """The transit, then the lawnmower (NED m; s on the plans' own clocks, end to end)."""

    x_m: list[float]
    y_m: list[float]
    z_m: list[float]
    t_s: list[float]
    body_start: int = Field(description="index of the lawnmower's first point (the entry)")


class SurveyVehicleDoc(BaseModel):
    """One vehicle's share: its block as its own lawnmower command."""

    vehicle: str
    from_: SurveyPosition = Field(alias="from", description="where it is believed to be")
    block: SurveyBlock
    entry: SurveyEntry
    command: EncodeDoc = Field(
        description="the command as /api/encode gives it: send pattern and params as they are"
    )
    exact: bool = Field(description="the lanes flown are exactly the block's")
    footprint: SurveyFootprint
    notes: list[str] = Field(description="what the codec's steps and lane pairs change")
    path: SurveyPath
    transit_length_m: float
    transit_duration_s: float = Field(description="as the vehicle flies it (the twin's)")
    survey_length_m: float
    survey_duration_s: float = Field(description="the lawnmower, as the vehicle flies it")
    duration_s: float = Field(description="transit_duration_s + survey_duration_s")
    duration_notes: list[str]
    violations: list[LimitViolation]
    checks: list[CheckLineDoc] = Field(description="the send's checks of its lawnmower")


class SurveyCoverage(BaseModel):
    """The area's cells by the vehicles' swaths (m^2; fractions of ``area_m2``)."""

    cell_along_m: float
    cell_across_m: float
    area_m2: float
    covered_m2: float
    covered_fraction: float
    overlap_m2: float = Field(description="covered by more than one vehicle")
    overlap_fraction: float
    gap_m2: float = Field(description="covered by none")
    gap_fraction: float


class SurveyPreviewDoc(BaseModel):
    """The survey split among the vehicles, each block its vehicle's own lawnmower."""

    lanes: int
    lanes_across_m: list[float] = Field(description="the area's lanes, across from the origin")
    vehicles: list[SurveyVehicleDoc]
    coverage: SurveyCoverage
    time_to_finish_s: float = Field(description="the slowest vehicle's duration_s")
    slowest: str
    exact: bool = Field(description="every block is flown exactly")
    assumptions: list[str]
