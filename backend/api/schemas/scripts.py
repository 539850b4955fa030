"""Mission scripts' documents: the onboard export and a run's state (the preview's model
is :class:`backend.scripts.operations.ScriptPreview`)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from backend.api.schemas.common import Params
from backend.scripts.operations import RunMode, StepState, Trigger, TriggerKind, WaitingFor


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


class RunStep(BaseModel):
    index: int
    pattern: str
    trigger: TriggerKind
    state: StepState
    transmitted: bool
    sent_s: float | None = Field(
        description="s from the run's start when the step was handed out for sending"
    )
    completion_s: float | None = Field(
        description="planned completion, s after the step takes effect (the end of its path; "
        "a hover: its duration); null: it repeats until retasked"
    )


class RunState(BaseModel):
    """A script run's state (all null / empty before any run)."""

    running: bool
    outcome: Literal["running", "completed", "stopped", "failed"] | None
    mode: RunMode | None
    name: str | None
    step: int | None = Field(description="the next step to hand out")
    next: ProposedStep | None
    waiting_for: WaitingFor | None
    due_s: float | None = Field(
        description="when the next step is due, s from the run's start (at: its time; "
        "after_previous: the previous step's send time plus its planned completion)"
    )
    elapsed_s: float | None = Field(description="run clock: vehicle s since the run started")
    steps: list[RunStep]
    reason: str | None
    commands: dict[int, int] = Field(description="step index -> command id, steps sent so far")
