"""The authoring operations on the running console: a command's frame, its preview from where
the vehicle is now, and the checks the command service and the scripts take.

:class:`backend.console.Console` keeps its methods (``encode``, ``preview``, ``assess``,
``plan_violations``) and answers them from here: they read the console's state (the
vehicle as last reported, the mirrored active path, the battery, the station, the link)
and change none of it, except queueing the preview's drawing in the 3D view.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from backend.authoring.preview import frame_doc, plan_doc
from backend.chart.reach import add_geo
from backend.commands.checks import CheckReport, SendViolation, check_plan
from backend.commands.service import Assessment
from codec import Encoded, decode_frame, delivery_probability, encode_frame
from planner import Plan, plan
from vehicle_contract.messages import number

if TYPE_CHECKING:
    from backend.console import Console


def encode(
    console: Console, pattern: str, params: dict[str, Any]
) -> tuple[Encoded, dict[str, Any]]:
    """Encode (raises codec.EncodeError naming the field) and describe the frame."""
    enc = encode_frame(pattern, params)
    return enc, frame_doc(enc, console.settings.bitrate_bps)


def report(console: Console, new: Plan) -> CheckReport:
    """Every check of the planned command ``new``, with the battery as it is now."""
    return check_plan(
        new,
        limits=console.limits,
        profile=console.profile,
        soc_pct=number((console.hub.status or {}).get("battery_pct")),
        station=console.station(),
        range_m=console.settings.me_range_m,
    )


def plan_violations(console: Console, new: Plan) -> tuple[SendViolation, ...]:
    """The send policy's checks of a planned command (a mission script's step)."""
    return report(console, new).violations


def assess(console: Console, pattern: str, params: Mapping[str, Any]) -> Assessment:
    """The checks of a send from where the vehicle is now (the command service's).

    Raises:
        codec.EncodeError / planner.PlanError: naming the parameter at fault.
    """
    enc = encode_frame(pattern, dict(params))
    cmd = decode_frame(enc.frame.bits).command  # what the vehicle will decode
    current = console.commands.mirror if console.commands else None
    found = report(console, plan(cmd, console.vehicle_state(), current))
    return Assessment(enc, found.violations, found.lines)


def preview(
    console: Console,
    pattern: str,
    params: dict[str, Any],
    *,
    show: bool,
    view: str | None = None,
) -> tuple[Encoded, dict[str, Any]]:
    """The frame and the path the vehicle would fly from where it is now, with the checks,
    the chart's reach and what sending it now would do; drawn (``show``) in the 3D view of
    page ``view``.

    Raises:
        codec.EncodeError / planner.PlanError: naming the parameter at fault.
    """
    enc, doc = encode(console, pattern, params)
    cmd = decode_frame(enc.frame.bits).command  # what the vehicle will decode
    state, start = console.vehicle_start()
    current = console.commands.mirror if console.commands else None
    new = plan(cmd, state, current)
    path = new.path
    soc = number((console.hub.status or {}).get("battery_pct"))
    station, range_m = console.station(), console.settings.me_range_m
    doc.update(
        plan_doc(
            new, current, console.limits, console.profile, soc, station=station, range_m=range_m
        )
    )
    add_geo(doc, console.datum, station, range_m)  # lat/lon, the chart's reach
    doc["from"] = state.as_dict()
    doc["start"] = start.model_dump()  # telemetry, dead reckoning or assumed: the page says
    if console.commands is not None:
        # what sending it now would do: copies chosen from the link, and their odds
        ber, loss = console.link_ber()
        copies = console.commands.copies_now()
        doc["two_way"] = console.commands.link.acknowledges
        doc["copies"] = copies
        doc["p_delivered"] = delivery_probability(ber, copies, loss=loss)
    if show and view is not None and console.viewer is not None:
        console.drawer.later(
            view, path.xs, path.ys, path.zs, path.body_start, f"preview: {cmd.pattern.name}"
        )
    if show and view is not None and console.foxglove is not None:  # the latest a page drew
        console.foxglove.preview(
            path.xs, path.ys, path.zs, path.body_start, f"preview: {cmd.pattern.name}"
        )
    return enc, doc


__all__ = ["assess", "encode", "plan_violations", "preview", "report"]
