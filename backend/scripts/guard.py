"""A running mission script gives way to the operator: any other command ends the run.

The developers' guide: "a newer command or Surface is never undone by an older one". A
script's later steps were written before the operator pressed Surface (or sent a command, a
retry, a training scenario); sending them when they fall due would undo it. So the run's
watcher on the command service (:class:`RunGuard`, a :class:`SendWatcher` the console adds
once; the service tells it of every command on every path, so every caller gets the rule):

* a command that is **not a step of the running script** ends the run at once, before its
  first copy leaves: the run is ``stopped`` with the reason in the operator's words
  (:func:`stop_reason`: "the operator sent Surface (command 42)"), no later step is handed
  out, and the stop is an event of the mission log (``script_stopped``) and of ``/ws``;
* a step whose send began before that (handed out, not yet written) is refused when it
  reaches the service (:class:`RunOver`): nothing of it is written or sent. A step already
  written when the Surface came is the manager's: the Surface supersedes it, and none of its
  copies leaves after the Surface's first (:mod:`backend.commands.manager`).

A step is known by its request (the object the run hands to the service, registered with
:meth:`RunGuard.step`), not by its origin: only the run that sent it may send it.

With a fleet a run drives one vehicle (its steps name it): a command to another vehicle does
not concern it and leaves it running; one to its vehicle, or a Surface to all, ends it.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Protocol

from backend.commands.service import SendOutcome, SendRefused, SendRequest
from backend.commands.vehicles import ALL_VEHICLES
from backend.messages import EventMessage
from backend.mission_log.records import CommandRecord, log_event
from backend.mission_log.store import LogWriteError
from backend.telemetry import TelemetryHub

if TYPE_CHECKING:
    from backend.dives import Dives
    from backend.scripts.runner import ScriptRunner

logger = logging.getLogger("backend.scripts.guard")

#: The mission log's event kind of a run the operator's command ended.
STOPPED_EVENT = "script_stopped"


class RunHost(Protocol):
    """What the guard reads of the console: its run, its dives (the mission log) and ``/ws`` hub."""

    @property
    def runner(self) -> ScriptRunner | None: ...
    @property
    def dives(self) -> Dives | None: ...
    @property
    def hub(self) -> TelemetryHub: ...


class RunOver(SendRefused):
    """A step of a run that ended (the operator sent something else) before the step
    reached the service: not sent."""

    status = 409


def stop_reason(request: SendRequest, record: CommandRecord) -> str:
    """Why the run stopped, in the operator's words: ``the operator sent Surface (command
    42)``, ``the operator sent a circle (command 43)``, ``the operator retried command 40: a
    circle (command 44)``."""
    what = "Surface" if record.pattern == "surface" else f"a {record.pattern.replace('_', ' ')}"
    which = f"command {record.id}"
    if request.origin == "retry":
        return f"the operator retried command {request.retry_of}: {what} ({which})"
    if request.origin == "scenario":
        return f"the operator loaded a training scenario, which sent {what} ({which})"
    if request.origin == "script":
        return f"a step of another script run sent {what} ({which})"
    if request.origin == "cli":
        return f"the operator sent {what} from the command line ({which})"
    return f"the operator sent {what} ({which})"


class RunGuard:
    """The console's run watcher on the command service (see the module's docstring)."""

    def __init__(self, host: RunHost) -> None:
        self._host = host
        #: The steps on their way to the service: (the request, the run that sent it).
        self._steps: list[tuple[SendRequest, ScriptRunner]] = []

    @contextmanager
    def step(self, request: SendRequest, runner: ScriptRunner) -> Iterator[None]:
        """While the body sends ``request``, it is a step of ``runner`` (not a reason to
        stop it)."""
        entry = (request, runner)
        self._steps.append(entry)
        try:
            yield
        finally:
            self._steps.remove(entry)

    def _run_of(self, request: SendRequest) -> ScriptRunner | None:
        return next((run for r, run in self._steps if r is request), None)

    def admit(self, request: SendRequest) -> None:
        """Refuse a step of a run that is over, or not the console's run any more.

        Raises:
            RunOver: the step's run ended (its reason, in words).
        """
        run = self._run_of(request)
        if run is None or (run.running and run is self._host.runner):
            return
        why = f"{run.outcome}: {run.reason}" if run.reason else f"{run.outcome}"
        raise RunOver(f"not sent: the script run it belongs to is over ({why})")

    def sent(self, request: SendRequest, outcome: SendOutcome) -> None:
        """A command that is not a step of the running run ends it (and is logged)."""
        run = self._host.runner
        if run is None or not run.running or self._run_of(request) is run:
            return
        drives = run.script.steps[0].vehicle
        to = outcome.record.vehicle  # a fleet's record names its vehicle (none without one)
        if to is not None and request.vehicle != ALL_VEHICLES and to != drives:
            return  # a fleet's other vehicle: not this run's
        reason = stop_reason(request, outcome.record)
        run.stop(reason)  # first: nothing more is handed out, whatever the log does
        self._log(run, reason, request, outcome.record)

    def _log(
        self, run: ScriptRunner, reason: str, request: SendRequest, record: CommandRecord
    ) -> None:
        host = self._host
        if host.dives is None:
            return
        sent = [s["index"] + 1 for s in run.state()["steps"] if s["transmitted"]]
        data = {
            "script": run.script.name,
            "command": record.id,
            "origin": request.origin,
            "pattern": record.pattern,
            "steps_sent": sent,
        }
        detail = f"mission script {run.script.name!r} stopped: {reason}"
        try:
            event = host.dives.event(STOPPED_EVENT, detail, data)
        except LogWriteError as err:  # stopped all the same
            logger.error("%s, but it could not be logged: %s", detail, err)
            return
        logger.info("%s", detail)
        host.hub.publish(EventMessage(event=log_event(event)))


__all__ = ["STOPPED_EVENT", "RunGuard", "RunHost", "RunOver", "stop_reason"]
