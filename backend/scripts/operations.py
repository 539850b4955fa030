"""Mission scripts: a list of commands with triggers, previewed, exported and run.

A mission script is the operator's plan for a dive, written ahead (``docs/api.md`` has the
endpoints, ``docs/scripts.md`` the rules)::

    {"format": "nemesys-mission-script", "version": 1, "name": "pod patrol",
     "steps": [
       {"pattern": "hover", "params": {"duration": 60, "depth": 2, "heading": 90},
        "trigger": {"kind": "at", "t_s": 0}},
       {"pattern": "circle", "params": {"speed": 0.18, "depth": 3, "radius": 5,
                                        "direction": "cw"}, "trigger": {"kind": "after_previous"}}
     ]}

Triggers:

* ``at``: ``t_s`` seconds after the run starts (0 = immediately; "at 60 s from the run's
  start", never "into the dive": a script is run at any point of a dive). ``at`` times never
  decrease along the script.
* ``after_previous``: when the previous step completes (:mod:`backend.scripts.completion`
  defines it: a finite pattern at the end of its path and its depth, a hover after its
  duration; the vehicle's status says it, else the estimate of :mod:`backend.scripts.timing`).
  A repeating pattern (square, circle) never completes, so a step "on completion" after one is
  refused.
* ``operator``: when the operator says go.

The first step is ``at`` or ``operator``. Every step's pattern and parameters are checked by
encoding them (:func:`codec.encode_frame`), so a script that validates can be sent as is;
errors name their place, e.g. ``steps.1.params.radius``.

Pure logic (no I/O, no web framework), split along its seams; every public name is importable
from here:

* :mod:`backend.scripts.model`: :class:`MissionScript` (pydantic v2 models) validates the JSON;
* :mod:`backend.scripts.completion`: the completion rule, in one place;
* :mod:`backend.scripts.timing`: how long each step takes as the vehicle flies it (the
  estimate; the caller passes the vehicle's profile in as a :data:`Timing`);
* :mod:`backend.scripts.expand`: :func:`expand` plans the steps in order, as the vehicle would
  fly them, each from where the previous one has taken the vehicle when it triggers;
* :mod:`backend.scripts.preview`: :func:`preview`, one path and a timeline;
* :mod:`backend.scripts.onboard`: :func:`export_onboard` / :func:`onboard_csv` give the onboard
  script of the paper's field trials: the timed frames the vehicle injects itself (a step "on
  completion" is refused: the onboard script cannot carry it);
* :mod:`backend.scripts.runner`: :class:`ScriptRunner` is the state machine the console
  drives during a run;
* :mod:`backend.scripts.labels`: the triggers and a run's state in the operator's words.

Times in the preview, the export and the run's state are seconds from the start of the run;
the planner's states use the vehicle's mission clock (``start.t_s`` + script time).
"""

from __future__ import annotations

from backend.scripts.completion import REPEATING, after_repeating, repeats
from backend.scripts.expand import ExpandedStep, describe_trigger, expand
from backend.scripts.labels import TRIGGER_WORDS
from backend.scripts.model import (
    MAX_SCRIPT_TIME_S,
    SCRIPT_FORMAT,
    Loc,
    MissionScript,
    RunMode,
    ScriptError,
    ScriptStep,
    StepState,
    Trigger,
    TriggerKind,
    WaitingFor,
)
from backend.scripts.onboard import (
    ONBOARD_FORMAT,
    completion_refusal,
    export_onboard,
    onboard_csv,
)
from backend.scripts.preview import (
    PREVIEW_MAX_POINTS,
    PREVIEW_MIN_POINTS_PER_STEP,
    PreviewPath,
    ScriptPreview,
    SnapOut,
    StartPose,
    StepPreview,
    TimelineEvent,
    preview,
)
from backend.scripts.runner import CompletionBy, Outcome, ScriptRunError, ScriptRunner
from backend.scripts.timing import ESTIMATED_TEXT, StepTiming, Timing, flown_timing

__all__ = [
    "ESTIMATED_TEXT",
    "MAX_SCRIPT_TIME_S",
    "ONBOARD_FORMAT",
    "PREVIEW_MAX_POINTS",
    "PREVIEW_MIN_POINTS_PER_STEP",
    "REPEATING",
    "SCRIPT_FORMAT",
    "TRIGGER_WORDS",
    "CompletionBy",
    "ExpandedStep",
    "Loc",
    "MissionScript",
    "Outcome",
    "PreviewPath",
    "RunMode",
    "ScriptError",
    "ScriptPreview",
    "ScriptRunError",
    "ScriptRunner",
    "ScriptStep",
    "SnapOut",
    "StartPose",
    "StepPreview",
    "StepState",
    "StepTiming",
    "TimelineEvent",
    "Timing",
    "Trigger",
    "TriggerKind",
    "WaitingFor",
    "after_repeating",
    "completion_refusal",
    "describe_trigger",
    "expand",
    "export_onboard",
    "flown_timing",
    "onboard_csv",
    "preview",
    "repeats",
]
