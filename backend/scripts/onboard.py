"""Mission scripts, exported onboard: the timed frames the vehicle injects itself (the
paper's field trials).

A frame's ``t_s`` is when its step takes effect in the expansion
(:func:`backend.scripts.expand.expand`): an ``after_previous`` step at the previous step's
start plus its completion time (:mod:`backend.scripts.completion`), the same time the
preview's timeline shows and the run sends at.
"""

from __future__ import annotations

from typing import Any

from backend.scripts.expand import ExpandedStep, expand
from backend.scripts.model import MissionScript
from planner import Plan, VehicleState

ONBOARD_FORMAT = "nemesys-onboard-script"


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
            prev = expanded[s.index - 1]
            notes.append(
                f"after step {s.index} completes: {prev.completion_s or 0.0:.1f} s after it "
                "takes effect"
            )
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
