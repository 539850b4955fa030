"""When a mission script's step is *complete*: the one rule the editor, the timeline, the
onboard export and the run all use.

The rule (one place, this module):

* a **finite** pattern completes when its planned path ends (:func:`completion_s` is the
  plan's ``path.duration_s``): straight, lawnmower, spiral, helix, box orbit (its ``laps``),
  surface (at the surface) and hover;
* a **hover** is a hold: it completes after its ``duration`` parameter, counted from when it
  takes effect (the approach to the hold point and depth is inside it; only an approach
  longer than the duration, or a hover retasking a hover in force, which keeps that hover's
  clock, makes it differ, and then the plan says so);
* a **repeating** pattern (square, circle: :data:`planner.REPEATING_PATTERNS`, whose paths
  have a ``loop_start``) never completes: it flies until retasked. The editor therefore
  refuses a step "on completion" (``after_previous``) after one (:func:`after_repeating`).

So an ``after_previous`` step takes effect at the previous step's start plus the previous
step's completion time, in the timeline, in the onboard export and in the run.

How the run times a step "on completion": **by the plan, on the run clock** (not by the
vehicle's status). A step "on completion" is sent :func:`completion_s` of the previous step after
the previous step was sent. Why:

1. On the ME modem link the station has no telemetry at all (the link is one-way): a run that
   waits for the vehicle to report completion waits forever there. The old rule (wait until
   the vehicle was seen running the pattern, then holding) also stalled in training: a hover
   that retasks a hover in force completes at once, the vehicle never reports it running, and
   the run waited for ever (issue 14: hover, then a circle on completion).
2. Every frame takes the link's delivery time to reach the vehicle. Sending the next frame the
   completion time after the previous one was sent makes it arrive when the previous pattern
   ends, as the timeline has it. Waiting for a completion report would add a delivery time and
   a telemetry period per step.
3. In training the status reaches the console about every 0.4 s of wall time: 20 s of vehicle
   time at the 50x time scale, too coarse to time a retask by.

The price: a vehicle slower than its plan (a commanded speed above its top speed, a head
current) is retasked at the planned time, before it has finished; the preview's speed checks
warn of the first case.

**When the run is over** is another question, with another answer (issue 20: a run said
"completed" when its last step was acknowledged, while that step flew on for two minutes). The
run ends when its **last step's pattern completes**:

* where the vehicle reports its status (two-way and telemetry links), when the status says so
  (:func:`vehicle_verdict`): the step's command is the active one and guidance reports it done
  (``holding``, at the path's end *and* its depth; a surface: ``surfaced``), the contract's
  modes (:class:`vehicle_contract.codes.Mode`), read as the simulator's own completion reads
  guidance (:func:`sim.completion.done_mode`);
* on a link that reports nothing (an ME modem), at the step's send plus its flyable duration
  (:func:`flyable_s`, the planner's estimate at the vehicle's top speed and heave rate), and
  the run says the completion is *estimated*;
* a last step that repeats (square, circle) never completes: once it is on its way the run
  has nothing left to do, and says the vehicle is "running until retasked".

The run clock (``backend/api/scripts.py``) counts vehicle seconds from the run's start: the
simulator's own clock in training (it runs at the time scale, and lags it under load), the
console's clock (:mod:`backend.clock`) on a real link.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Literal

from planner import REPEATING_PATTERNS, Plan, estimate
from sim.completion import done_mode
from vehicle_contract.codes import Mode
from vehicle_contract.messages import number

#: Patterns that repeat until retasked, so never complete (the planner's own set).
REPEATING = REPEATING_PATTERNS


def repeats(pattern: str) -> bool:
    """True when ``pattern`` flies until retasked (it never completes)."""
    return pattern in REPEATING


def completion_s(plan: Plan) -> float | None:
    """Seconds after ``plan`` takes effect when it is complete; ``None`` for a repeating
    pattern, which never completes (the plan's path then ends one lap in)."""
    path = plan.path
    return None if path.loop_start is not None else path.duration_s


def after_repeating(index: int, previous: str) -> str:
    """Why step ``index`` (0-based) may not wait for step ``index - 1``'s ``previous``
    pattern to complete; steps are named as the page numbers them (from 1)."""
    name = previous.replace("_", " ")
    return (
        f"step {index + 1} waits for step {index} ({name}) to complete, but a {name} repeats "
        "until retasked, so it never completes: use a time ('at') or the operator's go"
    )


def flyable_s(
    plan: Plan, top_speed_mps: float | None = None, heave_rate_mps: float | None = None
) -> float | None:
    """Seconds the vehicle needs to fly ``plan`` at the speed it can fly (the planner's
    estimate, :func:`planner.estimate`, at its top speed and heave rate; unknown: as planned);
    ``None`` for a repeating pattern (``Estimate.repeats``), which never completes."""
    est = estimate(plan, top_speed_mps, heave_rate_mps)
    return None if est.repeats else est.duration_s


#: What the vehicle's verdict on a step it was sent is, from one status.
#: ``ended``: the step will not complete (the vehicle was retasked, or its battery is empty).
Verdict = Literal["complete", "running", "ended", "unknown"]


def vehicle_verdict(
    status: Mapping[str, Any] | None,
    pattern: str,
    params: Mapping[str, Any],
    after_t_s: float | None,
) -> tuple[Verdict, str]:
    """What the vehicle's ``status`` says of the command ``pattern`` / ``params`` (the
    decoded values, as in its acknowledgement), accepted by the vehicle at ``after_t_s``
    (vehicle time; ``None``: unknown): the verdict and why, in words.

    The status's ``active`` command (optional in the contract) names the command; without it
    only ``pattern`` does, which cannot tell two commands of the same pattern apart, so it
    counts only from a status newer than the acceptance. A status naming another command ends
    the step (retasked) only when newer than the acceptance (an older one still shows the
    command before); so does an empty battery.
    """
    if not status:
        return "unknown", "no status from the vehicle yet"
    mode, t_s = status.get("mode"), number(status.get("t_s"))
    fresh = t_s is not None and after_t_s is not None and t_s > after_t_s
    active = status.get("active")
    if isinstance(active, Mapping):
        ours = active.get("pattern") == pattern and active.get("params") == dict(params)
        theirs = f"{active.get('pattern')}"
    else:
        if not fresh:
            return "unknown", "no status newer than the acknowledgement yet"
        ours = status.get("pattern") == pattern
        theirs = f"{status.get('pattern')}"
    if ours:
        if mode == Mode.BATTERY_EMPTY.value:
            return "ended", f"the vehicle's battery is empty during the {_name(pattern)}"
        if mode == done_mode(pattern).value:
            return "complete", f"the vehicle reports the {_name(pattern)} complete ({mode})"
        return "running", f"the vehicle reports the {_name(pattern)} {mode}"
    if not fresh:
        return "unknown", "no status newer than the acknowledgement yet"
    if theirs == "None":
        return "ended", f"the vehicle reports no active command ({mode})"
    return "ended", f"the vehicle runs {_name(theirs)} ({mode}), not this step's command"


def _name(pattern: str) -> str:
    return pattern.replace("_", " ")
