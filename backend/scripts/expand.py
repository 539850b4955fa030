"""Mission scripts, expanded: every step planned in order, as the vehicle would fly it.

Each step starts where the previous one has taken the vehicle when it triggers. An
``after_previous`` step takes effect at the previous step's start plus its completion time
(:mod:`backend.scripts.completion`), as the vehicle is estimated to fly it
(:mod:`backend.scripts.timing`: the one duration story, not the plan's own clock); the
preview's timeline, the onboard export and the run's due times all come from here. Times are
seconds from the start of the run; the planner's states use the vehicle's mission clock
(``start.t_s`` + script time). Steps are named in messages as the page numbers them (from 1).
"""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import dataclass, replace

from backend.scripts.model import Loc, MissionScript, ScriptError, ScriptStep, Trigger
from backend.scripts.timing import StepTiming, Timing, flown_timing
from codec import DecodeError, Encoded, decode_addressed_frame, decode_frame, encode_frame
from planner import Path, Plan, PlanError, VehicleState, plan


@dataclass(frozen=True, slots=True)
class ExpandedStep:
    """One step as the vehicle would fly it.

    Attributes:
        index: the step's index in the script (0-based; "step index + 1" in messages).
        step: the script's step.
        encoded: the frame (``encoded.snaps`` says what was snapped).
        plan: the plan of the decoded command, from ``state``, with the previous step's plan
            (or the ``current`` plan for step 0) in force.
        state: the vehicle's state when the step takes effect (mission clock ``t_s``).
        t_start_s: when it takes effect (s from the start of the run).
        t_end_s: when the next step takes over, or for the last step when it is estimated
            done (one lap for a repeating pattern).
        warnings: what the operator should know about this step's timing.
        timing: when the vehicle is estimated to fly the plan (:mod:`backend.scripts.timing`).
        start_estimated: ``t_start_s`` rests on an estimate (a completion, or the operator's
            go assumed then), not on a time the script sets.
    """

    index: int
    step: ScriptStep
    encoded: Encoded
    plan: Plan
    state: VehicleState
    t_start_s: float
    t_end_s: float
    warnings: tuple[str, ...]
    timing: StepTiming
    start_estimated: bool = False

    @property
    def repeats(self) -> bool:
        return self.plan.path.loop_start is not None

    @property
    def duration_s(self) -> float:
        """The estimated duration: join and pattern (one lap for a repeating pattern)."""
        return self.timing.duration_s

    @property
    def completion_s(self) -> float | None:
        """Seconds after it takes effect when the step is estimated complete (``None``: it
        repeats until retasked); the rule: :mod:`backend.scripts.completion`."""
        return self.timing.completion_s


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


def _state_at(p: Plan, timing: StepTiming, t_rel_s: float, t_abs_s: float) -> VehicleState:
    """Where the vehicle flying ``p`` (as ``timing`` estimates it) is ``t_rel_s`` after ``p``
    took effect, at mission time ``t_abs_s``."""
    path = p.path
    t_rel_s = timing.to_plan_s(t_rel_s)
    sp = path.sample(t_rel_s)
    heading = sp.course_deg
    if sp.speed_mps == 0.0 and path.hold_heading_deg is not None:
        heading = path.hold_heading_deg
    return VehicleState(
        sp.x_m, sp.y_m, sp.z_m, heading, sp.speed_mps, t_abs_s, _segment_at(path, t_rel_s)
    )


def describe_trigger(trigger: Trigger, index: int) -> str:
    """``at its set time``, ``after step 2 completes`` or ``on the operator's go`` (0-based
    ``index``; steps named from 1): beside the time the step takes effect, which the timeline
    gives as a time from the run's start."""
    if trigger.kind == "at":
        return "at its set time"
    if trigger.kind == "after_previous":
        return f"after step {index} completes"
    return "on the operator's go"


def _continued(p: Plan, done: float | None, in_force: Plan | None, index: int) -> str | None:
    """A warning when step ``index`` retasks the same finite pattern the vehicle is flying,
    which keeps its progress (the planner's rule), so it completes (``done``, s) sooner than
    it reads."""
    if in_force is None or in_force.pattern != p.pattern or done is None:
        return None
    if p.pattern == "hover":
        wanted = float(p.command.params.get("duration", 0.0))
        if done >= wanted - 1e-6:
            return None
        return (
            f"the vehicle is already hovering: a hover retask keeps that hover's clock, so "
            f"step {index + 1} completes about {done:.1f} s after it takes effect (estimated), "
            f"not {wanted:g} s (give a longer duration to hover longer)"
        )
    if done <= 1e-6:
        return (
            f"step {index + 1} repeats the {p.pattern.replace('_', ' ')} the vehicle has "
            "already completed (a retask of the same pattern keeps its progress): it "
            "completes at once"
        )
    return None


def _first_start(
    t_start: float, start: VehicleState, current: Plan | None, timing: Timing
) -> VehicleState:
    """The vehicle when step 0 takes effect, ``t_start`` s after the run's start."""
    if current is not None:
        t_abs = start.t_s + t_start
        return _state_at(current, timing(current), t_abs - current.t0_s, t_abs)
    if t_start > 0.0:
        return VehicleState(
            start.x_m, start.y_m, start.z_m, start.heading_deg, 0.0, start.t_s + t_start
        )
    return start


def _after(
    prev: ExpandedStep, trigger: Trigger, i: int, warnings: list[str]
) -> tuple[float, float, bool]:
    """(start time from the run's start, time into ``prev``'s flight, whether the start is
    estimated) of step ``i``, which follows ``prev``; appends the timing warnings."""
    done = prev.completion_s
    name = prev.step.pattern.replace("_", " ")
    estimated = True
    if trigger.kind == "at" and trigger.t_s is not None:
        t_start, estimated = trigger.t_s, False
        if t_start < prev.t_start_s:
            warnings.append(
                f"at {t_start:g} s is before step {i} is expected to start "
                f"({prev.t_start_s:.1f} s): it is sent as soon as step {i} is acknowledged"
            )
            t_start, estimated = prev.t_start_s, prev.start_estimated
        t_rel = t_start - prev.t_start_s
    elif done is None:  # operator (after_previous is refused after a repeating pattern)
        t_rel = prev.duration_s
        t_start = prev.t_start_s + t_rel
        warnings.append(
            f"step {i} ({name}) repeats until retasked, so this step has no completion to "
            "wait for: the preview assumes the operator's go after one lap (estimated "
            f"{t_rel:.1f} s)"
        )
    else:
        t_rel = done
        t_start = prev.t_start_s + done
        if trigger.kind == "operator":
            warnings.append(
                "waits for the operator's go: the time is unknown; the preview assumes "
                f"step {i} completes first (estimated {t_start:.1f} s)"
            )
    if t_start == prev.t_start_s:
        warnings.append(f"takes effect at the same time as step {i}, which is replaced at once")
    return t_start, t_rel, estimated


def expand(
    script: MissionScript,
    start: VehicleState,
    current: Plan | None = None,
    timing: Timing | None = None,
    address: int | None = None,
) -> list[ExpandedStep]:
    """Plan every step of ``script`` in order, as the vehicle would fly them.

    Args:
        script: a validated script.
        start: the vehicle when the run starts (its ``t_s`` is the mission clock then).
        current: the plan the vehicle is running at the start, if any: it keeps the mission
            anchor (orbits stay around the same point) and is flown until step 0 triggers.
        timing: how the vehicle flies a plan (:func:`backend.scripts.timing.flown_timing` of
            its profile); default: a vehicle of unknown figures (flown at the plans' speeds).
        address: a fleet's vehicle's: the steps' frames carry it (None: today's frames).

    Raises:
        ScriptError: the planner cannot expand a step (e.g. more waypoints than the vehicle
            holds); ``loc`` names the step and, when known, the parameter.
        EncodeError: only for a script built without validation (``model_construct``).
    """
    out: list[ExpandedStep] = []
    in_force = current
    timing = timing if timing is not None else flown_timing(None)
    for i, step in enumerate(script.steps):
        encoded = encode_frame(step.pattern, step.params, address=address)
        try:
            if address is None:
                command = decode_frame(encoded.frame.bits).command
            else:
                command = decode_addressed_frame(encoded.frame).command
        except DecodeError as e:  # pragma: no cover - the codec round-trips every command
            raise ScriptError(f"the frame does not decode: {e}", ("steps", i)) from e
        warnings: list[str] = []
        trigger = step.trigger
        prev = out[-1] if out else None
        if prev is None:
            if trigger.kind == "operator":
                warnings.append("waits for the operator's go: assumed at the start of the run")
            t_start = trigger.t_s if trigger.kind == "at" and trigger.t_s is not None else 0.0
            state = _first_start(t_start, start, current, timing)
            estimated = False
        else:
            t_start, t_rel, estimated = _after(prev, trigger, i, warnings)
            state = _state_at(prev.plan, prev.timing, t_rel, start.t_s + t_start)
        try:
            p = plan(command, state, in_force)
        except PlanError as e:
            loc: Loc = ("steps", i, "params", e.field) if e.field else ("steps", i)
            raise ScriptError(str(e), loc) from e
        flies = timing(p)
        note = _continued(p, flies.completion_s, in_force, i)
        if note is not None:
            warnings.append(note)
        if prev is not None:
            out[-1] = replace(prev, t_end_s=t_start)
        end = t_start + flies.duration_s
        out.append(
            ExpandedStep(
                i, step, encoded, p, state, t_start, end, tuple(warnings), flies, estimated
            )
        )
        in_force = p
    return out
