"""The authoring operations on the running console: a command's frame, its preview from where
the vehicle is now, and the checks the command service and the scripts take.

:class:`backend.console.Console` keeps its methods (``encode``, ``preview``, ``assess``,
``plan_violations``) and answers them from here: they read the console's state (the
vehicle as last reported, the mirrored active path, the battery, the station, the link)
and change none of it, except queueing the preview's drawing in the 3D view. With a fleet each
takes the ``vehicle`` it is for (the command service has checked the name): its position, its
mirrored path, its battery, its link; and the frame carries its address.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from backend.authoring.preview import frame_doc, plan_doc
from backend.chart.reach import add_geo
from backend.commands.checks import CheckReport, SendViolation, check_plan
from backend.commands.service import Assessment
from backend.commands.vehicles import ALL_VEHICLES
from codec import (
    AddressedFrame,
    Command,
    Encoded,
    decode_addressed_frame,
    decode_frame,
    delivery_probability,
    encode_frame,
)
from planner import Plan, plan
from vehicle_contract.messages import number

if TYPE_CHECKING:
    from backend.console import Console


def _address(console: Console, vehicle: str | None) -> int | None:
    """The address a fleet's ``vehicle``'s frames carry (None: the single vehicle's)."""
    if vehicle is None or not console.fleet.configured:
        return None
    return 0 if vehicle == ALL_VEHICLES else console.fleet.get(vehicle).address


def _decoded(enc: Encoded) -> Command:
    """The command the vehicle will decode from ``enc``'s frame (addressed or not)."""
    if isinstance(enc.frame, AddressedFrame):
        return decode_addressed_frame(enc.frame).command
    return decode_frame(enc.frame.bits).command


def _mirror(console: Console, vehicle: str | None) -> Plan | None:
    """The plan the vehicle flies as mirrored (a fleet's ``vehicle``'s)."""
    cm = console.commands
    if cm is None:
        return None
    return cm.addressee(vehicle if console.fleet.configured else None).mirror.plan


def _battery(console: Console, vehicle: str | None) -> float | None:
    return number((console.fleet.get(vehicle).hub.status or {}).get("battery_pct"))


def encode(
    console: Console, pattern: str, params: dict[str, Any], vehicle: str | None = None
) -> tuple[Encoded, dict[str, Any]]:
    """Encode (raises codec.EncodeError naming the field; a fleet's ``vehicle``: its address
    in the frame) and describe the frame."""
    enc = encode_frame(pattern, params, address=_address(console, vehicle))
    return enc, frame_doc(enc, console.settings.bitrate_bps)


def report(console: Console, new: Plan, vehicle: str | None = None) -> CheckReport:
    """Every check of the planned command ``new``, with the battery (of a fleet's
    ``vehicle``) as it is now."""
    return check_plan(
        new,
        limits=console.limits,
        profile=console.profile,
        soc_pct=_battery(console, vehicle),
        station=console.station(),
        range_m=console.settings.me_range_m,
    )


def plan_violations(
    console: Console, new: Plan, vehicle: str | None = None
) -> tuple[SendViolation, ...]:
    """The send policy's checks of a planned command (a mission script's step)."""
    return report(console, new, vehicle).violations


def assess(
    console: Console, pattern: str, params: Mapping[str, Any], vehicle: str | None = None
) -> Assessment:
    """The checks of a send from where the vehicle (a fleet's ``vehicle``) is now (the
    command service's); the frame carries its address.

    Raises:
        codec.EncodeError / planner.PlanError: naming the parameter at fault.
    """
    enc = encode_frame(pattern, dict(params), address=_address(console, vehicle))
    cmd = _decoded(enc)  # what the vehicle will decode
    current = _mirror(console, vehicle)
    found = report(console, plan(cmd, console.vehicle_state(vehicle), current), vehicle)
    return Assessment(enc, found.violations, found.lines)


def preview(
    console: Console,
    pattern: str,
    params: dict[str, Any],
    *,
    show: bool,
    view: str | None = None,
    vehicle: str | None = None,
) -> tuple[Encoded, dict[str, Any]]:
    """The frame and the path the vehicle would fly from where it is now, with the checks,
    the chart's reach and what sending it now would do; drawn (``show``) in the 3D view of
    page ``view``. A fleet's ``vehicle``: from where it is, its frame addressed.

    Raises:
        codec.EncodeError / planner.PlanError: naming the parameter at fault.
    """
    enc, doc = encode(console, pattern, params, vehicle)
    cmd = _decoded(enc)  # what the vehicle will decode
    state, start = console.vehicle_start(vehicle)
    current = _mirror(console, vehicle)
    new = plan(cmd, state, current)
    path = new.path
    soc = _battery(console, vehicle)
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
        key = vehicle if console.fleet.configured else None
        ber, loss = console.link_ber(key)
        copies = console.commands.copies_now(key)
        doc["two_way"] = console.commands.addressee(key).acknowledges
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
