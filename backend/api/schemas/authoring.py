"""Session, dictionary, encode, preview and decode documents."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, Field

from backend.api.schemas.chart import DatumDoc, LinkReach
from backend.api.schemas.common import (
    CheckLineDoc,
    CommandJson,
    LimitViolation,
    Number,
    Params,
    ParamValue,
    VehicleStateOut,
)
from backend.belief.model import BelievedPosition
from station.link import Capability

# --- session ------------------------------------------------------------------------------


class SessionLimits(BaseModel):
    max_depth_m: float
    max_speed_mps: float


class LinkCapability(BaseModel):
    """What the vehicle link can report back (``unknown`` before it is known)."""

    capability: Capability
    acknowledges: bool
    telemetry: bool


class VehicleProfileDoc(BaseModel):
    """What the vehicle can do (``backend/authoring/profile.py``): the twin's figures in training,
    the
    settings' for a real vehicle; null: unknown (the checks needing it are skipped)."""

    top_speed_mps: float | None = Field(description="top speed through the water (m/s)")
    heave_rate_mps: float | None = Field(description="largest vertical speed (m/s)")
    yaw_rate_dps: float | None = Field(description="largest turn rate (deg/s)")
    max_depth_m: float = Field(description="deepest allowed depth (m)")
    endurance_s: float | None = Field(description="time on a full battery at cruise (s)")
    source: Literal["twin", "settings"]
    ascent_rate_mps: float | None = Field(
        default=None, description="largest ascent rate (m/s); null: the heave rate's"
    )


class SessionConsole(BaseModel):
    """This console among those that may share its mission log (who is in control of each
    vehicle: ``/api/control``)."""

    name: str = Field(
        description="this console's name (NEMESYS_CONSOLE_NAME, else the one kept beside its log)"
    )
    shared_log: bool = Field(
        description="true: the mission log is a PostgreSQL database other consoles may share; "
        "control of each vehicle is explicit (request, grant, refuse, release, takeover) and "
        "only the console in control sends. false: a SQLite file, this console alone, always "
        "in control (no send is refused for control)"
    )
    control_timeout_s: float = Field(
        description="a control is released this long after its console's last heartbeat (s; "
        "a shared log only)"
    )


class Session(BaseModel):
    """Mode, target, where the 3D view is, and whether the caller holds the operator token."""

    mode: Literal["training", "vehicle"]
    target: str
    viewer_url: str | None = Field(description="the 3D view's page; null without a viewer")
    bitrate_bps: float
    operator: str
    authenticated: bool = Field(description="the request carried the operator token")
    dive: int | None = Field(
        description="the current dive; null: none yet (a dive starts when the vehicle is first "
        "heard, at the first command or event before that, or at a training reset)"
    )
    version: str
    limits: SessionLimits
    link: LinkCapability
    profile: VehicleProfileDoc
    datum: DatumDoc | None = Field(
        description="the NED origin's lat/lon (deg, WGS84); null: none yet (metres only)"
    )
    console: SessionConsole | None = Field(
        description="this console and its mission log; null: it is starting"
    )


# --- dictionary ---------------------------------------------------------------------------


class ScaleSegment(BaseModel):
    start: float
    step: float
    count: int


class _FieldDoc(BaseModel):
    j: int = Field(description="position in the frame: 1 for j1")
    name: str
    label: str
    unit: str
    doc: str
    scale: str
    range: str
    steps: str
    error: str


class ChoiceFieldDoc(_FieldDoc):
    """A field whose value is one of ``choices``."""

    kind: Literal["choice"]
    default: ParamValue
    choices: list[str]


class NumberFieldDoc(_FieldDoc):
    """A numeric field (``count``: integers): its range, codes and scale segments."""

    kind: Literal["count", "number"]
    default: ParamValue
    min: Number
    max: Number
    codes: list[int] = Field(description="first and last code")
    segments: list[ScaleSegment]
    period: float | None = Field(None, description="present for a periodic scale (angles)")
    max_rel_error: float | None = Field(None, description="present for a relative scale")
    max_abs_error: float


FieldDoc = Annotated[ChoiceFieldDoc | NumberFieldDoc, Field(discriminator="kind")]


class PatternDoc(BaseModel):
    """A pattern of the command dictionary with its fields (j1..j6)."""

    id: int
    name: str
    label: str
    doc: str
    fields: list[FieldDoc]


# --- encode / preview / decode ------------------------------------------------------------


class Snap(BaseModel):
    """A value as asked for and as sent (snapped to the field's steps)."""

    field: str
    requested: ParamValue
    sent: ParamValue
    unit: str
    changed: bool
    text: str


class FrameSection(BaseModel):
    name: str
    start: int
    length: int
    bits: str


class EncodeDoc(CommandJson):
    """The frame: snapped values, bits by section, hex, airtime."""

    requested: Params
    snaps: list[Snap]
    bits: str
    hex: str
    sections: list[FrameSection]
    airtime_ms: float
    bitrate_bps: float
    frame_bits: int


class PlannedPath(BaseModel):
    """The path (NED m, s from the command's start; lat/lon deg); ``body_start``: the index
    where the pattern begins after the join; ``repeats``: the pattern loops."""

    x_m: list[float]
    y_m: list[float]
    z_m: list[float]
    t_s: list[float]
    body_start: int
    repeats: bool
    lat_deg: list[float] | None = Field(description="from the datum; null without one")
    lon_deg: list[float] | None


class PlanEstimate(BaseModel):
    """Size and cost of the path (a repeating pattern: the join and one lap). Durations (s:
    ``duration_s``, ``transit_duration_s``/``join_duration_s``, ``lap_duration_s``) and
    ``battery_pct`` are as the vehicle flies the path: the onboard guidance on a vehicle of
    its profile (top speed, heave, ascent and yaw rates), the motion model the prediction's
    twin shares; ``planned_duration_s`` is the path's own clock, at the commanded speed and
    the planner's depth ramps; ``duration_notes`` says why the two differ where they differ
    by more than 20 %."""

    waypoints: int
    length_m: float
    duration_s: float = Field(
        description="duration as the vehicle flies it (s): a finite pattern to its end and "
        "depth, a repeating one the join and one lap"
    )
    planned_duration_s: float = Field(
        description="duration by the plan's own clock (s): the path's times, at the commanded speed"
    )
    planned_speed_mps: float | None = Field(
        description="the speed the plan asks for (m/s); null: it does not move horizontally"
    )
    flyable_speed_mps: float | None = Field(
        description="the speed the vehicle will fly: min(planned, top speed) (m/s)"
    )
    transit_length_m: float
    transit_duration_s: float
    lap_length_m: float | None
    lap_duration_s: float | None
    depth_min_m: float
    depth_max_m: float
    x_min_m: float
    x_max_m: float
    y_min_m: float
    y_max_m: float
    join_length_m: float
    join_duration_s: float
    repeats: bool = Field(
        description="the pattern repeats its lap until retasked: ``duration_s`` is the join "
        "and one lap (``lap_duration_s``), never a total"
    )
    battery_pct: float = Field(
        description="charge used (percentage points): the whole battery fit from the charge now"
    )
    duration_notes: list[str] = Field(
        description="why duration_s and planned_duration_s differ, in words, where they differ "
        "by more than 20 % (empty otherwise)"
    )


class ParamChange(BaseModel):
    param: str
    old: ParamValue | None
    new: ParamValue | None
    unit: str


class PlanDiff(BaseModel):
    """What replacing the vehicle's active pattern by this one changes."""

    active: str
    changes: list[ParamChange]
    pattern_changed: bool
    duration_delta_s: float | None
    length_delta_m: float | None
    anchor_moved_m: float


class PreviewDoc(EncodeDoc):
    """The frame and the path the vehicle would fly from where it is now, with estimates,
    the checks and their violations, the diff against the active pattern, and what sending
    it now would do (``two_way``, ``copies``, ``p_delivered``: absent while the console starts)."""

    path: PlannedPath
    estimate: PlanEstimate
    violations: list[LimitViolation]
    checks: list[CheckLineDoc] = Field(
        description="every check a send runs (backend/commands/checks.py), in order, with its "
        "status"
    )
    skipped_checks: list[str] = Field(
        description="checks and estimates the vehicle profile's unknown figures prevent"
    )
    diff: PlanDiff | None = Field(description="null when no pattern is active")
    from_: VehicleStateOut = Field(alias="from", description="where the path starts")
    start: BelievedPosition | None = Field(
        None,
        description="what the start rests on: the last fix (telemetry), the fix run forward "
        "(dead_reckoning) or an assumed start (assumed), with its uncertainty",
    )
    two_way: bool | None = None
    copies: int | None = None
    p_delivered: float | None = None
    link_reach: LinkReach | None = Field(
        description="the path's range from the ME transmitter; null: the transmitter is not "
        "placed (its lat/lon without a datum)"
    )


class DecodeResult(BaseModel):
    ok: Literal[True]
    command: CommandJson
    corrected: int = Field(description="bits the BCH decoder corrected")
    sync_errors: int = Field(description="preamble and delimiter bits wrong")


class AddressedDecodeResult(DecodeResult):
    """A fleet's addressed (108-bit) frame: the decode and whom it is addressed to."""

    address: int = Field(ge=0, le=15, description="the frame's address: 0 all vehicles, 1-15 one")
    vehicle: str | None = Field(
        description='the console\'s vehicle with that address ("all" for address 0); null: '
        "no vehicle of this console has it"
    )
    addressed_to: str = Field(description="whom the frame is for, in words")
