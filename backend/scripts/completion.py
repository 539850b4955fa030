"""When a mission script's step is *complete*: the one rule the editor, the timeline, the
onboard export and the run all use, and the simulator, the estimate and the vehicle share
(:mod:`sim.completion`).

The rule:

* a **finite** pattern (straight, lawnmower, spiral, helix, box orbit, surface, hover)
  completes when guidance holds the end of its path *and* the vehicle is at the held depth
  (a surface: at the surface); a **hover** when its ``duration`` is up (counted from when it
  takes effect, the approach inside it; a hover retasking a hover in force keeps that hover's
  clock) and it is at its depth. Onboard guidance reports exactly that as ``holding``
  (``surfaced``), so the vehicle's status says it;
* a **repeating** pattern (square, circle: :data:`planner.REPEATING_PATTERNS`, whose paths
  have a ``loop_start``) never completes: it flies until retasked. The editor therefore
  refuses a step "on completion" (``after_previous``) after one (:func:`after_repeating`).

**How long** a step takes is the estimate (:mod:`backend.scripts.timing`: the onboard guidance
flying the plan on the vehicle's profile, done by the rule above), never the plan's own clock,
which the vehicle does not keep (issue 20: a straight 210 s by its plan, done at 160 s). So an
``after_previous`` step takes effect at the previous step's start plus the previous step's
estimated completion, in the timeline and in the onboard export's refusal.

**When the run sends a step "on completion"**, and **when the run is over** (its last step's
pattern complete; issue 20: "completed" at 120 s while the last step flew on to 248 s), follow
the same reading of the step it waits for:

* where the vehicle reports its status (two-way and telemetry links), when the status says the
  step is complete (:func:`vehicle_verdict`): the step's command is the active one and the
  mode is :func:`sim.completion.done_mode` (``holding``; a surface: ``surfaced``), the
  contract's modes (:class:`vehicle_contract.codes.Mode`). The next frame then costs a
  telemetry period and a delivery time after the completion, and arrives after it, never
  before: a vehicle slower than its estimate (a head current) is not retasked early. A status
  saying the step will not complete (another command newer than its acceptance, an empty
  battery, a navigation fault: the vehicle holds or surfaces from where it last knew it was
  and reports ``nav_fault`` until it accepts a command again) stops the run with the reason;
* on a link that reports nothing (an ME modem), at the step's send plus its estimated
  completion, and the run says the completion is *estimated*;
* a last step that repeats (square, circle) never completes: once it is on its way the run
  has nothing left to do, and says the vehicle is "running until retasked".

The old stall (issue 14: a hover retasking a hover in force completes at once, and a run that
waited to see it running, then holding, waited for ever) cannot recur: the verdict reads the
active command and its mode from a status newer than the acceptance, not a transition.

The run clock (``backend/api/scripts.py``) counts vehicle seconds from the run's start: the
simulator's own clock in training (it runs at the time scale, and lags it under load), the
console's clock (:mod:`backend.clock`) on a real link.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Literal

from planner import REPEATING_PATTERNS
from sim.completion import done_mode
from vehicle_contract.codes import Mode
from vehicle_contract.messages import number

#: Patterns that repeat until retasked, so never complete (the planner's own set).
REPEATING = REPEATING_PATTERNS


def repeats(pattern: str) -> bool:
    """True when ``pattern`` flies until retasked (it never completes)."""
    return pattern in REPEATING


def after_repeating(index: int, previous: str) -> str:
    """Why step ``index`` (0-based) may not wait for step ``index - 1``'s ``previous``
    pattern to complete; steps are named as the page numbers them (from 1)."""
    name = previous.replace("_", " ")
    return (
        f"step {index + 1} waits for step {index} ({name}) to complete, but a {name} repeats "
        "until retasked, so it never completes: use a time ('at') or the operator's go"
    )


#: What the vehicle's verdict on a step it was sent is, from one status.
#: ``ended``: the step will not complete (the vehicle was retasked, its battery is empty, or
#: its navigation went stale).
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
    command before); so does an empty battery, and a navigation fault.
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
        if mode == Mode.NAV_FAULT.value:
            return "ended", _nav_fault(status, pattern)
        if mode == done_mode(pattern).value:
            return "complete", f"the vehicle reports the {_name(pattern)} complete ({mode})"
        return "running", f"the vehicle reports the {_name(pattern)} {mode}"
    if not fresh:
        return "unknown", "no status newer than the acknowledgement yet"
    if theirs == "None":
        return "ended", f"the vehicle reports no active command ({mode})"
    return "ended", f"the vehicle runs {_name(theirs)} ({mode}), not this step's command"


def _nav_fault(status: Mapping[str, Any], pattern: str) -> str:
    """A navigation fault during ``pattern``, in words."""
    age_s = number(status.get("nav_age_s"))
    age = "" if age_s is None else f", its last navigation {age_s:.0f} s old"
    return (
        f"the vehicle's navigation went stale during the {_name(pattern)} (nav_fault{age}): it "
        "holds or surfaces from where it last knew it was, and cannot report the step complete "
        "until navigation is back and it accepts a command again"
    )


def _name(pattern: str) -> str:
    return pattern.replace("_", " ")
