"""Mission scripts, exported onboard: the timed frames the vehicle injects itself (the
paper's field trials).

A frame's ``t_s`` is when its step takes effect in the expansion
(:func:`backend.scripts.expand.expand`), s from the start of the run: an ``at`` step's own time.

What the export does with the other triggers:

* **on completion** (``after_previous``) is **refused**, naming the step and why. The onboard
  script is a list of timed frames; nothing in it, and nothing the onboard agent runs
  (:mod:`onboard.agent`: decode, validate, replan for each frame it receives), evaluates a
  completion. Writing the step at the previous step's planned completion time would turn "on
  completion" into a fixed time without saying so (issue 20: "on completion" became t = 20 s):
  the vehicle would be retasked early when the pattern runs slow (a head current, a speed
  above its top speed) and hold idle when it runs fast. The refusal gives the estimated time
  (the vehicle's profile flying the plan, :mod:`backend.scripts.timing`), so the operator who
  wants a fixed time writes it ('at') knowingly.
* **on the operator's go** becomes the estimated time, with a ``note`` saying so (the vehicle
  out of contact has no operator to wait for).
"""

from __future__ import annotations

from typing import Any

from backend.scripts.expand import ExpandedStep, expand
from backend.scripts.labels import at_time
from backend.scripts.model import MissionScript, ScriptError
from backend.scripts.timing import Timing
from planner import Plan, VehicleState

ONBOARD_FORMAT = "nemesys-onboard-script"


def completion_refusal(expanded: list[ExpandedStep]) -> ScriptError | None:
    """Why the onboard script cannot hold this script: its first step "on completion" (a
    422 at ``steps.<i>.trigger.kind`` naming the step, why, and the estimated time), or
    ``None``."""
    for s in expanded:
        if s.step.trigger.kind != "after_previous":
            continue
        prev = expanded[s.index - 1]
        name = prev.step.pattern.replace("_", " ")
        return ScriptError(
            f"step {s.index + 1} waits for step {s.index} ({name}) to complete, but an "
            "onboard script holds only timed frames: the vehicle cannot evaluate a completion "
            "from it, and a fixed time would retask it early or late if the pattern runs slow "
            f"or fast. Give step {s.index + 1} a time ('at'): step {s.index} is estimated to "
            f"complete {at_time(s.t_start_s)} (its plan flown on the vehicle's profile)",
            ("steps", s.index, "trigger", "kind"),
            "onboard_completion_trigger",
        )
    return None


def _onboard(script: MissionScript, expanded: list[ExpandedStep]) -> dict[str, Any]:
    refusal = completion_refusal(expanded)
    if refusal is not None:
        raise refusal
    frames: list[dict[str, Any]] = []
    for s in expanded:
        frame: dict[str, Any] = {
            "t_s": round(s.t_start_s, 3),
            "pattern": s.step.pattern,
            "hex": s.encoded.frame.hex,
            "bits": s.encoded.frame.bits,
        }
        notes: list[str] = []
        if s.step.trigger.kind == "operator":
            notes.append("operator go in the script: the vehicle sends it at the estimated time")
        elif s.start_estimated:
            notes.append("its time is estimated")
        notes.extend(s.warnings)
        if notes:
            frame["note"] = "; ".join(notes)
        frames.append(frame)
    return {"format": ONBOARD_FORMAT, "version": 1, "name": script.name, "frames": frames}


def export_onboard(
    script: MissionScript,
    start: VehicleState,
    current: Plan | None = None,
    timing: Timing | None = None,
    address: int | None = None,
) -> dict[str, Any]:
    """The onboard script: the timed frames the vehicle injects itself (the field trials').

    ``{"format": "nemesys-onboard-script", "version": 1, "name", "frames": [{"t_s", "pattern",
    "hex", "bits", "note"?}]}``; times are the preview's trigger times (s from the start), so
    an ``operator`` step becomes its estimated time, with a ``note``; ``timing``: how the
    vehicle flies a plan (see :func:`expand`); ``address``: a fleet's vehicle's (its frames
    addressed, as it takes them).

    Raises:
        ScriptError: the planner cannot expand a step, or a step waits for the previous one
            to complete (:func:`completion_refusal`).
    """
    return _onboard(script, expand(script, start, current, timing, address))


def onboard_csv(
    script: MissionScript,
    start: VehicleState,
    current: Plan | None = None,
    timing: Timing | None = None,
    address: int | None = None,
) -> str:
    """The onboard script as CSV: ``t_s,pattern,hex``, one frame per line (the same refusal
    as :func:`export_onboard`)."""
    rows = ["t_s,pattern,hex"]
    for f in export_onboard(script, start, current, timing, address)["frames"]:
        rows.append(f"{f['t_s']:.3f},{f['pattern']},{f['hex']}")
    return "\n".join(rows) + "\n"
