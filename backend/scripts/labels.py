"""Mission scripts, in words: what the page shows of a script's triggers and of a run.

Issue 20: the page said "completion 127.778 s" (a duration that read like a time), "time into
the dive" (for a time counted from the run's start) and "trigger after_previous, transmitted
yes". The rules here, in one place:

* a **duration** reads "takes 127.8 s", and "takes 160 s (estimated)" when it is the estimate
  of how the vehicle flies the step (:mod:`backend.scripts.timing`), as every step's is; a
  **time** reads "at 20 s from the run's start" (every time of a script counts from its run's
  start: a script is written ahead and run at any point of a dive, and the onboard export's
  times count from its start too);
* triggers and states are in the operator's words (:data:`TRIGGER_WORDS`, "sent", "not sent
  yet"), never the identifiers of the JSON.

The page shows these texts as the run's state carries them (``summary`` and each step's
``trigger_text``, ``takes_text`` and ``state_text``), so it decides nothing itself.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

#: Each trigger kind in the operator's words (the page's trigger list says the same).
TRIGGER_WORDS = {
    "after_previous": "after the previous step completes",
    "at": "at a time from the run's start",
    "operator": "on the operator's go",
}


def seconds(value_s: float) -> str:
    """``20 s``, ``127.8 s``: whole seconds without a decimal, else one decimal."""
    rounded = round(value_s, 1)
    return f"{rounded:.0f} s" if rounded == int(rounded) else f"{rounded:.1f} s"


def at_time(t_s: float) -> str:
    """A time of the run: ``at 20 s from the run's start``."""
    return f"at {seconds(t_s)} from the run's start"


def takes(
    completion_s: float | None, estimated: bool = False, planned_s: float | None = None
) -> str:
    """A step's duration: ``takes 127.8 s``, ``takes 160 s (estimated)``, with the plan's own
    clock where it reads differently (``takes 160 s (estimated; 210 s by the plan's own
    clock)``), or ``repeats until retasked``."""
    if completion_s is None:
        return "repeats until retasked"
    text = f"takes {seconds(completion_s)}"
    if not estimated:
        return text
    if planned_s is not None and seconds(planned_s) != seconds(completion_s):
        return f"{text} (estimated; {seconds(planned_s)} by the plan's own clock)"
    return f"{text} (estimated)"


def trigger_text(kind: str, t_s: float | None) -> str:
    """``at 60 s from the run's start``, ``after the previous step completes`` or ``on the
    operator's go``."""
    if kind == "at":
        return at_time(t_s or 0.0)
    return TRIGGER_WORDS.get(kind, kind)


def _step_name(steps: list[dict[str, Any]], i: int) -> str:
    return f"step {i + 1} ({steps[i]['pattern'].replace('_', ' ')})"


def state_text(step: Mapping[str, Any]) -> str:
    """Where one step of a run is: ``not sent yet``, ``sending``, ``sent at 3 s from the
    run's start, acknowledged by the vehicle``, ``failed``, and for the last step when it
    completed."""
    state = step["state"]
    if state == "pending":
        return "not sent yet"
    if state == "failed":
        return "failed"
    if not step["transmitted"]:
        return "sending"
    sent_s = step.get("sent_s")
    text = "sent" if sent_s is None else f"sent {at_time(sent_s)}"
    if state == "acknowledged":
        text += (
            ", acknowledged by the vehicle"
            if step.get("acknowledged_by_vehicle")
            else " (this link gives no acknowledgement)"
        )
    else:
        text += ", waiting for the acknowledgement"
    done = step.get("completed_s")
    if done is not None:
        how = step.get("completion_by")
        text += (
            f"; completed {at_time(done)}, as the vehicle reported"
            if how == "vehicle"
            else f"; completed {at_time(done)} by the estimate (the link reports nothing)"
        )
    return text


def describe_steps(steps: list[dict[str, Any]], completion_by: str) -> None:
    """Add each run step's ``trigger_text``, ``takes_text`` and ``state_text`` (in place)."""
    for s in steps:
        s["trigger_text"] = trigger_text(s["trigger"], s.get("t_s"))
        s["takes_text"] = takes(s.get("completion_s"), estimated=True)
        s["state_text"] = state_text({**s, "completion_by": completion_by})


def run_summary(run: Mapping[str, Any]) -> str:
    """The run's state in one sentence (``run`` is a run's state without its texts)."""
    steps: list[dict[str, Any]] = run["steps"]
    outcome, reason = run["outcome"], run.get("reason")
    last = len(steps) - 1
    if outcome == "completed":
        done = run.get("completed_s")
        when = "" if done is None else f" {at_time(done)}"
        if run.get("completion_by") == "vehicle":
            return f"completed{when}: the vehicle reported {_step_name(steps, last)} complete"
        return (
            f"completed{when} (estimated): {_step_name(steps, last)} completes then by the "
            "estimate; the link reports nothing to confirm it"
        )
    if outcome == "until_retasked":
        return f"every step sent: {_step_name(steps, last)} is running until retasked"
    if outcome in ("stopped", "failed"):
        return f"{outcome}: {reason}" if reason else str(outcome)
    if not run["running"]:
        return "not running"
    head = "running (step mode)" if run["mode"] == "step" else "running (auto)"
    waiting, due, i = run["waiting_for"], run.get("due_s"), run.get("step")
    soon = run.get("expected_s")
    expected = "" if soon is None else f", expected {at_time(soon)} by the estimate"
    by_vehicle = run.get("completion_by") == "vehicle"
    if i is None:  # every step handed out
        if waiting == "acknowledgement":
            return f"{head}: every step sent; {_step_name(steps, last)} is on its way"
        if by_vehicle:
            return (
                f"{head}: every step sent; waiting for the vehicle to report "
                f"{_step_name(steps, last)} complete{expected}"
            )
        when = "" if soon is None else f" {at_time(soon)}"
        return (
            f"{head}: every step sent; {_step_name(steps, last)} is estimated to complete"
            f"{when} (the link reports nothing)"
        )
    name, previous = _step_name(steps, i), _step_name(steps, i - 1) if i > 0 else ""
    if waiting == "acknowledgement":
        return f"{head}: {previous} is on its way; {name} is next"
    if waiting == "operator":
        return f"{head}: {name} awaits the operator's go"
    if waiting == "time":
        return f"{head}: {name} goes {at_time(due or 0.0)}"
    if by_vehicle:
        return f"{head}: {name} goes when the vehicle reports {previous} complete{expected}"
    when = "" if due is None else f" {at_time(due)}"
    return (
        f"{head}: {name} goes when {previous} is estimated to complete{when} (the link "
        "reports nothing)"
    )
