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

How the run detects completion: **by the plan, on the run clock** (not by the vehicle's
status). A step "on completion" is sent :func:`completion_s` of the previous step after the
previous step was sent. Why:

1. On the ME modem link the station has no telemetry at all (the link is one-way): a run that
   waits for the vehicle to report completion waits forever there. The old rule (wait until
   the vehicle was seen running the pattern, then holding) also stalled in training: a hover
   that retasks a hover in force completes at once, the vehicle never reports it running, and
   the run waited for ever (issue 14: hover, then a circle on completion).
2. Every frame takes the link's delivery time to reach the vehicle. Sending the next frame the
   completion time after the previous one was sent makes it arrive when the previous pattern
   ends, as the onboard script (which the vehicle injects itself) and the timeline have it.
   Waiting for a completion report would add a delivery time and a telemetry period per step.
3. In training the status reaches the console about every 0.4 s of wall time: 20 s of vehicle
   time at the 50x time scale, too coarse to time a retask by.

The run therefore never waits on the vehicle beyond the plan: the longest a step "on
completion" waits is the previous step's planned completion time (plus, like every step, the
previous step's acknowledgement, which the command's own timeout bounds). The price: a vehicle
slower than its plan (a commanded speed above its top speed, a head current) is retasked at the
planned time, before it has finished; the preview's speed checks warn of the first case.

The run clock (``backend/api/scripts.py``) counts vehicle seconds from the run's start: the
simulator's own clock in training (it runs at the time scale, and lags it under load), the
station's monotonic clock on a real link.
"""

from __future__ import annotations

from planner import REPEATING_PATTERNS, Plan

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
