"""A fleet survey (issue 23, item 6): one lawnmower area split into lane blocks, one per
vehicle, each that vehicle's own lawnmower; :func:`preview_survey` is the entry point."""

from backend.authoring.survey.area import SurveyArea, SurveyError, SurveyVehicle
from backend.authoring.survey.command import SurveyChecks, VehicleSurvey
from backend.authoring.survey.preview import SurveyPreview, preview_survey

__all__ = [
    "SurveyArea",
    "SurveyChecks",
    "SurveyError",
    "SurveyPreview",
    "SurveyVehicle",
    "VehicleSurvey",
    "preview_survey",
]
