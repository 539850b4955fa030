"""A survey preview as the API gives it (``POST /api/survey/preview``,
:class:`backend.api.schemas.survey.SurveyPreviewDoc`): each vehicle's command as the encode
API gives a frame (:func:`backend.authoring.preview.frame_doc`), its path (the transit, then
the lawnmower), footprint, durations and checks; the coverage and the time to finish."""

from __future__ import annotations

from typing import Any, Final

from backend.authoring.preview import frame_doc
from backend.authoring.survey.command import VehicleSurvey
from backend.authoring.survey.preview import SurveyPreview

#: What the preview takes for granted, in words (the page shows them).
ASSUMPTIONS: Final = (
    "a lawnmower starts where its vehicle is when it takes effect, along its heading: send "
    "each command once its vehicle is at its entry, heading as the entry says; the transit "
    "there is the planner's join (turn, straight, turn) at the survey speed",
    "each swath is one lane spacing wide, centred on the vehicle's planned path",
    "the battery is checked as full: a fleet vehicle's charge is not known here",
)


def survey_doc(preview: SurveyPreview, bitrate_bps: float) -> dict[str, Any]:
    """The preview's document (NED m, s, m^2; fractions of the area's m^2)."""
    cov = preview.coverage
    return {
        "lanes": len(preview.lanes_across_m),
        "lanes_across_m": list(preview.lanes_across_m),
        "vehicles": [
            _vehicle_doc(v, m2, bitrate_bps)
            for v, m2 in zip(preview.vehicles, cov.vehicle_m2, strict=True)
        ],
        "coverage": {
            "cell_along_m": cov.cell_along_m,
            "cell_across_m": cov.cell_across_m,
            "area_m2": cov.area_m2,
            "covered_m2": cov.covered_m2,
            "covered_fraction": cov.covered_fraction,
            "overlap_m2": cov.overlap_m2,
            "overlap_fraction": cov.overlap_fraction,
            "gap_m2": cov.gap_m2,
            "gap_fraction": cov.gap_fraction,
        },
        "time_to_finish_s": preview.time_to_finish_s,
        "slowest": preview.slowest,
        "exact": all(v.footprint.exact for v in preview.vehicles),
        "assumptions": list(ASSUMPTIONS),
    }


def _vehicle_doc(v: VehicleSurvey, swath_m2: float, bitrate_bps: float) -> dict[str, Any]:
    a, f = v.assignment, v.footprint
    block, entry, start = a.block, a.entry, v.vehicle
    return {
        "vehicle": start.name,
        "from": {
            "x_m": start.x_m,
            "y_m": start.y_m,
            "z_m": start.z_m,
            "heading_deg": start.heading_deg,
        },
        "block": {
            "index": block.index,
            "first_lane": block.first_lane,
            "last_lane": block.last_lane,
            "lane_count": block.lane_count,
            "laps": block.laps,
        },
        "entry": {
            "x_m": entry.x_m,
            "y_m": entry.y_m,
            "heading_deg": entry.heading_deg,
            "along_m": entry.along_m,
            "across_m": entry.across_m,
            "from_end": entry.from_end,
        },
        "command": frame_doc(v.encoded, bitrate_bps),
        "exact": f.exact,
        "footprint": {
            "along_start_m": f.along_start_m,
            "along_end_m": f.along_end_m,
            "lanes_across_m": list(f.lanes_across_m),
            "block_across_m": list(f.block_across_m),
            "max_lane_shift_m": f.max_lane_shift_m,
            "extra_lanes": f.extra_lanes,
            "sweep_length_m": f.sweep_length_m,
            "lane_spacing_m": f.lane_spacing_m,
            "swath_m2": swath_m2,
        },
        "notes": list(v.notes),
        "path": _path_doc(v),
        "transit_length_m": v.transit_length_m,
        "transit_duration_s": v.transit_duration_s,
        "survey_length_m": v.survey_estimate.length_m,
        "survey_duration_s": v.survey_estimate.duration_s,
        "duration_s": v.duration_s,
        "duration_notes": list(v.duration_notes),
        "violations": [x.as_json() for x in v.report.violations],
        "checks": [
            {"check": line.check, "status": line.status, "detail": line.detail}
            for line in v.report.lines
        ],
    }


def _path_doc(v: VehicleSurvey) -> dict[str, Any]:
    """The transit, then the lawnmower (its first point is the transit's last), on the plans'
    own clocks run end to end; ``body_start`` the lawnmower's first point."""
    survey = v.survey.path
    xs, ys, zs, ts = list(survey.xs), list(survey.ys), list(survey.zs), list(survey.times)
    body_start = 0
    if v.transit is not None:
        transit = v.transit.path
        offset = transit.times[-1]
        body_start = len(transit) - 1
        xs = [*transit.xs[:-1], *xs]
        ys = [*transit.ys[:-1], *ys]
        zs = [*transit.zs[:-1], *zs]
        ts = [*transit.times[:-1], *(t + offset for t in ts)]
    return {"x_m": xs, "y_m": ys, "z_m": zs, "t_s": ts, "body_start": body_start}
