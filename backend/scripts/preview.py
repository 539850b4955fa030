"""Mission scripts, previewed: one path (NED) for the whole script and its timeline.

:func:`preview` expands the steps (:func:`backend.scripts.expand.expand`) and joins their
plans into one path, each step's portion up to when the next step takes over (a repeating
pattern's lap unrolled until then), thinned to :data:`PREVIEW_MAX_POINTS`. The timeline lists
when each step takes effect and when a finite one completes (the completion rule of
:mod:`backend.scripts.completion`). Times and durations are as the vehicle is estimated to fly
the plans (:mod:`backend.scripts.timing`), and every one that rests on that estimate says so.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

from pydantic import BaseModel, Field

from backend.commands.checks import SendViolation
from backend.scripts.checks import PlanCheck, step_violations, step_warning
from backend.scripts.expand import ExpandedStep, describe_trigger, expand
from backend.scripts.labels import at_time, seconds, takes
from backend.scripts.model import MissionScript, Trigger
from backend.scripts.timing import ESTIMATED_TEXT, StepTiming, Timing, flown_timing
from planner import Path, Plan, VehicleState

#: Most points of the preview's combined path (the plans' waypoints are thinned beyond it).
PREVIEW_MAX_POINTS = 20_000
#: Fewest points any one step's portion of the combined path is thinned to.
PREVIEW_MIN_POINTS_PER_STEP = 200


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


class StepViolation(BaseModel):
    """A limit the step breaks, from where the expansion has the vehicle then: ``hard``
    refuses the script; ``soft`` needs the step's ``override``."""

    check: str
    param: str
    kind: Literal["hard", "soft"]
    message: str
    value: float | None
    limit: float | None
    unit: str
    allowed: str


class StepPreview(BaseModel):
    index: int
    pattern: str
    trigger: Trigger
    params: dict[str, float | str]
    requested: dict[str, float | str]
    snaps: list[SnapOut]
    hex: str
    bits: str
    t_start_s: float = Field(description="when it takes effect, s from the run's start")
    start_estimated: bool = Field(
        description="t_start_s follows from an estimated completion (or the operator's go "
        "assumed then); false: the time the script sets"
    )
    t_end_s: float
    duration_s: float = Field(description="estimated: join and pattern (one lap if it repeats)")
    planned_duration_s: float = Field(description="the same by the plan's own clock")
    completion_s: float | None = Field(
        description="estimated: s after the step takes effect when it is complete (at its "
        "path's end and depth; a hover: its time up, at its depth); null: it repeats"
    )
    planned_completion_s: float | None = Field(description="the same by the plan's own clock")
    duration_notes: list[str] = Field(description="why the estimate and the plan's clock differ")
    repeats: bool
    waypoints: int
    start: StartPose
    warnings: list[str]
    violations: list[StepViolation] = Field(
        default_factory=list, description="the send policy's checks of this step"
    )
    override: bool = Field(False, description="the step's override of soft violations")
    timing_text: str = Field("", description="when it takes effect and how long it takes, in words")


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
    t_s: float = Field(description="a time: s from the run's start")
    step: int | None
    text: str
    estimated: bool = Field(description="the time follows from an estimated duration")
    label: str = Field(description="the event as the page shows it: its time, then the text")


class ScriptPreview(BaseModel):
    name: str
    steps: list[StepPreview]
    path: PreviewPath
    duration_s: float = Field(
        description="estimated: to the last step's end (one lap if it repeats)"
    )
    durations_text: str = Field(description="which durations are estimated, and how, in words")
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


def _flown_window(
    path: Path, timing: StepTiming, a_s: float, b_s: float, max_points: int
) -> tuple[list[tuple[float, float, float, float]], bool]:
    """:func:`_window` on the estimate's clock: the points of ``path`` the vehicle is
    estimated to fly from ``a_s`` to ``b_s`` (s after the plan took effect), timed as it flies
    them (a finite path's end held until ``b_s``)."""
    pts, cut = _window(path, timing.to_plan_s(a_s), timing.to_plan_s(b_s), max_points)
    inner = [(timing.from_plan_s(t), x, y, z) for t, x, y, z in pts[1:-1]]
    out = [(a_s, *pts[0][1:]), *(p for p in inner if a_s < p[0] < b_s)]
    if b_s > a_s:
        out.append((b_s, *pts[-1][1:]))
    return out, cut


def _combined_path(
    expanded: list[ExpandedStep], start: VehicleState, current: Plan | None, timing: Timing
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
        pts, cut = _flown_window(current.path, timing(current), a, a + t_first, per)
        thinned |= cut
        add(pts, -a)
    else:
        add([(0.0, start.x_m, start.y_m, start.z_m)], 0.0)
    for s in expanded:
        pts, cut = _flown_window(s.plan.path, s.timing, 0.0, s.t_end_s - s.t_start_s, per)
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


def _event(*, t_s: float, step: int, text: str, estimated: bool) -> TimelineEvent:
    """A timeline event, labelled with its time from the run's start."""
    return TimelineEvent(
        t_s=t_s, step=step, text=text, estimated=estimated, label=f"{at_time(t_s)}: {text}"
    )


def _timeline(expanded: list[ExpandedStep]) -> list[TimelineEvent]:
    events: list[TimelineEvent] = []
    for k, s in enumerate(expanded):
        pattern = s.step.pattern
        how = describe_trigger(s.step.trigger, s.index)
        verb = "starts" if k == 0 else "retasks the vehicle"
        guess = s.start_estimated
        text = f"{pattern} {verb} ({how}{', estimated' if guess else ''})"
        events.append(_event(t_s=s.t_start_s, step=s.index, text=text, estimated=guess))
        done = s.completion_s
        last = k == len(expanded) - 1
        if done is None:
            if last:
                events.append(
                    _event(
                        t_s=s.t_start_s + s.duration_s,
                        step=s.index,
                        text=f"{pattern}: one lap shown (estimated); it repeats until retasked",
                        estimated=True,
                    )
                )
        elif last or s.t_start_s + done <= expanded[k + 1].t_start_s + 1e-6:
            t_done = s.t_start_s + done
            end = s.plan.path
            where = f"({end.xs[-1]:.1f}, {end.ys[-1]:.1f}) m"
            text = (
                f"surface completes: the vehicle is at the surface at {where}"
                if pattern == "surface"
                else f"{pattern} completes: the vehicle holds at {where}, {end.zs[-1]:.1f} m depth"
            )
            planned = s.timing.planned_completion_s
            clock = (
                f", {seconds(planned)} by the plan's own clock"
                if planned is not None and seconds(planned) != seconds(done)
                else ""
            )
            text += f" (estimated: it takes {seconds(done)}{clock})"
            events.append(_event(t_s=t_done, step=s.index, text=text, estimated=True))
    events.sort(key=lambda e: (e.t_s, -1 if e.step is None else e.step))
    return events


def _step_preview(
    s: ExpandedStep, t0_abs_s: float, violations: Sequence[SendViolation]
) -> StepPreview:
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
        start_estimated=s.start_estimated,
        t_end_s=s.t_end_s,
        duration_s=s.duration_s,
        planned_duration_s=s.timing.planned_duration_s,
        completion_s=s.completion_s,
        planned_completion_s=s.timing.planned_completion_s,
        duration_notes=list(s.timing.notes),
        repeats=s.repeats,
        waypoints=len(s.plan.path),
        start=StartPose.model_validate({**s.state.as_dict(), "t_s": s.state.t_s - t0_abs_s}),
        warnings=list(s.warnings),
        violations=[
            StepViolation.model_validate(v.as_json()) for v in violations if v.step == s.index
        ],
        override=s.step.override,
        timing_text=_timing_text(s),
    )


def _timing_text(s: ExpandedStep) -> str:
    """``starts at 30 s from the run's start (estimated), takes 160 s (estimated; 210 s by
    the plan's own clock)``."""
    start = at_time(s.t_start_s) + (" (estimated)" if s.start_estimated else "")
    return f"starts {start}, {takes(s.completion_s, True, s.timing.planned_completion_s)}"


def preview(
    script: MissionScript,
    start: VehicleState,
    current: Plan | None = None,
    check: PlanCheck | None = None,
    timing: Timing | None = None,
) -> ScriptPreview:
    """Expand ``script`` from ``start`` (see :func:`expand`) into the operator's preview.

    Each step's values are the decoded frame's (snapped); its path starts where the previous
    step has the vehicle when it triggers. ``duration_s`` runs to the end of the last plan
    (one lap when it repeats, ``path.repeats``). With ``check`` (the send policy's checks),
    every step lists its violations, and the warnings name them. ``timing``: how the vehicle
    flies a plan (:func:`backend.scripts.timing.flown_timing` of its profile; default: of
    unknown figures); every duration and the times that follow from one are estimated.

    Raises:
        ScriptError: the planner cannot expand a step.
    """
    timing = timing if timing is not None else flown_timing(None)
    expanded = expand(script, start, current, timing)
    last = expanded[-1]
    warnings = [f"step {s.index + 1}: {w}" for s in expanded for w in s.warnings]
    found = step_violations(expanded, check) if check is not None else []
    warnings += [step_warning(v) for v in found]
    return ScriptPreview(
        name=script.name,
        steps=[_step_preview(s, start.t_s, found) for s in expanded],
        path=_combined_path(expanded, start, current, timing),
        duration_s=last.t_start_s + last.duration_s,
        durations_text=ESTIMATED_TEXT,
        timeline=_timeline(expanded),
        warnings=warnings,
    )
