"""Mission scripts: a list of commands with triggers, previewed, exported and run.

A mission script is the operator's plan for a dive, written ahead (``docs/api.md`` has the
endpoints)::

    {"format": "nemesys-mission-script", "version": 1, "name": "pod patrol",
     "steps": [
       {"pattern": "square", "params": {"speed": 0.18, "depth": 2, "side_span": 8,
                                        "direction": "cw"}, "trigger": {"kind": "at", "t_s": 0}},
       {"pattern": "circle", "params": {"speed": 0.18, "depth": 3, "radius": 5,
                                        "direction": "cw"}, "trigger": {"kind": "at", "t_s": 200}}
     ]}

Triggers:

* ``at``: ``t_s`` seconds after the run starts (0 = immediately). ``at`` times never decrease
  along the script.
* ``after_previous``: when the vehicle reports the previous (finite) pattern complete. A
  repeating pattern (square, circle) never completes, so a step after one never triggers.
* ``operator``: when the operator says go.

The first step is ``at`` or ``operator``. Every step's pattern and parameters are checked by
encoding them (:func:`codec.encode_frame`), so a script that validates can be sent as is;
errors name their place, e.g. ``steps.1.params.radius``.

This module is pure logic (no I/O, no web framework):

* :class:`MissionScript` (pydantic v2 models) validates the JSON;
* :func:`preview` expands the steps in order as the vehicle would fly them, each from where
  the previous one has taken the vehicle when it triggers (:func:`expand` gives the plans);
* :func:`export_onboard` / :func:`onboard_csv` give the onboard script of the paper's field
  trials: the timed frames the vehicle injects itself;
* :class:`ScriptRunner` is the state machine the console drives during a run.

Times in the preview and the export are seconds from the start of the run; the planner's
states use the vehicle's mission clock (``start.t_s`` + script time).
"""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import dataclass, replace
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator
from pydantic_core import InitErrorDetails, PydanticCustomError, ValidationError

from codec import DecodeError, Encoded, EncodeError, decode_frame, encode_frame
from planner import Path, Plan, PlanError, VehicleState, plan

SCRIPT_FORMAT = "nemesys-mission-script"
ONBOARD_FORMAT = "nemesys-onboard-script"
#: Latest "at" time a script may use (s from the start of the run): a day, beyond any dive.
MAX_SCRIPT_TIME_S = 86_400.0
#: Most points of the preview's combined path (the plans' waypoints are thinned beyond it).
PREVIEW_MAX_POINTS = 20_000
#: Fewest points any one step's portion of the combined path is thinned to.
PREVIEW_MIN_POINTS_PER_STEP = 200
#: Vehicle modes that mean "the previous pattern is complete" for ``after_previous``.
COMPLETION_MODES = frozenset({"holding", "surfaced"})

TriggerKind = Literal["at", "after_previous", "operator"]
RunMode = Literal["auto", "step"]
StepState = Literal["pending", "sent", "acknowledged", "failed"]
WaitingFor = Literal["time", "completion", "operator", "acknowledgement"]
Loc = tuple[int | str, ...]


# --- the script -------------------------------------------------------------------------


def _line_error(
    loc: Loc, kind: str, message: str, value: object, **ctx: object
) -> InitErrorDetails:
    """One pydantic error at ``loc`` (``{`` and ``}`` in ``message`` are taken literally)."""
    text = message.replace("{", "{{").replace("}", "}}")
    error: InitErrorDetails = {
        "type": PydanticCustomError(kind, text, ctx or None),
        "loc": loc,
        "input": value,
    }
    return error


class Trigger(BaseModel):
    """When a step is sent: ``at`` ``t_s`` seconds into the run, ``after_previous`` (the
    previous pattern completed) or ``operator`` (the operator's go)."""

    model_config = ConfigDict(extra="forbid")

    kind: TriggerKind
    t_s: float | None = Field(
        default=None, ge=0.0, le=MAX_SCRIPT_TIME_S, allow_inf_nan=False, strict=True
    )

    @model_validator(mode="after")
    def _time_only_for_at(self) -> Trigger:
        if self.kind == "at" and self.t_s is None:
            raise ValidationError.from_exception_data(
                "Trigger",
                [
                    _line_error(
                        ("t_s",),
                        "missing",
                        "an 'at' trigger needs t_s: seconds from the start of the run "
                        "(0 = immediately)",
                        None,
                    )
                ],
            )
        if self.kind != "at" and self.t_s is not None:
            raise ValidationError.from_exception_data(
                "Trigger",
                [
                    _line_error(
                        ("t_s",),
                        "unexpected_time",
                        f"an '{self.kind}' trigger takes no t_s (only 'at' triggers have a time)",
                        self.t_s,
                    )
                ],
            )
        return self


class ScriptStep(BaseModel):
    """One command of the script: a pattern with its parameters, and its trigger."""

    model_config = ConfigDict(extra="forbid")

    pattern: str
    params: dict[str, float | str] = Field(default_factory=dict)
    trigger: Trigger

    @field_validator("params", mode="before")
    @classmethod
    def _no_booleans(cls, value: object) -> object:
        # pydantic would read true/false as 1.0/0.0; a boolean is never a parameter value
        if isinstance(value, dict):
            for key, v in value.items():
                if isinstance(v, bool):
                    raise ValidationError.from_exception_data(
                        "ScriptStep",
                        [
                            _line_error(
                                (str(key),),
                                "float_type",
                                f"{key} must be a number or a choice, not {str(v).lower()}",
                                v,
                            )
                        ],
                    )
        return value

    @model_validator(mode="after")
    def _encodes(self) -> ScriptStep:
        """The step must encode: the codec names the parameter at fault."""
        try:
            encode_frame(self.pattern, self.params)
        except EncodeError as e:
            if e.field is None:
                error = _line_error(("pattern",), "unknown_pattern", str(e), self.pattern)
            else:
                value = self.params.get(e.field)
                error = _line_error(("params", e.field), "invalid_param", str(e), value)
            raise ValidationError.from_exception_data("ScriptStep", [error]) from e
        return self


class MissionScript(BaseModel):
    """A mission script (``format`` ``nemesys-mission-script``, ``version`` 1)."""

    model_config = ConfigDict(extra="forbid")

    format: Literal["nemesys-mission-script"]
    version: Literal[1]
    name: str = Field(min_length=1, max_length=80)
    steps: list[ScriptStep] = Field(min_length=1, max_length=100)

    @model_validator(mode="after")
    def _check_steps(self) -> MissionScript:
        errors: list[InitErrorDetails] = []
        first = self.steps[0].trigger
        if first.kind == "after_previous":
            errors.append(
                _line_error(
                    ("steps", 0, "trigger", "kind"),
                    "first_trigger",
                    "the first step has no previous one: use 'at' (t_s 0 = immediately) or "
                    "'operator'",
                    first.kind,
                )
            )
        last_at: tuple[int, float] | None = None
        for i, step in enumerate(self.steps):
            t = step.trigger.t_s
            if step.trigger.kind == "at" and t is not None:
                if last_at is not None and t < last_at[1]:
                    errors.append(
                        _line_error(
                            ("steps", i, "trigger", "t_s"),
                            "time_order",
                            f"'at' times must not decrease along the script: {t:g} s is before "
                            f"step {last_at[0]}'s {last_at[1]:g} s",
                            t,
                        )
                    )
                last_at = (i, t)
        if errors:
            raise ValidationError.from_exception_data("MissionScript", errors)
        return self


class ScriptError(ValueError):
    """A valid script that cannot be expanded (the planner refused a step).

    Attributes:
        loc: where, as in a validation error: ``("steps", 2, "params", "radius")``.
        message: why (the planner's message, naming the parameter).
    """

    def __init__(self, message: str, loc: Loc) -> None:
        super().__init__(f"{'.'.join(map(str, loc))}: {message}")
        self.message = message
        self.loc = loc

    def errors(self) -> list[dict[str, Any]]:
        """The error in FastAPI's 422 ``detail`` shape (without the ``body`` prefix)."""
        return [{"loc": list(self.loc), "msg": self.message, "type": "plan_error"}]


# --- expansion --------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class ExpandedStep:
    """One step as the vehicle would fly it.

    Attributes:
        index: the step's index in the script.
        step: the script's step.
        encoded: the frame (``encoded.snaps`` says what was snapped).
        plan: the plan of the decoded command, from ``state``, with the previous step's plan
            (or the ``current`` plan for step 0) in force.
        state: the vehicle's state when the step takes effect (mission clock ``t_s``).
        t_start_s: when it takes effect (s from the start of the run).
        t_end_s: when the next step takes over, or for the last step when its plan ends
            (one lap for a repeating pattern).
        warnings: what the operator should know about this step's timing.
    """

    index: int
    step: ScriptStep
    encoded: Encoded
    plan: Plan
    state: VehicleState
    t_start_s: float
    t_end_s: float
    warnings: tuple[str, ...]

    @property
    def repeats(self) -> bool:
        return self.plan.path.loop_start is not None

    @property
    def duration_s(self) -> float:
        """The plan's own duration: join and pattern (one lap for a repeating pattern)."""
        return self.plan.path.duration_s


def _segment_at(path: Path, t_rel_s: float) -> int | None:
    """Index of the segment the path is on at ``t_rel_s`` (wrapping a repeating lap)."""
    times = path.times
    n = len(times)
    if n < 2:
        return None
    t = t_rel_s
    if t > times[-1] and path.loop_start is not None:
        t_loop = times[path.loop_start]
        lap = times[-1] - t_loop
        t = t_loop + math.fmod(t - t_loop, lap) if lap > 0 else t_loop
    return min(max(bisect_right(times, t) - 1, 0), n - 2)


def _state_at(p: Plan, t_rel_s: float, t_abs_s: float) -> VehicleState:
    """Where ``p`` has the vehicle ``t_rel_s`` after it took effect, at mission time
    ``t_abs_s``."""
    path = p.path
    sp = path.sample(t_rel_s)
    heading = sp.course_deg
    if sp.speed_mps == 0.0 and path.hold_heading_deg is not None:
        heading = path.hold_heading_deg
    return VehicleState(
        sp.x_m, sp.y_m, sp.z_m, heading, sp.speed_mps, t_abs_s, _segment_at(path, t_rel_s)
    )


def _describe_trigger(trigger: Trigger, index: int) -> str:
    if trigger.kind == "at":
        return f"at {trigger.t_s:g} s"
    if trigger.kind == "after_previous":
        return f"after step {index - 1} completes"
    return "on the operator's go"


def expand(
    script: MissionScript, start: VehicleState, current: Plan | None = None
) -> list[ExpandedStep]:
    """Plan every step of ``script`` in order, as the vehicle would fly them.

    Args:
        script: a validated script.
        start: the vehicle when the run starts (its ``t_s`` is the mission clock then).
        current: the plan the vehicle is running at the start, if any: it keeps the mission
            anchor (orbits stay around the same point) and is flown until step 0 triggers.

    Raises:
        ScriptError: the planner cannot expand a step (e.g. more waypoints than the vehicle
            holds); ``loc`` names the step and, when known, the parameter.
        EncodeError: only for a script built without validation (``model_construct``).
    """
    out: list[ExpandedStep] = []
    t0_abs = start.t_s
    in_force = current
    for i, step in enumerate(script.steps):
        encoded = encode_frame(step.pattern, step.params)
        try:
            command = decode_frame(encoded.frame.bits).command
        except DecodeError as e:  # pragma: no cover - the codec round-trips every command
            raise ScriptError(f"the frame does not decode: {e}", ("steps", i)) from e
        warnings: list[str] = []
        trigger = step.trigger
        prev = out[-1] if out else None
        if prev is None:
            t_start = trigger.t_s if trigger.kind == "at" and trigger.t_s is not None else 0.0
            if trigger.kind == "operator":
                warnings.append("waits for the operator's go: assumed at the start of the run")
            if current is not None:
                state = _state_at(current, t0_abs + t_start - current.t0_s, t0_abs + t_start)
            elif t_start > 0.0:
                state = VehicleState(
                    start.x_m, start.y_m, start.z_m, start.heading_deg, 0.0, t0_abs + t_start
                )
            else:
                state = start
        else:
            prev_end = prev.t_start_s + prev.duration_s
            if trigger.kind == "at" and trigger.t_s is not None:
                t_start = trigger.t_s
                if t_start < prev.t_start_s:
                    warnings.append(
                        f"at {t_start:g} s is before step {i - 1} is expected to start "
                        f"({prev.t_start_s:.1f} s): it is sent as soon as step {i - 1} is "
                        "acknowledged"
                    )
                    t_start = prev.t_start_s
            else:
                t_start = prev_end
                if prev.repeats:
                    what = (
                        "can never trigger"
                        if trigger.kind == "after_previous"
                        else "has no completion to wait for"
                    )
                    warnings.append(
                        f"step {i - 1} ({prev.step.pattern}) repeats until retasked, so this "
                        f"step {what}: the preview assumes one lap ({prev.duration_s:.1f} s)"
                    )
                if trigger.kind == "operator":
                    warnings.append(
                        "waits for the operator's go: the time is unknown; the preview assumes "
                        f"step {i - 1} completes first ({t_start:.1f} s)"
                    )
            if t_start == prev.t_start_s:
                warnings.append(
                    f"takes effect at the same time as step {i - 1}, which is replaced at once"
                )
            # after_previous / operator: exactly the end of the previous plan
            t_rel = prev.duration_s if trigger.kind != "at" else t_start - prev.t_start_s
            state = _state_at(prev.plan, t_rel, t0_abs + t_start)
        try:
            p = plan(command, state, in_force)
        except PlanError as e:
            loc: Loc = ("steps", i, "params", e.field) if e.field else ("steps", i)
            raise ScriptError(str(e), loc) from e
        if prev is not None:
            out[-1] = replace(prev, t_end_s=t_start)
        out.append(
            ExpandedStep(
                i, step, encoded, p, state, t_start, t_start + p.path.duration_s, tuple(warnings)
            )
        )
        in_force = p
    return out


# --- preview ----------------------------------------------------------------------------


class SnapOut(BaseModel):
    field: str
    unit: str
    requested: float | str
    sent: float | str
    changed: bool


class StartPose(BaseModel):
    """The vehicle when a step takes effect (NED m, deg, m/s; ``t_s`` from the run start)."""

    x_m: float
    y_m: float
    z_m: float
    heading_deg: float
    speed_mps: float
    t_s: float


class StepPreview(BaseModel):
    index: int
    pattern: str
    trigger: Trigger
    params: dict[str, float | str]
    requested: dict[str, float | str]
    snaps: list[SnapOut]
    hex: str
    bits: str
    t_start_s: float
    t_end_s: float
    duration_s: float
    repeats: bool
    waypoints: int
    start: StartPose
    warnings: list[str]


class PreviewPath(BaseModel):
    """The whole script's path (NED m; ``t_s`` from the run start). ``step_start[k]`` is the
    index of the point where step ``k`` takes effect (shared with the previous step's
    portion). ``thinned``: waypoints were left out to keep the path under
    :data:`PREVIEW_MAX_POINTS`."""

    x_m: list[float]
    y_m: list[float]
    z_m: list[float]
    t_s: list[float]
    step_start: list[int]
    repeats: bool
    thinned: bool


class TimelineEvent(BaseModel):
    t_s: float
    step: int | None
    text: str


class ScriptPreview(BaseModel):
    name: str
    steps: list[StepPreview]
    path: PreviewPath
    duration_s: float
    timeline: list[TimelineEvent]
    warnings: list[str]


def _virtual_time(path: Path, j: int) -> float:
    """Time of virtual waypoint ``j``: the waypoints, then the repeated lap again and again
    (``j >= len(path)`` only for a repeating path)."""
    n = len(path.times)
    if j < n:
        return path.times[j]
    ls = path.loop_start
    assert ls is not None
    per = n - 1 - ls
    k, r = divmod(j - n, per)
    lap = path.times[-1] - path.times[ls]
    return path.times[ls + 1 + r] + (k + 1) * lap


def _virtual_point(path: Path, j: int) -> tuple[float, float, float, float]:
    n = len(path.times)
    if j < n:
        i = j
    else:
        ls = path.loop_start
        assert ls is not None
        i = ls + 1 + (j - n) % (n - 1 - ls)
    return _virtual_time(path, j), path.xs[i], path.ys[i], path.zs[i]


def _first_after(path: Path, t_s: float, hi: int) -> int:
    """Smallest virtual index in ``[0, hi]`` whose time is above ``t_s`` (``hi`` if none)."""
    lo = 0
    while lo < hi:
        mid = (lo + hi) // 2
        if _virtual_time(path, mid) > t_s:
            hi = mid
        else:
            lo = mid + 1
    return lo


def _window(
    path: Path, a_s: float, b_s: float, max_points: int
) -> tuple[list[tuple[float, float, float, float]], bool]:
    """Points ``(t, x, y, z)`` of ``path`` from ``a_s`` to ``b_s`` (plan-relative, both ends
    sampled), repeating the lap of a repeating path; thinned to about ``max_points``."""
    first = path.sample(a_s)
    pts = [(a_s, first.x_m, first.y_m, first.z_m)]
    if b_s <= a_s:
        return pts, False
    n = len(path.times)
    ls = path.loop_start
    lap = path.times[-1] - path.times[ls] if ls is not None else 0.0
    if ls is not None and lap > 0 and ls < n - 1 and b_s > path.times[-1]:
        laps = math.ceil((b_s - path.times[-1]) / lap) + 1
        end = n + laps * (n - 1 - ls)
    else:
        end = n
    ja = _first_after(path, a_s, end)
    jb = _first_after(path, b_s - 1e-9, end)  # inner points strictly before b_s
    count = max(0, jb - ja)
    stride = max(1, math.ceil(count / max(1, max_points - 2)))
    pts.extend(_virtual_point(path, j) for j in range(ja, jb, stride))
    last = path.sample(b_s)
    pts.append((b_s, last.x_m, last.y_m, last.z_m))
    return pts, stride > 1


def _combined_path(
    expanded: list[ExpandedStep], start: VehicleState, current: Plan | None
) -> PreviewPath:
    windows = len(expanded) + 1
    per = max(PREVIEW_MIN_POINTS_PER_STEP, PREVIEW_MAX_POINTS // windows)
    xs: list[float] = []
    ys: list[float] = []
    zs: list[float] = []
    ts: list[float] = []
    step_start: list[int] = []
    thinned = False

    def add(points: list[tuple[float, float, float, float]], offset_s: float) -> bool:
        """Append ``points``; True when the first one was merged with the last kept (the
        shared point at a retask)."""
        merged = False
        for k, (t, x, y, z) in enumerate(points):
            t_run = round(offset_s + t, 3)
            if ts and t_run <= ts[-1]:
                merged |= k == 0
                continue
            ts.append(t_run)
            xs.append(round(x, 3))
            ys.append(round(y, 3))
            zs.append(round(z, 3))
        return merged

    # before step 0 takes effect: the current plan, or the vehicle waiting at its start
    t_first = expanded[0].t_start_s
    if current is not None:
        a = start.t_s - current.t0_s
        pts, cut = _window(current.path, a, a + t_first, per)
        thinned |= cut
        add(pts, -a)
    else:
        add([(0.0, start.x_m, start.y_m, start.z_m)], 0.0)
    for s in expanded:
        pts, cut = _window(s.plan.path, 0.0, s.t_end_s - s.t_start_s, per)
        thinned |= cut
        before = len(ts)
        step_start.append(before - 1 if add(pts, s.t_start_s) else before)
    return PreviewPath(
        x_m=xs,
        y_m=ys,
        z_m=zs,
        t_s=ts,
        step_start=step_start,
        repeats=expanded[-1].repeats,
        thinned=thinned,
    )


def _timeline(expanded: list[ExpandedStep]) -> list[TimelineEvent]:
    events: list[TimelineEvent] = []
    for k, s in enumerate(expanded):
        pattern = s.step.pattern
        how = _describe_trigger(s.step.trigger, s.index)
        verb = "starts" if k == 0 else "retasks the vehicle"
        events.append(
            TimelineEvent(t_s=s.t_start_s, step=s.index, text=f"{pattern} {verb} ({how})")
        )
        t_done = s.t_start_s + s.duration_s
        last = k == len(expanded) - 1
        if s.repeats:
            if last:
                events.append(
                    TimelineEvent(
                        t_s=t_done,
                        step=s.index,
                        text=f"{pattern}: one lap shown; it repeats until retasked",
                    )
                )
        elif last or t_done <= expanded[k + 1].t_start_s + 1e-6:
            end = s.plan.path
            where = f"({end.xs[-1]:.1f}, {end.ys[-1]:.1f}) m"
            text = (
                f"surface completes: the vehicle is at the surface at {where}"
                if pattern == "surface"
                else f"{pattern} completes: the vehicle holds at {where}, {end.zs[-1]:.1f} m depth"
            )
            events.append(TimelineEvent(t_s=t_done, step=s.index, text=text))
    events.sort(key=lambda e: (e.t_s, -1 if e.step is None else e.step))
    return events


def _step_preview(s: ExpandedStep, t0_abs_s: float) -> StepPreview:
    enc = s.encoded
    return StepPreview(
        index=s.index,
        pattern=s.step.pattern,
        trigger=s.step.trigger,
        params=dict(s.plan.command.params),
        requested=dict(s.step.params),
        snaps=[
            SnapOut(
                field=n.field, unit=n.unit, requested=n.requested, sent=n.sent, changed=n.changed
            )
            for n in enc.snaps
        ],
        hex=enc.frame.hex,
        bits=enc.frame.bits,
        t_start_s=s.t_start_s,
        t_end_s=s.t_end_s,
        duration_s=s.duration_s,
        repeats=s.repeats,
        waypoints=len(s.plan.path),
        start=StartPose.model_validate({**s.state.as_dict(), "t_s": s.state.t_s - t0_abs_s}),
        warnings=list(s.warnings),
    )


def preview(
    script: MissionScript, start: VehicleState, current: Plan | None = None
) -> ScriptPreview:
    """Expand ``script`` from ``start`` (see :func:`expand`) into the operator's preview.

    Each step's values are the decoded frame's (snapped); its path starts where the previous
    step has the vehicle when it triggers. ``duration_s`` runs to the end of the last plan
    (one lap when it repeats, ``path.repeats``).

    Raises:
        ScriptError: the planner cannot expand a step.
    """
    expanded = expand(script, start, current)
    last = expanded[-1]
    warnings = [f"step {s.index}: {w}" for s in expanded for w in s.warnings]
    return ScriptPreview(
        name=script.name,
        steps=[_step_preview(s, start.t_s) for s in expanded],
        path=_combined_path(expanded, start, current),
        duration_s=last.t_start_s + last.duration_s,
        timeline=_timeline(expanded),
        warnings=warnings,
    )


# --- onboard export ---------------------------------------------------------------------


def _onboard(script: MissionScript, expanded: list[ExpandedStep]) -> dict[str, Any]:
    frames: list[dict[str, Any]] = []
    for s in expanded:
        frame: dict[str, Any] = {
            "t_s": round(s.t_start_s, 3),
            "pattern": s.step.pattern,
            "hex": s.encoded.frame.hex,
            "bits": s.encoded.frame.bits,
        }
        kind = s.step.trigger.kind
        notes: list[str] = []
        if kind == "operator":
            notes.append("operator go in the script: the vehicle sends it at the expected time")
        elif kind == "after_previous":
            notes.append(f"after step {s.index - 1} completes: its expected completion time")
        notes.extend(s.warnings)
        if notes:
            frame["note"] = "; ".join(notes)
        frames.append(frame)
    return {"format": ONBOARD_FORMAT, "version": 1, "name": script.name, "frames": frames}


def export_onboard(
    script: MissionScript, start: VehicleState, current: Plan | None = None
) -> dict[str, Any]:
    """The onboard script: the timed frames the vehicle injects itself (the field trials').

    ``{"format": "nemesys-onboard-script", "version": 1, "name", "frames": [{"t_s", "pattern",
    "hex", "bits", "note"?}]}``; times are the preview's trigger times (s from the start), so
    ``operator`` and ``after_previous`` steps become their expected times, with a ``note``.

    Raises:
        ScriptError: the planner cannot expand a step.
    """
    return _onboard(script, expand(script, start, current))


def onboard_csv(script: MissionScript, start: VehicleState, current: Plan | None = None) -> str:
    """The onboard script as CSV: ``t_s,pattern,hex``, one frame per line."""
    rows = ["t_s,pattern,hex"]
    for f in export_onboard(script, start, current)["frames"]:
        rows.append(f"{f['t_s']:.3f},{f['pattern']},{f['hex']}")
    return "\n".join(rows) + "\n"


# --- the run ----------------------------------------------------------------------------


class ScriptRunError(RuntimeError):
    """A runner call that does not fit its state (e.g. ``go()`` with nothing proposed)."""


class ScriptRunner:
    """The state machine of a script run; no I/O, no clock of its own.

    The console calls :meth:`poll` with the dive time and the vehicle's reported mode and
    pattern (telemetry), sends the steps it returns (or the one :meth:`go` releases) and
    reports back with :meth:`mark_sent`, :meth:`mark_acknowledged` or :meth:`mark_failed`.

    Rules:

    * a step is due only after the previous one is acknowledged, and is handed out once
      (by :meth:`poll` or :meth:`go`), never twice;
    * ``mode="auto"``: ``at`` steps are due when ``now_s - start_s >= t_s`` (``start_s``:
      the constructor's, else the first poll's ``now_s``); ``after_previous`` steps when the
      vehicle, after the previous step was acknowledged, has been seen running that pattern
      (a mode outside :data:`COMPLETION_MODES`) and then reports it complete (``holding``, or
      ``surfaced`` after a surface); ``operator`` steps are proposed and wait for :meth:`go`;
    * ``mode="step"``: every step is proposed and waits for :meth:`go`;
    * :meth:`mark_failed` and :meth:`stop` end the run; it also ends when every step is
      acknowledged.

    A handed-out step shows as ``sent`` (``transmitted`` false until :meth:`mark_sent`).
    """

    def __init__(
        self, script: MissionScript, mode: RunMode = "auto", *, start_s: float | None = None
    ) -> None:
        if mode not in ("auto", "step"):
            raise ValueError(f"run mode must be 'auto' or 'step', got {mode!r}")
        self.script = script
        self.mode: RunMode = mode
        self.start_s = start_s
        self.now_s: float | None = None
        self.running = True
        self.outcome: Literal["running", "completed", "stopped", "failed"] = "running"
        self.reason: str | None = None
        n = len(script.steps)
        self._states: list[StepState] = ["pending"] * n
        self._transmitted = [False] * n
        self._next = 0  # the first step not yet handed out
        self._seen_running = False  # the previous step's pattern seen in progress after its ack

    # --- queries --------------------------------------------------------------------------

    @property
    def next_index(self) -> int | None:
        """The next step to hand out, or ``None`` when every step has been."""
        return self._next if self._next < len(self.script.steps) else None

    def step_state(self, i: int) -> StepState:
        """Step ``i``'s state: pending, sent, acknowledged or failed."""
        return self._states[i]

    def _previous_acknowledged(self) -> bool:
        return self._next == 0 or self._states[self._next - 1] == "acknowledged"

    def waiting_for(self) -> WaitingFor | None:
        """What the next step waits for, or ``None`` when the run is over."""
        i = self.next_index
        if not self.running:
            return None
        if not self._previous_acknowledged():
            return "acknowledgement"
        if i is None:  # pragma: no cover - the run ends when the last step is acknowledged
            return None
        kind = self.script.steps[i].trigger.kind
        if self.mode == "step" or kind == "operator":
            return "operator"
        return "time" if kind == "at" else "completion"

    def proposed(self) -> int | None:
        """The step awaiting the operator's go, if any (step mode: every step; auto mode:
        ``operator`` steps), once the previous one is acknowledged."""
        return self.next_index if self.waiting_for() == "operator" else None

    def due_s(self) -> float | None:
        """For an ``at`` step waiting in auto mode: when it is due (dive time), if known."""
        i = self.next_index
        if i is None or self.mode != "auto" or self.start_s is None:
            return None
        t = self.script.steps[i].trigger
        return self.start_s + t.t_s if t.kind == "at" and t.t_s is not None else None

    def state(self) -> dict[str, Any]:
        """The run as JSON: ``{running, mode, outcome, step, next, waiting_for, due_s,
        elapsed_s, steps: [{index, pattern, state, transmitted}], reason}``."""
        proposed = self.proposed()
        nxt: dict[str, Any] | None = None
        if proposed is not None:
            s = self.script.steps[proposed]
            nxt = {
                "index": proposed,
                "pattern": s.pattern,
                "params": dict(s.params),
                "trigger": s.trigger.model_dump(),
            }
        elapsed = (
            self.now_s - self.start_s
            if self.now_s is not None and self.start_s is not None
            else None
        )
        return {
            "running": self.running,
            "mode": self.mode,
            "outcome": self.outcome,
            "name": self.script.name,
            "step": self.next_index,
            "next": nxt,
            "waiting_for": self.waiting_for(),
            "due_s": self.due_s() if self.running else None,
            "elapsed_s": elapsed,
            "steps": [
                {
                    "index": i,
                    "pattern": s.pattern,
                    "trigger": s.trigger.kind,
                    "state": self._states[i],
                    "transmitted": self._transmitted[i],
                }
                for i, s in enumerate(self.script.steps)
            ],
            "reason": self.reason,
        }

    # --- driving --------------------------------------------------------------------------

    def poll(
        self, now_s: float, vehicle_mode: str, vehicle_pattern: str | None = None
    ) -> list[int]:
        """The steps to send now (auto mode; at most one, as each waits for the previous
        acknowledgement). ``now_s``: dive time (s); ``vehicle_mode``/``vehicle_pattern``: the
        vehicle's reported mode (``running``, ``holding``, ...) and active pattern (``None``
        when unknown)."""
        if self.start_s is None:
            self.start_s = now_s
        self.now_s = now_s
        i = self.next_index
        if not self.running or i is None or not self._previous_acknowledged():
            return []
        if i > 0:
            prev = self.script.steps[i - 1].pattern
            ours = vehicle_pattern is None or vehicle_pattern == prev
            if ours and vehicle_mode not in COMPLETION_MODES:
                self._seen_running = True
            complete = ours and self._seen_running and vehicle_mode in COMPLETION_MODES
        else:
            complete = False
        if self.mode != "auto":
            return []
        trigger = self.script.steps[i].trigger
        if trigger.kind == "at":
            due = trigger.t_s is not None and now_s - self.start_s >= trigger.t_s - 1e-9
        else:
            due = trigger.kind == "after_previous" and complete
        if not due:
            return []
        self._hand_out(i)
        return [i]

    def go(self) -> int:
        """The operator confirms the proposed step: returns its index, to send.

        Raises:
            ScriptRunError: nothing is proposed (the run is over, the previous step is not
                acknowledged yet, or in auto mode the next step is not an ``operator`` one).
        """
        i = self.proposed()
        if i is None:
            why = self.waiting_for()
            raise ScriptRunError(
                "no step awaits the operator"
                + (f": the run is waiting for {why}" if why else ": the run is over")
            )
        self._hand_out(i)
        return i

    def _hand_out(self, i: int) -> None:
        self._states[i] = "sent"
        self._next = i + 1
        self._seen_running = False

    def _check_handed_out(self, i: int, what: str) -> None:
        if not 0 <= i < len(self._states):
            raise ScriptRunError(f"{what}: the script has no step {i}")
        if self._states[i] == "pending":
            raise ScriptRunError(f"{what}: step {i} has not been handed out for sending")

    def mark_sent(self, i: int) -> None:
        """Step ``i`` left the station."""
        self._check_handed_out(i, "mark_sent")
        self._transmitted[i] = True

    def mark_acknowledged(self, i: int) -> None:
        """The vehicle accepted step ``i``; the run ends when it is the last step."""
        self._check_handed_out(i, "mark_acknowledged")
        if self._states[i] in ("failed", "acknowledged"):
            return
        self._states[i] = "acknowledged"
        self._transmitted[i] = True
        if i == self._next - 1:
            self._seen_running = False
        if self.running and all(s == "acknowledged" for s in self._states):
            self.running = False
            self.outcome = "completed"

    def mark_failed(self, i: int, reason: str) -> None:
        """Step ``i`` could not be delivered (failed, rejected, timed out): the run stops."""
        self._check_handed_out(i, "mark_failed")
        self._states[i] = "failed"
        if self.running:
            self.running = False
            self.outcome = "failed"
            self.reason = f"step {i} ({self.script.steps[i].pattern}) failed: {reason}"

    def stop(self, reason: str = "stopped by the operator") -> None:
        """End the run; nothing more is handed out."""
        if self.running:
            self.running = False
            self.outcome = "stopped"
            self.reason = reason
