"""The checks of a send from the command line (:class:`Assessment`), from the surface at the
NED origin: ``nemesys send`` does not know where the vehicle is. The same
:func:`backend.commands.checks.check_plan` as the console's (``Console.assess``) and the
preview's."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from backend.authoring.profile import VehicleProfile
from backend.commands.checks import check_plan
from backend.commands.service import Assessment
from backend.settings import Settings
from codec import decode_frame, encode_frame
from planner import Limits, VehicleState, plan


def assess_from(
    pattern: str, params: Mapping[str, Any], settings: Settings, profile: VehicleProfile
) -> Assessment:
    """The checks of a command planned from the surface at the NED origin, with the settings'
    limits and ``profile``, the battery unknown (checked as full) and the reach skipped (the
    vehicle's position is unknown).

    Raises:
        codec.EncodeError / planner.PlanError: naming the parameter at fault.
    """
    enc = encode_frame(pattern, dict(params))
    new = plan(decode_frame(enc.frame.bits).command, VehicleState(0.0, 0.0, 0.0), None)
    limits = Limits(max_depth_m=settings.max_depth_m, max_speed_mps=settings.max_speed_mps)
    report = check_plan(
        new, limits=limits, profile=profile, soc_pct=None, station=None, range_m=None
    )
    return Assessment(enc, report.violations, report.lines)
