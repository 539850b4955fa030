"""Mission scripts' documents: the onboard export and a run's state (the preview's model
is :class:`backend.scripts.operations.ScriptPreview`)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from backend.api.schemas.common import Params
from backend.scripts.operations import (
    CompletionBy,
    Outcome,
    RunMode,
    StepState,
    Trigger,
    TriggerKind,
    WaitingFor,
)


class OnboardFrame(BaseModel):
    t_s: float = Field(
        description="s from the start of the run; an after_previous step: the previous "
        "step's start plus its completion time"
    )
    pattern: str
    hex: str
    bits: str
    note: str | None = Field(None, description="present for operator / after_previous steps")


class OnboardScript(BaseModel):
    """The onboard script of the field trials: the timed frames the vehicle injects."""

    format: Literal["nemesys-onboard-script"]
    version: Literal[1]
    name: str
    frames: list[OnboardFrame]


class ProposedStep(BaseModel):
    """The step awaiting the operator's go."""

    index: int
    pattern: str
    params: Params
    trigger: Trigger
    vehicle: str | None = Field(
        None, description="the fleet's vehicle it goes to (absent without a fleet)"
    )


class RunStep(BaseModel):
    index: int
    pattern: str
    vehicle: str | None = Field(
        None, description="the fleet's vehicle the step is sent to (absent without a fleet)"
    )
    trigger: TriggerKind
    t_s: float | None = Field(description="an 'at' trigger's time, s from the run's start")
    state: StepState
    transmitted: bool
    acknowledged_by_vehicle: bool = Field(
        description="the vehicle acknowledged it (false on a link without acknowledgements, "
        "where 'acknowledged' means its last copy left)"
    )
    sent_s: float | None = Field(
        description="s from the run's start when the step was handed out for sending"
    )
    completion_s: float | None = Field(
        description="a duration, estimated: how long the step takes as the vehicle flies it, "
        "s after it takes effect (the end of its path and its depth; a hover: its duration); "
        "null: it repeats until retasked"
    )
    completed_s: float | None = Field(
        description="when the step completed, s from the run's start, for the steps the run "
        "waited for (before a step on completion, and the last; see completion_by); null "
        "otherwise"
    )
    trigger_text: str = Field(description="the trigger in words ('at 60 s from the run's start')")
    takes_text: str = Field(description="the duration in words ('takes 127.8 s')")
    state_text: str = Field(description="where the step is, in words ('sent at 3 s ...')")


class RunState(BaseModel):
    """A script run's state (all null / empty before any run)."""

    running: bool
    outcome: Outcome | None = Field(
        description="completed: the last step's pattern completed; until_retasked: every step "
        "was sent and the last one repeats (the vehicle runs it until retasked)"
    )
    mode: RunMode | None
    name: str | None
    step: int | None = Field(description="the next step to hand out")
    next: ProposedStep | None
    waiting_for: WaitingFor | None
    due_s: float | None = Field(
        description="when the next step is due, s from the run's start (at: its time; "
        "after_previous: when the vehicle reported the previous step complete, null until "
        "then; on a link that reports nothing, the previous step's send time plus its "
        "estimated completion); once every step is sent, when the last is expected to "
        "complete (estimated)"
    )
    expected_s: float | None = Field(
        None,
        description="when the step the run waits for (before a step on completion, or the "
        "last) is estimated to complete, s from the run's start",
    )
    elapsed_s: float | None = Field(description="run clock: vehicle s since the run started")
    completion_by: CompletionBy | None = Field(
        description="how a step's completion is known: vehicle (its status reports it) or "
        "estimate (the link reports nothing)"
    )
    completed_s: float | None = Field(description="when the run completed, s from the run's start")
    steps: list[RunStep]
    reason: str | None
    summary: str = Field(description="the run's state in words, as the page shows it")
    commands: dict[int, int] = Field(description="step index -> command id, steps sent so far")
