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
    ADDRESSED_FRAME_BITS,
    BROADCAST_ADDRESS,
    FRAME_BITS,
    AddressedDecoded,
    AddressedFrame,
    Command,
    Decoded,
    DecodeError,
    Encoded,
    RejectReason,
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


#: The text forms of a frame, by length (characters, once spaces, ``_`` and a ``0x`` are
#: dropped): a single vehicle's 100 bits or 25 hex digits, a fleet's addressed 108 bits or 27.
_SINGLE_LENGTHS = (FRAME_BITS, FRAME_BITS // 4)
_ADDRESSED_LENGTHS = (ADDRESSED_FRAME_BITS, ADDRESSED_FRAME_BITS // 4)
_HEX_DIGITS = "0123456789abcdefABCDEF"


def decode_text(text: str) -> Decoded:
    """The frame ``text`` as the console reads it: a 100-bit frame as the single vehicle
    decodes it (:func:`codec.decode_frame`), a 108-bit addressed one with any address
    (:class:`codec.AddressedDecoded`: its ``address``, 0 for all vehicles). Its length decides
    which, never a guess at what a broken frame might have been.

    Raises:
        DecodeError: the codec's reason; a length of neither is ``malformed``, naming both.
    """
    compact = text.strip().replace(" ", "").replace("_", "")
    if compact[:2].lower() == "0x":
        compact = compact[2:]
    if len(compact) in _ADDRESSED_LENGTHS:
        digits = "01" if len(compact) == ADDRESSED_FRAME_BITS else _HEX_DIGITS
        bad = [c for c in compact if c not in digits]
        if bad:
            kind = "binary" if digits == "01" else "hex"
            raise DecodeError(
                RejectReason.MALFORMED,
                f"malformed frame: {len(compact)} {kind} digits make an addressed frame, but "
                f"{bad[0]!r} is no {kind} digit",
            )
        return decode_addressed_frame(compact)
    if len(compact) in _SINGLE_LENGTHS:
        return decode_frame(text)
    shown = text if len(text) <= 40 else text[:37] + "..."
    raise DecodeError(
        RejectReason.MALFORMED,
        f"malformed frame: expected {FRAME_BITS} binary digits or {FRAME_BITS // 4} hex digits "
        f"(a single vehicle's frame), or {ADDRESSED_FRAME_BITS} binary digits or "
        f"{ADDRESSED_FRAME_BITS // 4} hex digits (a fleet's addressed frame), got "
        f"{len(compact)} characters: {shown!r}",
    )


def addressee(console: Console, decoded: AddressedDecoded) -> tuple[str | None, str]:
    """Whom an addressed frame is for on this console: the name of the fleet's vehicle with
    its address (``"all"`` for address 0; None: no vehicle of this console has it), and that
    in words."""
    address = decoded.address
    if address == BROADCAST_ADDRESS:
        return ALL_VEHICLES, f"all vehicles (address {address})"
    if console.fleet.configured:
        for vehicle in console.fleet.vehicles.values():
            if vehicle.address == address:
                return vehicle.name, f"{vehicle.name} (address {address})"
        has = ", ".join(f"{v.name} {v.address}" for v in console.fleet.vehicles.values())
        return None, f"address {address}: no vehicle of this console's fleet ({has})"
    return None, f"address {address}: this console has no fleet (one vehicle, unaddressed)"


__all__ = [
    "addressee",
    "assess",
    "decode_text",
    "encode",
    "plan_violations",
    "preview",
    "report",
]
