"""Session, dictionary, preview, encode, decode: read-only, no token needed."""

from __future__ import annotations

from dataclasses import asdict

from fastapi import APIRouter, HTTPException, Request
from pydantic import TypeAdapter

from backend.api.deps import ConsoleDep, token_from, token_ok
from backend.api.models import CommandIn, DecodeIn
from backend.api.responses import DocResponse
from backend.api.schemas import (
    AddressedDecodeResult,
    DecodeFailure,
    DecodeResult,
    EncodeDoc,
    PatternDoc,
    PreviewDoc,
    Session,
    ValidationErrorResponse,
    errors,
)
from backend.api.schemas.authoring import (
    LinkCapability,
    SessionConsole,
    SessionLimits,
    VehicleProfileDoc,
)
from backend.api.schemas.chart import DatumDoc
from backend.api.view import ViewHeader
from backend.authoring import operations
from backend.mission_log.records import CommandJson
from codec import AddressedDecoded, DecodeError, describe_dictionary
from onboard.agent import command_json
from station.link import Capability

router = APIRouter(prefix="/api", tags=["authoring"])

#: The command dictionary as its documents (the codec describes it; read once per call).
_PATTERNS = TypeAdapter(list[PatternDoc])


@router.get("/session", response_model=Session)
def session(request: Request, console: ConsoleDep) -> Session:
    """Mode, target, where the 3D view is, and whether the caller holds the operator token."""
    s, d = console.settings, console.datum
    token = token_from(request.headers.get("authorization"), request.headers.get("x-nemesys-token"))
    viewer_url = None
    if console.viewer is not None:
        host = request.url.hostname or s.viewer_host
        viewer_url = f"/viewer/?websocket=ws://{host}:{console.viewer.port}&hideViserLogo"
    return Session(
        mode="training" if s.training else "vehicle",
        target=s.target,
        viewer_url=viewer_url,
        bitrate_bps=s.bitrate_bps,
        operator=s.operator,
        authenticated=token_ok(console, token),
        dive=console.dive,
        version=request.app.version,
        limits=SessionLimits(max_depth_m=s.max_depth_m, max_speed_mps=s.max_speed_mps),
        link=_link_capability(console),
        profile=VehicleProfileDoc.model_validate(asdict(console.profile)),
        datum=None if d is None else DatumDoc(lat_deg=d.lat_deg, lon_deg=d.lon_deg),
        console=_console(console),
    )


def _console(console: ConsoleDep) -> SessionConsole | None:
    if console.control is None:
        return None
    desk = console.control.desk
    return SessionConsole(
        name=desk.console, shared_log=desk.shared, control_timeout_s=desk.timeout_s
    )


def _link_capability(console: ConsoleDep) -> LinkCapability:
    link = console.link
    if link is None:
        return LinkCapability(capability=Capability.UNKNOWN, acknowledges=False, telemetry=False)
    return LinkCapability(
        capability=link.capability, acknowledges=link.acknowledges, telemetry=link.telemetry
    )


@router.get(
    "/dictionary",
    response_model=list[PatternDoc],
    response_model_exclude_unset=True,  # a field's optional keys stay absent, as in the codec
)
def dictionary() -> list[PatternDoc]:
    """Every pattern with its fields: name, unit, range, steps, default, choices."""
    return _PATTERNS.validate_python(describe_dictionary())


# preview and encode answer their model in a DocResponse (rendered once, by pydantic-core). They
# are async: their work (0.3-1.2 ms) runs on the event loop without a thread hop per request,
# and the preview's drawing is queued from the loop's thread.
@router.post(
    "/preview",
    response_class=DocResponse,
    response_model=PreviewDoc,
    responses=errors((413, 422)),
)
async def preview(
    body: CommandIn, console: ConsoleDep, x_nemesys_view: ViewHeader = None
) -> DocResponse:
    """The frame (bits, sections, hex, airtime) and the path the vehicle would fly from where it
    is now, expanded from the decoded packet, with estimates, limit violations and the diff
    against the active pattern. Also drawn in the caller's own 3D view (``X-Nemesys-View``).
    With a fleet, of ``vehicle`` (required: 422 naming the vehicles), its frame addressed."""
    vehicle = console.checked_vehicle(body.vehicle)
    doc = console.preview(body.pattern, dict(body.params), view=x_nemesys_view, vehicle=vehicle)
    return DocResponse(PreviewDoc.model_validate(doc))


@router.post(
    "/encode", response_class=DocResponse, response_model=EncodeDoc, responses=errors((413, 422))
)
async def encode(body: CommandIn, console: ConsoleDep) -> DocResponse:
    """The frame only: snapped values, bits by section, hex, airtime. With a fleet,
    ``vehicle`` (or ``"all"``) gives the addressed frame; omitted, the unaddressed one."""
    surface = body.pattern == "surface"
    vehicle = (
        None if body.vehicle is None else console.checked_vehicle(body.vehicle, surface=surface)
    )
    _, doc = operations.encode(console, body.pattern, dict(body.params), vehicle)
    return DocResponse(EncodeDoc.model_validate(doc))


@router.post(
    "/decode",
    # the addressed answer first: a single vehicle's lacks its fields, so is never taken for one
    response_model=AddressedDecodeResult | DecodeResult,
    responses=errors(
        (413, 422),
        models={422: ValidationErrorResponse | DecodeFailure},
        why={422: "invalid input, or the frame is rejected (detail: reason, message, field)"},
    ),
)
def decode(body: DecodeIn, console: ConsoleDep) -> AddressedDecodeResult | DecodeResult:
    """Decode a frame: 100 bits or 25 hex digits (a single vehicle's), or a fleet's addressed
    frame, 108 bits or 27 hex digits (then also its ``address``, the console's ``vehicle``
    with it, ``"all"`` for 0, and ``addressed_to`` in words); 422 with the reason when the
    frame is rejected, a wrong length naming both."""
    try:
        dec = operations.decode_text(body.frame)
    except DecodeError as err:
        raise HTTPException(
            422, {"reason": err.reason.value, "message": str(err), "field": err.field}
        ) from None
    command = CommandJson.model_validate(command_json(dec.command))
    if isinstance(dec, AddressedDecoded):
        vehicle, words = operations.addressee(console, dec)
        return AddressedDecodeResult(
            ok=True,
            command=command,
            corrected=dec.corrected,
            sync_errors=dec.sync_errors,
            address=dec.address,
            vehicle=vehicle,
            addressed_to=words,
        )
    return DecodeResult(
        ok=True, command=command, corrected=dec.corrected, sync_errors=dec.sync_errors
    )
