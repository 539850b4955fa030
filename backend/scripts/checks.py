"""Mission scripts, checked: every step through the send policy's checks when the script is
authored (preview, export, run), from where the expansion has the vehicle at that step.

A hard violation refuses the script (export and run: 422 naming the step and the
parameter); a soft one needs the step's ``override`` (409 otherwise). At send time each step
goes through the command service again, from where the vehicle really is then.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace

from backend.commands.checks import SendViolation
from backend.commands.service import LimitRefused, OverrideNeeded
from backend.scripts.expand import ExpandedStep
from backend.scripts.model import MissionScript
from planner import Plan

#: The checks of one planned step (the console's, with its limits and vehicle profile).
PlanCheck = Callable[[Plan], tuple[SendViolation, ...]]


def step_violations(expanded: Sequence[ExpandedStep], check: PlanCheck) -> list[SendViolation]:
    """Every step's violations, each naming its step (``step``: 0-based index)."""
    return [replace(v, step=s.index) for s in expanded for v in check(s.plan)]


def refuse_unsafe(script: MissionScript, found: Sequence[SendViolation]) -> None:
    """The send policy on a whole script, before it is exported or run.

    Raises:
        LimitRefused: a step breaks a limit no operator can override.
        OverrideNeeded: a step breaks an overridable limit without its ``override``.
    """
    hard = [v for v in found if v.kind == "hard"]
    if hard:
        raise LimitRefused("limit violation in the script: no operator can override it", hard)
    soft = [v for v in found if v.kind == "soft" and not _overridden(script, v)]
    if soft:
        raise OverrideNeeded(
            "limit violation in the script: set override on the step to accept it", soft
        )


def _overridden(script: MissionScript, v: SendViolation) -> bool:
    return v.step is not None and script.steps[v.step].override


def step_warning(v: SendViolation) -> str:
    """A violation as a line of the preview's warnings."""
    kind = "cannot be overridden" if v.kind == "hard" else "needs the step's override"
    step = "" if v.step is None else f"step {v.step + 1}: "
    return f"{step}{v.message} ({kind})"
