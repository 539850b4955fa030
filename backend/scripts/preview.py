"""Mission scripts, previewed: one path (NED) for the whole script and its timeline.

:func:`preview` expands the steps (:func:`backend.scripts.expand.expand`) and joins their
plans into one path, each step's portion up to when the next step takes over (a repeating
pattern's lap unrolled until then), thinned to :data:`PREVIEW_MAX_POINTS`. The timeline lists
when each step takes effect and when a finite one completes (the completion rule of
:mod:`backend.scripts.completion`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

from pydantic import BaseModel, Field

from backend.commands.checks import SendViolation
from backend.scripts.checks import PlanCheck, step_violations, step_warning
from backend.scripts.expand import ExpandedStep, describe_trigger, expand
from backend.scripts.labels import at_time, takes
from backend.scripts.model import MissionScript, Trigger
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
    t_start_s: float
    t_end_s: float
    duration_s: float
    completion_s: float | None = Field(
        description="s after the step takes effect when it is complete (the end of its "
        "path; a hover: its duration); null: it repeats until retasked"
    )
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
    label: str = Field(description="the event as the page shows it: its time, then the text")


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


def _event(*, t_s: float, step: int, text: str) -> TimelineEvent:
    """A timeline event, labelled with its time from the run's start."""
    return TimelineEvent(t_s=t_s, step=step, text=text, label=f"{at_time(t_s)}: {text}")


def _timeline(expanded: list[ExpandedStep]) -> list[TimelineEvent]:
    events: list[TimelineEvent] = []
    for k, s in enumerate(expanded):
        pattern = s.step.pattern
        how = describe_trigger(s.step.trigger, s.index)
        verb = "starts" if k == 0 else "retasks the vehicle"
        events.append(_event(t_s=s.t_start_s, step=s.index, text=f"{pattern} {verb} ({how})"))
        done = s.completion_s
        last = k == len(expanded) - 1
        if done is None:
            if last:
                events.append(
                    _event(
                        t_s=s.t_start_s + s.duration_s,
                        step=s.index,
                        text=f"{pattern}: one lap shown; it repeats until retasked",
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
            events.append(_event(t_s=t_done, step=s.index, text=text))
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
        t_end_s=s.t_end_s,
        duration_s=s.duration_s,
        completion_s=s.completion_s,
        repeats=s.repeats,
        waypoints=len(s.plan.path),
        start=StartPose.model_validate({**s.state.as_dict(), "t_s": s.state.t_s - t0_abs_s}),
        warnings=list(s.warnings),
        violations=[
            StepViolation.model_validate(v.as_json()) for v in violations if v.step == s.index
        ],
        override=s.step.override,
        timing_text=f"starts {at_time(s.t_start_s)}, {takes(s.completion_s)}",
    )


def preview(
    script: MissionScript,
    start: VehicleState,
    current: Plan | None = None,
    check: PlanCheck | None = None,
) -> ScriptPreview:
    """Expand ``script`` from ``start`` (see :func:`expand`) into the operator's preview.

    Each step's values are the decoded frame's (snapped); its path starts where the previous
    step has the vehicle when it triggers. ``duration_s`` runs to the end of the last plan
    (one lap when it repeats, ``path.repeats``). With ``check`` (the send policy's checks),
    every step lists its violations, and the warnings name them.

    Raises:
        ScriptError: the planner cannot expand a step.
    """
    expanded = expand(script, start, current)
    last = expanded[-1]
    warnings = [f"step {s.index + 1}: {w}" for s in expanded for w in s.warnings]
    found = step_violations(expanded, check) if check is not None else []
    warnings += [step_warning(v) for v in found]
    return ScriptPreview(
        name=script.name,
        steps=[_step_preview(s, start.t_s, found) for s in expanded],
        path=_combined_path(expanded, start, current),
        duration_s=last.t_start_s + last.duration_s,
        timeline=_timeline(expanded),
        warnings=warnings,
    )
