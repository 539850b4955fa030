"""``POST /api/survey/preview``: one lawnmower area split among vehicles, each block its
vehicle's own lawnmower command (read-only, no token needed; nothing is sent: each command
goes through the normal send, ``POST /api/commands``, one vehicle at a time)."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import JSONResponse

from backend.api.deps import ConsoleDep
from backend.api.responses import DocResponse
from backend.api.schemas import errors
from backend.api.schemas.survey import SurveyIn, SurveyPreviewDoc
from backend.authoring.survey import (
    SurveyArea,
    SurveyChecks,
    SurveyError,
    SurveyVehicle,
    preview_survey,
)
from backend.authoring.survey.doc import survey_doc
from backend.bounded_input import shorten

router = APIRouter(prefix="/api", tags=["authoring"])


# a plain def: the survey's work (a plan, two twin flights and a raster per vehicle, 5-50 ms)
# runs in the threadpool, not on the event loop the previews share
@router.post(
    "/survey/preview",
    response_class=DocResponse,
    response_model=SurveyPreviewDoc,
    responses=errors(
        (413, 422),
        why={
            422: "invalid input, or a survey that cannot be made of it (loc names the field: "
            "the area's, or a vehicle's; msg says what is allowed)"
        },
    ),
)
def survey_preview(body: SurveyIn, console: ConsoleDep) -> JSONResponse:
    """Split the area's lanes into one block per vehicle (assigned to minimise the time to
    finish), each block that vehicle's lawnmower from its entry: the commands (snapped to the
    codec's scales, checked as every send is), the paths (transit, then lanes), the coverage,
    overlaps and gaps of their swaths, and the time to finish."""
    area = SurveyArea(**body.area.model_dump())
    vehicles = [SurveyVehicle(v.vehicle, v.x_m, v.y_m, v.heading_deg, v.z_m) for v in body.vehicles]
    checks = SurveyChecks(
        console.limits, console.profile, console.station(), console.settings.me_range_m
    )
    try:
        preview = preview_survey(area, vehicles, checks)
    except SurveyError as err:
        item = {"loc": ["body", *err.loc], "msg": shorten(str(err)), "type": "survey_error"}
        return JSONResponse({"detail": [item]}, status_code=422)
    doc = survey_doc(preview, console.settings.bitrate_bps)
    return DocResponse(SurveyPreviewDoc.model_validate(doc))
