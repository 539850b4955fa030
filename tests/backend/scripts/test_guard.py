"""The run watcher's rules without the app (the app's: test_run_stop.py): the reason in the
operator's words for every origin, a step of the running run does not stop it, a step of a
run that is over is refused, and a handed-out step withdrawn reads "not sent yet"."""

from __future__ import annotations

from typing import Any

import pytest

from backend.commands.service import ORIGINS, Origin, SendOutcome, SendRequest
from backend.dives import Dives
from backend.mission_log.records import CommandRecord
from backend.scripts.guard import RunGuard, RunOver, stop_reason
from backend.scripts.operations import ScriptRunner
from backend.telemetry import TelemetryHub
from tests.backend.scripts.test_runner import runner

WORDS: dict[Origin, str] = {
    "api": "the operator sent a box orbit (command 7)",
    "ws": "the operator sent a box orbit (command 7)",
    "surface": "the operator sent a box orbit (command 7)",
    "retry": "the operator retried command 3: a box orbit (command 7)",
    "scenario": "the operator loaded a training scenario, which sent a box orbit (command 7)",
    "script": "a step of another script run sent a box orbit (command 7)",
    "cli": "the operator sent a box orbit from the command line (command 7)",
}


def record(pattern: str, command_id: int = 7) -> CommandRecord:
    fields: dict[str, Any] = {"id": command_id, "pattern": pattern}
    return CommandRecord.model_construct(**fields)


@pytest.mark.parametrize("origin", ORIGINS)
def test_the_reason_names_the_command_in_words(origin: Origin) -> None:
    request = SendRequest("box_orbit", {}, origin, retry_of=3 if origin == "retry" else None)
    assert stop_reason(request, record("box_orbit")) == WORDS[origin]
    surface = SendRequest("surface", {}, origin)
    if origin in ("api", "ws", "surface"):
        assert (
            stop_reason(surface, record("surface", 42)) == "the operator sent Surface (command 42)"
        )


class Host:
    """The console as the guard reads it, with no mission log."""

    def __init__(self, run: ScriptRunner | None) -> None:
        self.runner = run
        self.dives: Dives | None = None
        self.hub = TelemetryHub()


def test_another_command_stops_the_run_and_a_late_step_is_refused() -> None:
    run = runner(start_s=0.0)
    guard = RunGuard(Host(run))
    assert run.poll(0.0) == [0]
    step = SendRequest("straight", {}, "script", kind="script")
    with guard.step(step, run):
        guard.admit(step)
        guard.sent(step, SendOutcome(record("straight", 1)))
    assert run.running
    circle = SendRequest("circle", {}, "api")
    guard.admit(circle)  # the operator's commands are never refused here
    guard.sent(circle, SendOutcome(record("circle", 2)))
    assert not run.running and run.reason == "the operator sent a circle (command 2)"
    late = SendRequest("lawnmower", {}, "script", kind="script")
    with guard.step(late, run), pytest.raises(RunOver) as refused:
        guard.admit(late)
    assert refused.value.status == 409
    assert "over (stopped: the operator sent a circle (command 2))" in str(refused.value)


def test_a_step_of_a_run_replaced_by_another_is_refused() -> None:
    old, new = runner(start_s=0.0), runner(start_s=0.0)
    host = Host(old)
    guard = RunGuard(host)
    host.runner = new
    stale = SendRequest("straight", {}, "script", kind="script")
    with guard.step(stale, old), pytest.raises(RunOver):
        guard.admit(stale)


def test_withdraw_leaves_a_handed_out_step_unsent_and_a_sent_one_as_it_was() -> None:
    r = runner(start_s=0.0)
    assert r.poll(0.0) == [0]
    r.stop("the operator sent Surface (command 9)")
    r.withdraw(0)
    st = r.state()
    assert st["steps"][0]["state"] == "pending" and st["steps"][0]["state_text"] == "not sent yet"
    assert st["steps"][0]["sent_s"] is None and st["step"] == 0
    assert st["summary"] == "stopped: the operator sent Surface (command 9)"
    sent = runner(start_s=0.0)
    assert sent.poll(0.0) == [0]
    sent.mark_sent(0)
    sent.withdraw(0)
    assert sent.step_state(0) == "sent"
