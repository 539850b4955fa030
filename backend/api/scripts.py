"""Mission scripts: preview (one 3D path and a timeline), onboard export, and runs.

With a fleet every step names its vehicle, the same one throughout (a script drives one
vehicle: :func:`script_vehicle`, 422 at the step otherwise); the script is expanded from
where that vehicle is, its steps sent to it, and only a command to it (or a Surface to all)
ends its run."""

from __future__ import annotations

import asyncio
import functools
from collections.abc import Callable
from typing import Any, Literal

from fastapi import APIRouter, HTTPException
from fastapi.responses import JSONResponse, Response
from pydantic import BaseModel, ConfigDict

from backend.api.deps import ConsoleDep, OperatorDep
from backend.api.schemas import (
    OPERATOR,
    ErrorDetail,
    LimitViolationError,
    OnboardScript,
    RunState,
    ValidationErrorResponse,
    errors,
)
from backend.api.view import ViewHeader
from backend.clock import Clock
from backend.commands.service import SendRequest
from backend.console import Console
from backend.mission_log.store import FINAL_STATES
from backend.scripts.checks import refuse_unsafe, step_violations
from backend.scripts.fleet import address_of, mirror_of, script_vehicle
from backend.scripts.guard import RunOver
from backend.scripts.operations import (
    CompletionBy,
    MissionScript,
    ScriptError,
    ScriptPreview,
    ScriptRunError,
    ScriptRunner,
    completion_refusal,
    expand,
    export_onboard,
    flown_timing,
    onboard_csv,
    preview,
)
from station.link import Capability
from vehicle_contract.messages import number

router = APIRouter(prefix="/api/scripts", tags=["scripts"])

#: How often a run checks its triggers, acknowledgements and the vehicle's status at most
#: (s on the console's clock, :mod:`backend.clock`); it wakes sooner for a due step.
POLL_S = 0.2
#: Shortest sleep of a run's loop (s on the console's clock).
MIN_SLEEP_S = 0.005
#: How often a due step's loop looks for the previous step's acknowledgement (s, same clock).
ACK_POLL_S = 0.05
#: The run state before any run: every key of a run's, empty.
IDLE: dict[str, Any] = {
    "running": False,
    "outcome": None,
    "mode": None,
    "name": None,
    "step": None,
    "next": None,
    "waiting_for": None,
    "due_s": None,
    "expected_s": None,
    "elapsed_s": None,
    "steps": [],
    "completion_by": None,
    "completed_s": None,
    "reason": None,
    "summary": "not running",
}
#: The errors of a run control.
RUN_CONTROL = errors((*OPERATOR, 409), why={409: "no step awaits the operator's go"})


class RunIn(BaseModel):
    model_config = ConfigDict(extra="forbid")
    script: MissionScript
    mode: Literal["auto", "step"] = "auto"


def _plan_error(err: ScriptError) -> HTTPException:
    return HTTPException(422, [{**e, "loc": ["body", *e["loc"]]} for e in err.errors()])


@router.post("/preview", responses=errors((413, 422)))
def script_preview(
    script: MissionScript, console: ConsoleDep, x_nemesys_view: ViewHeader = None
) -> ScriptPreview:
    """The whole script as one path (NED) with its timeline, from where the vehicle is now,
    timed as the vehicle's profile flies it (estimated); drawn in the caller's own 3D view
    (``X-Nemesys-View``)."""
    vehicle = script_vehicle(console, script)
    mirror = mirror_of(console, vehicle)
    timing = flown_timing(console.profile)
    checks = functools.partial(console.plan_violations, vehicle=vehicle)
    try:
        doc = preview(script, console.vehicle_state(vehicle), mirror, checks, timing)
    except ScriptError as err:
        raise _plan_error(err) from None
    if console.viewer is not None:
        path = doc.path
        labels = [
            (i, f"{s.index + 1}: {s.pattern}")
            for s, i in zip(doc.steps, path.step_start, strict=False)
        ]
        console.viewer.show_script(x_nemesys_view, path.x_m, path.y_m, path.z_m, labels)
    return doc


@router.post(
    "/export",
    response_class=Response,
    responses={
        **errors(
            (409, 413, 422),
            models={409: LimitViolationError, 422: ValidationErrorResponse | LimitViolationError},
            why={
                409: "a step breaks an overridable limit without its override",
                422: "invalid script, a step 'on completion' (the onboard script cannot "
                "carry it), or a step breaks a limit no operator can override",
            },
        ),
        200: {
            "description": "the onboard script: JSON (format=json) or CSV t_s,pattern,hex "
            "(format=csv), as an attachment",
            "model": OnboardScript,
            "content": {"text/csv": {"schema": {"type": "string"}}},
        },
    },
)
def script_export(
    script: MissionScript, console: ConsoleDep, format: Literal["json", "csv"] = "json"
) -> Response:
    """The onboard script the paper's field trials used: a timed list of frames. A step "on
    completion" is refused (422 at its trigger): the onboard script cannot carry it
    (:mod:`backend.scripts.onboard`)."""
    vehicle = script_vehicle(console, script)
    mirror, address = mirror_of(console, vehicle), address_of(console, vehicle)
    state = console.vehicle_state(vehicle)
    name = "".join(c if c.isalnum() else "-" for c in script.name)
    timing = flown_timing(console.profile)
    try:
        expanded = expand(script, state, mirror, timing, address)
        refusal = completion_refusal(expanded)
        if refusal is not None:
            raise refusal
    except ScriptError as err:
        raise _plan_error(err) from None
    checks = functools.partial(console.plan_violations, vehicle=vehicle)
    refuse_unsafe(script, step_violations(expanded, checks))
    try:
        if format == "csv":
            return Response(
                onboard_csv(script, state, mirror, timing, address),
                media_type="text/csv",
                headers={"Content-Disposition": f'attachment; filename="{name}-onboard.csv"'},
            )
        doc = export_onboard(script, state, mirror, timing, address)
    except ScriptError as err:
        raise _plan_error(err) from None
    return JSONResponse(
        doc, headers={"Content-Disposition": f'attachment; filename="{name}-onboard.json"'}
    )


def _state(console: Console) -> RunState:
    """The run's state with the command ids of its steps sent so far."""
    state = console.runner.state() if console.runner is not None else IDLE
    return RunState.model_validate({**state, "commands": console.script_commands})


@router.get("/run", response_model=RunState, response_model_exclude_unset=True)
def run_state(console: ConsoleDep) -> RunState:
    return _state(console)


@router.post(
    "/run",
    response_model=RunState,
    response_model_exclude_unset=True,
    responses=errors(
        (*OPERATOR, 409, 413, 422),
        models={
            409: LimitViolationError | ErrorDetail,
            422: ValidationErrorResponse | LimitViolationError,
        },
        why={
            409: "a script is already running, or a step breaks an overridable limit "
            "without its override",
            422: "invalid script, or a step breaks a limit no operator can override",
        },
    ),
)
async def run(body: RunIn, console: ConsoleDep, _op: OperatorDep) -> RunState:
    """Run a script against the vehicle: ``auto`` sends each step at its trigger; ``step``
    proposes each step and waits for the operator's go (``/run/next``)."""
    if console.runner is not None and console.runner.running:
        raise HTTPException(409, "a script is already running; stop it first")
    vehicle = script_vehicle(console, body.script, ("body", "script"))
    mirror = mirror_of(console, vehicle)
    timing = flown_timing(console.profile)
    try:  # timed by the same expansion as the preview and the export
        expanded = expand(body.script, console.vehicle_state(vehicle), mirror, timing)
    except ScriptError as err:
        raise HTTPException(
            422, [{**e, "loc": ["body", "script", *e["loc"]]} for e in err.errors()]
        ) from None
    checks = functools.partial(console.plan_violations, vehicle=vehicle)
    refuse_unsafe(body.script, step_violations(expanded, checks))
    console.runner = ScriptRunner.planned(
        body.script,
        expanded,
        body.mode,
        clock=run_clock(console),
        completion_by=_completion_by(console, "estimate", vehicle),
        vehicle=vehicle,
    )
    console.script_commands = {}
    console.start_script_loop(_loop(console))
    await asyncio.sleep(0)
    return _state(console)


@router.post(
    "/run/next", response_model=RunState, response_model_exclude_unset=True, responses=RUN_CONTROL
)
async def run_next(console: ConsoleDep, _op: OperatorDep) -> RunState:
    """Operator's go: send the proposed step."""
    runner = console.runner
    if runner is None:
        raise HTTPException(409, "no script is running")
    try:
        index = runner.go()
    except ScriptRunError as err:
        raise HTTPException(409, str(err)) from None
    await _send(console, runner, index)
    return _state(console)


@router.post(
    "/run/stop",
    response_model=RunState,
    response_model_exclude_unset=True,
    responses=errors(OPERATOR),
)
def run_stop(console: ConsoleDep, _op: OperatorDep) -> RunState:
    if console.runner is not None:
        console.runner.stop()
    return _state(console)


async def _send(console: Console, runner: ScriptRunner, index: int) -> None:
    step = runner.script.steps[index]
    assert console.service is not None
    request = SendRequest(
        step.pattern,
        step.params,
        "script",
        override=step.override,
        kind="script",
        vehicle=step.vehicle,
    )
    try:  # checked again now: the vehicle may have moved since the script was authored
        with console.script_guard.step(request, runner):  # a step: it does not stop the run
            record = (await console.service.send(request)).record
    except RunOver:  # the operator sent something else first: the run is over, this unsent
        runner.withdraw(index)
        return
    except Exception as err:  # refused, rate limit, log, link: the run stops with the reason
        runner.mark_failed(index, f"not sent: {err}")
        return
    console.script_commands[index] = record.id
    runner.mark_sent(index)


def _time_scale(console: Console) -> float:
    """Vehicle seconds per wall second: the simulator's time scale in training, else 1."""
    bridge = getattr(console, "bridge", None)
    scale = getattr(bridge, "time_scale", 1.0) if bridge is not None else 1.0
    return float(scale) if isinstance(scale, int | float) else 1.0


def run_clock(console: Console) -> Callable[[], float]:
    """The run clock: vehicle seconds since the run started.

    In training it follows the simulator's own clock (``sim.t_s``: it runs at the time
    scale and lags it under load, so the run keeps the vehicle's time, not the wall's); on a
    real link, where a one-way modem gives no telemetry, the console's clock
    (:attr:`Console.clock`: a test's manual clock moves it by hand). It only ever moves
    forward (a training reset does not send it back).
    """
    sim = getattr(console, "sim", None)
    clock = console.clock
    last_wall = clock.monotonic()
    last_sim = float(sim.t_s) if sim is not None else 0.0
    elapsed = 0.0

    def now() -> float:
        nonlocal last_wall, last_sim, elapsed
        wall = clock.monotonic()
        if sim is not None:
            t = float(sim.t_s)
            elapsed += max(0.0, t - last_sim)
            last_sim = t
        else:
            elapsed += wall - last_wall
        last_wall = wall
        return elapsed

    return now


def _completion_by(console: Console, was: CompletionBy, vehicle: str | None = None) -> CompletionBy:
    """How a run knows a step completed: from the vehicle's status (a fleet's ``vehicle``'s)
    where its link carries it, else by the estimate. A link whose capability is not known
    (yet, or again while it reconnects) changes nothing: a vehicle that reports is not taken
    for one that does not."""
    link = console.fleet.get(vehicle).link
    if link is None or link.capability is Capability.UNKNOWN:
        return was
    return "vehicle" if link.telemetry else "estimate"


async def _sleep(clock: Clock, seconds: float) -> None:
    """Wait ``seconds`` on ``clock`` (a timer, not ``asyncio.sleep``: a test's manual clock
    fires it when it moves past it, with no real waiting)."""
    woken: asyncio.Future[None] = asyncio.get_running_loop().create_future()

    def wake() -> None:
        if not woken.done():
            woken.set_result(None)

    timer = clock.call_later(seconds, wake)
    try:
        await woken
    finally:
        timer.cancel()


def _sleep_s(console: Console, runner: ScriptRunner) -> float:
    """Seconds to sleep (console clock): :data:`POLL_S`, or less when a step falls due
    sooner (run-clock seconds over the time scale)."""
    due, now = runner.due_s(), runner.now_s
    scale = _time_scale(console)
    if due is None or now is None or scale <= 0 or runner.next_index is None:
        return POLL_S  # nothing due, or only the last step's completion to wait for
    if due <= now:  # due, waiting for the previous step's acknowledgement
        return ACK_POLL_S
    return min(POLL_S, max(MIN_SLEEP_S, (due - now) / scale))


async def _loop(console: Console) -> None:
    runner = console.runner
    assert runner is not None and console.log is not None
    vehicle = runner.script.steps[0].vehicle if console.fleet.configured else None
    hub = console.fleet.get(vehicle).hub
    while runner.running:
        runner.completion_by = _completion_by(console, runner.completion_by, vehicle)
        # only the steps on their way are looked up in the log (one at a time, in practice)
        for index, command_id in list(console.script_commands.items()):
            if runner.step_state(index) != "sent":
                continue
            record = console.log.command(command_id)
            if record is None:
                continue
            # sent: a one-way link's end, all that can be known; the run goes on
            if record["state"] in ("acknowledged", "sent"):
                ack = record.get("ack") or {}
                runner.mark_acknowledged(
                    index,
                    by_vehicle=record["state"] == "acknowledged",
                    vehicle_t_s=number(ack.get("t_s")) if isinstance(ack, dict) else None,
                )
            elif record["state"] in FINAL_STATES:  # rejected, timed_out, failed, ...
                runner.mark_failed(index, f"{record['state']}: {record['reason']}")
        # the completion the run waits for, as reported: a step on completion may go at once
        runner.observe(hub.status)
        for index in runner.poll():
            await _send(console, runner, index)
        await _sleep(console.clock, _sleep_s(console, runner))
