"""The checks of a send as the command service takes them (:class:`Assessment`), from a plan:
the console's (from where the vehicle is now) and the command line's (from the surface at the
NED origin: ``nemesys send`` does not know where the vehicle is)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from backend.authoring.preview import plan_doc
from backend.authoring.profile import VehicleProfile
from backend.commands.service import Assessment, Violation
from backend.settings import Settings
from codec import Encoded, decode_frame, encode_frame
from planner import Limits, Plan, VehicleState, plan


def violation_of(v: Mapping[str, Any]) -> Violation:
    """A violation of the preview document, as the command service takes it."""
    return Violation(
        check=str(v.get("check") or v["param"]),
        param=str(v["param"]),
        kind="soft" if v["overridable"] else "hard",
        message=str(v["message"]),
        value=v.get("value"),
        limit=v.get("limit"),
        unit=str(v.get("unit") or ""),
        allowed=str(v.get("allowed") or ""),
    )


def assessment_of(enc: Encoded, violations: list[dict[str, Any]]) -> Assessment:
    return Assessment(enc, tuple(violation_of(v) for v in violations))


def assess_from(
    pattern: str, params: Mapping[str, Any], settings: Settings, profile: VehicleProfile
) -> Assessment:
    """The checks of a command planned from the surface at the NED origin, with the settings'
    limits and ``profile``, at a full battery.

    Raises:
        codec.EncodeError / planner.PlanError: naming the parameter at fault.
    """
    enc = encode_frame(pattern, dict(params))
    new: Plan = plan(decode_frame(enc.frame.bits).command, VehicleState(0.0, 0.0, 0.0), None)
    limits = Limits(max_depth_m=settings.max_depth_m, max_speed_mps=settings.max_speed_mps)
    return assessment_of(enc, plan_doc(new, None, limits, profile, None)["violations"])
