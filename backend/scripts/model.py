"""Mission scripts, the document: the pydantic models that validate a script's JSON.

A script (``format`` ``nemesys-mission-script``, ``version`` 1) is a name and 1..100 steps,
each a pattern with its parameters and a trigger (``at``, ``after_previous``, ``operator``;
see :mod:`backend.scripts.operations`). Every step's pattern and parameters are checked by encoding
them
(:func:`codec.encode_frame`); a step "on completion" after a repeating pattern is refused
(:mod:`backend.scripts.completion`). Errors name their place, e.g. ``steps.1.params.radius``.
With a fleet (``NEMESYS_VEHICLES``) every step names its ``vehicle``, the same one throughout
(a run drives one vehicle; the console checks the name: :mod:`backend.api.scripts`).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator
from pydantic_core import InitErrorDetails, PydanticCustomError, ValidationError

from backend.scripts.completion import after_repeating, repeats
from backend.strict_input import NotBool
from codec import EncodeError, encode_frame

SCRIPT_FORMAT = "nemesys-mission-script"
#: Latest "at" time a script may use (s from the start of the run): a day, beyond any dive.
MAX_SCRIPT_TIME_S = 86_400.0

TriggerKind = Literal["at", "after_previous", "operator"]
RunMode = Literal["auto", "step"]
StepState = Literal["pending", "sent", "acknowledged", "failed"]
WaitingFor = Literal["time", "completion", "operator", "acknowledgement"]
Loc = tuple[int | str, ...]


def _line_error(
    loc: Loc, kind: str, message: str, value: object, **ctx: object
) -> InitErrorDetails:
    """One pydantic error at ``loc`` (``{`` and ``}`` in ``message`` are taken literally)."""
    text = message.replace("{", "{{").replace("}", "}}")
    error: InitErrorDetails = {
        "type": PydanticCustomError(kind, text, ctx or None),
        "loc": loc,
        "input": value,
    }
    return error


class Trigger(BaseModel):
    """When a step is sent: ``at`` ``t_s`` seconds into the run, ``after_previous`` (the
    previous pattern completed) or ``operator`` (the operator's go)."""

    model_config = ConfigDict(extra="forbid")

    kind: TriggerKind
    t_s: float | None = Field(
        default=None, ge=0.0, le=MAX_SCRIPT_TIME_S, allow_inf_nan=False, strict=True
    )

    @model_validator(mode="after")
    def _time_only_for_at(self) -> Trigger:
        if self.kind == "at" and self.t_s is None:
            raise ValidationError.from_exception_data(
                "Trigger",
                [
                    _line_error(
                        ("t_s",),
                        "missing",
                        "an 'at' trigger needs t_s: seconds from the start of the run "
                        "(0 = immediately)",
                        None,
                    )
                ],
            )
        if self.kind != "at" and self.t_s is not None:
            raise ValidationError.from_exception_data(
                "Trigger",
                [
                    _line_error(
                        ("t_s",),
                        "unexpected_time",
                        f"an '{self.kind}' trigger takes no t_s (only 'at' triggers have a time)",
                        self.t_s,
                    )
                ],
            )
        return self


class ScriptStep(BaseModel):
    """One command of the script: a pattern with its parameters, and its trigger."""

    model_config = ConfigDict(extra="forbid")

    pattern: str
    params: dict[str, float | str] = Field(default_factory=dict)
    trigger: Trigger
    override: bool = Field(
        False,
        description="the operator accepts this step's overridable limit violations (recorded "
        "with its command); a hard one refuses the script whatever this says",
    )
    vehicle: str | None = Field(
        None,
        max_length=32,
        description="the fleet's vehicle the step is for: required with a fleet, the same in "
        'every step (a run drives one vehicle); without one, omitted or "nemesys"',
    )

    @field_validator("params", mode="before")
    @classmethod
    def _no_booleans(cls, value: object) -> object:
        # pydantic would read true/false as 1.0/0.0; a boolean is never a parameter value
        if isinstance(value, dict):
            for key, v in value.items():
                if isinstance(v, bool):
                    raise ValidationError.from_exception_data(
                        "ScriptStep",
                        [
                            _line_error(
                                (str(key),),
                                "float_type",
                                f"{key} must be a number or a choice, not {str(v).lower()}",
                                v,
                            )
                        ],
                    )
        return value

    @model_validator(mode="after")
    def _encodes(self) -> ScriptStep:
        """The step must encode: the codec names the parameter at fault."""
        try:
            encode_frame(self.pattern, self.params)
        except EncodeError as e:
            if e.field is None:
                error = _line_error(("pattern",), "unknown_pattern", str(e), self.pattern)
            else:
                value = self.params.get(e.field)
                error = _line_error(("params", e.field), "invalid_param", str(e), value)
            raise ValidationError.from_exception_data("ScriptStep", [error]) from e
        return self


class MissionScript(BaseModel):
    """A mission script (``format`` ``nemesys-mission-script``, ``version`` 1)."""

    model_config = ConfigDict(extra="forbid")

    format: Literal["nemesys-mission-script"]
    #: ``true`` is refused: pydantic's ``Literal[1]`` would take it (``True == 1``).
    version: Annotated[Literal[1], NotBool]
    name: str = Field(min_length=1, max_length=80)
    steps: list[ScriptStep] = Field(min_length=1, max_length=100)

    @model_validator(mode="after")
    def _check_steps(self) -> MissionScript:
        errors: list[InitErrorDetails] = []
        first = self.steps[0].trigger
        if first.kind == "after_previous":
            errors.append(
                _line_error(
                    ("steps", 0, "trigger", "kind"),
                    "first_trigger",
                    "the first step has no previous one: use 'at' (t_s 0 = immediately) or "
                    "'operator'",
                    first.kind,
                )
            )
        last_at: tuple[int, float] | None = None
        for i, step in enumerate(self.steps):
            if i > 0 and step.trigger.kind == "after_previous":
                previous = self.steps[i - 1].pattern
                if repeats(previous):
                    errors.append(
                        _line_error(
                            ("steps", i, "trigger", "kind"),
                            "never_completes",
                            after_repeating(i, previous),
                            step.trigger.kind,
                        )
                    )
            t = step.trigger.t_s
            if step.trigger.kind == "at" and t is not None:
                if last_at is not None and t < last_at[1]:
                    errors.append(
                        _line_error(
                            ("steps", i, "trigger", "t_s"),
                            "time_order",
                            f"'at' times must not decrease along the script: {t:g} s is before "
                            f"step {last_at[0] + 1}'s {last_at[1]:g} s",
                            t,
                        )
                    )
                last_at = (i, t)
        if errors:
            raise ValidationError.from_exception_data("MissionScript", errors)
        return self


class ScriptError(ValueError):
    """A valid script that cannot be expanded (the planner refused a step), or exported (the
    onboard script cannot carry a step's trigger).

    Attributes:
        loc: where, as in a validation error: ``("steps", 2, "params", "radius")``.
        message: why (the planner's message, naming the parameter).
        kind: the error's ``type`` (``plan_error``; the onboard export's refusals say theirs).
    """

    def __init__(self, message: str, loc: Loc, kind: str = "plan_error") -> None:
        super().__init__(f"{'.'.join(map(str, loc))}: {message}")
        self.message = message
        self.loc = loc
        self.kind = kind

    def errors(self) -> list[dict[str, Any]]:
        """The error in FastAPI's 422 ``detail`` shape (without the ``body`` prefix)."""
        return [{"loc": list(self.loc), "msg": self.message, "type": self.kind}]
