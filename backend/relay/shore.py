"""The shore's end of the relay: a checked command written to the shared log's outbox, and the
answer of the console that holds the transmitter, waited for.

The command service of a console without a transmitter (``NEMESYS_TARGET=relay``) has run
its own checks, its gate (this console must be in control; Surface from anyone) and its
watchers when it hands the request here (:class:`RelaySender` is its
:class:`backend.commands.service.Relay`). :meth:`RelaySender.relay` writes the ``waiting`` row
(committed: a log that cannot be written refuses the send with 503, nothing written) and waits
up to ``relay_wait_s`` for the decision, woken by the row's notification (the transmitting
console's commit) and reading the row again at least every :data:`POLL_S`:

* ``taken``: the record the other console made of it (``origin`` ``relay:<this console>``, the
  operator who asked; a fleet's Surface to all: one per vehicle, their ids on the row),
  returned as a direct send's is (202); its states reach this console's pages live, as every
  record of another console does (:mod:`backend.control.sync`);
* ``refused``: :class:`RelayRefused`, with the other console's status (422 limits, 409 control
  or an override needed, 429 its rate limit, ...) and its reason and violations;
* no decision in time: the row is withdrawn (only if it still waits and no console is deciding
  it: ``FOR UPDATE SKIP LOCKED``) and :class:`RelayNoAnswer` (504) says nothing was sent; a row
  being decided at that moment is waited for a little longer (:data:`GRACE_S`).

A console killed while it waits leaves the row ``waiting``: the transmitting console sends it
once when it finds it (unless it waited longer than that console's ``relay_max_age_s``), and
this console, started again, neither withdraws nor writes it again.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
from collections.abc import Mapping
from typing import Any, Final

from backend.commands.checks import SendViolation
from backend.commands.policy import Accepted, key
from backend.commands.refusals import OverrideNeeded
from backend.commands.service import SendRefused, SendRequest
from backend.mission_log import outbox
from backend.mission_log.outbox import OutboxRow
from backend.mission_log.records import CommandRecord, command_record
from backend.mission_log.store import LogWriteError, MissionLog
from vehicle_contract.fleet import SINGLE_VEHICLE

logger = logging.getLogger("backend.relay")

#: The row is read again at least this often while waiting (s), notification or not.
POLL_S: Final = 0.25
#: How much longer a row another console is deciding at the deadline is waited for (s).
GRACE_S: Final = 5.0


#: How many commands' refusals :attr:`RelaySender._shown` keeps (the newest).
SHOWN_KEPT: Final = 32


class RelayRefused(SendRefused):
    """The console holding the transmitter refused the relayed command: its ``status``,
    reason and violations (nothing was sent)."""

    def __init__(
        self, status: int, message: str, violations: tuple[SendViolation, ...] = ()
    ) -> None:
        super().__init__(message, violations)
        self.status = status


class RelayNoAnswer(SendRefused):
    """No console holding the transmitter decided within the wait: the row was withdrawn,
    nothing was sent."""

    status = 504


class RelaySender:
    """This console's relay (see the module's doc): ``console`` and ``operator`` are this
    console's, ``wait_s`` the settings' ``relay_wait_s``."""

    def __init__(self, log: MissionLog, console: str, operator: str, wait_s: float) -> None:
        self.log = log
        self.console = console
        self.operator = operator
        self.wait_s = wait_s
        self._waiting: dict[int, asyncio.Event] = {}
        #: The soft violations the transmitting console last refused a command for (shown to
        #: the operator with that refusal), by the command (vehicle, pattern, parameters).
        self._shown: dict[str, Accepted] = {}

    def notice(self, row_id: int) -> None:
        """Another console wrote outbox row ``row_id`` (a decision, perhaps on one of ours)."""
        event = self._waiting.get(row_id)
        if event is not None:
            event.set()

    async def relay(self, request: SendRequest, accepted: Accepted) -> tuple[CommandRecord, ...]:
        """Write ``request`` to the outbox and wait for the answer (see the module's doc): the
        records the other console made (one; a Surface to all: one per vehicle).
        ``accepted``: what this console's checks found and its operator overrode; with an
        override, also what the transmitting console refused this same command for lately
        (its own limits: the operator was shown them and sent again with override).

        Raises:
            RelayRefused: the other console's refusal. RelayNoAnswer: none in time (504).
            LogWriteError: the row cannot be written (nothing sent), or, once written, the
                log cannot be read for the answer (the row may still be sent: its record
                then shows in the log).
        """
        surface = request.pattern == "surface"
        vehicle = getattr(request, "vehicle", None) or SINGLE_VEHICLE
        what = _command_key(vehicle, request.pattern, request.params)
        if request.override:
            accepted |= self._shown.get(what, frozenset())
        row = outbox.put(
            self.log,
            console=self.console,
            operator=self.operator,
            vehicle=vehicle,
            origin=request.origin,
            kind="surface" if surface else request.kind,
            pattern=request.pattern,
            params=request.params,
            override=request.override,
            copies=request.copies,
            retry_of=request.retry_of,
            accepted=accepted,
        )
        logger.info("%s relayed as outbox row %d", request.pattern, row.id)
        event = self._waiting[row.id] = asyncio.Event()
        try:
            return await self._answer(row.id, event)
        except RelayRefused as err:
            if err.status == OverrideNeeded.status and err.violations:  # shown to the operator
                self._shown.pop(what, None)
                self._shown[what] = frozenset(key(v) for v in err.violations)
                while len(self._shown) > SHOWN_KEPT:  # the oldest go
                    del self._shown[next(iter(self._shown))]
            raise
        except LogWriteError as err:
            err.outcome = (
                f"outbox row {row.id} was written: whether it was sent shows in the log once "
                "it can be read"
            )
            raise
        finally:
            del self._waiting[row.id]

    async def _answer(self, row_id: int, event: asyncio.Event) -> tuple[CommandRecord, ...]:
        loop = asyncio.get_running_loop()
        deadline = loop.time() + self.wait_s
        grace = deadline + GRACE_S
        while True:
            row = outbox.get(self.log, row_id)
            assert row is not None, f"outbox row {row_id} vanished"
            if row.state != "waiting":
                return self._decided(row)
            now = loop.time()
            if now >= deadline:
                why = f"no console holding the transmitter answered within {self.wait_s:g} s"
                if outbox.withdraw(self.log, row_id, self.console, why):
                    raise RelayNoAnswer(f"{why}: withdrawn (outbox row {row_id}), nothing was sent")
                if now >= grace:  # held by a console deciding it all this time
                    raise RelayNoAnswer(
                        f"{why}; one is deciding it now (outbox row {row_id}): if it is sent, "
                        "its record shows in the log"
                    )
            wait = min(POLL_S, max(deadline - now, 0.0) or POLL_S)
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(event.wait(), wait)
            event.clear()

    def _decided(self, row: OutboxRow) -> tuple[CommandRecord, ...]:
        if row.state == "taken":
            assert row.command_id is not None
            ids = [row.command_id]
            if isinstance(row.detail, dict) and isinstance(row.detail.get("commands"), list):
                ids = [int(i) for i in row.detail["commands"]]  # a Surface to all's
            made = []
            for command_id in ids:
                got = self.log.command(command_id)
                assert got is not None, f"outbox row {row.id} names no command {command_id}"
                made.append(command_record(got))
            return tuple(made)
        if row.state == "withdrawn":
            raise RelayNoAnswer(f"withdrawn (outbox row {row.id}): {row.reason}; nothing was sent")
        message, violations = refusal_of(row.detail, row.reason or "refused")
        raise RelayRefused(
            row.status or 422,
            f"console {row.decided_by!r} (holding the transmitter) refused it: {message}",
            violations,
        )


def _command_key(vehicle: str, pattern: str, params: Mapping[str, Any]) -> str:
    """One command, whatever its parameters' order."""
    return json.dumps([vehicle, pattern, dict(params)], sort_keys=True)


def refusal_of(detail: Any, reason: str) -> tuple[str, tuple[SendViolation, ...]]:
    """A refusal's words and violations from the row's ``detail`` (the refusal's JSON:
    :func:`backend.commands.service.refusal_detail`), else its ``reason``."""
    if not isinstance(detail, dict) or not isinstance(detail.get("violations"), list):
        return reason, ()
    violations = tuple(
        SendViolation(
            check=v["check"],
            param=v["param"],
            kind=v["kind"],
            message=v["message"],
            value=v["value"],
            limit=v["limit"],
            unit=v["unit"],
            allowed=v["allowed"],
            step=v.get("step"),
        )
        for v in detail["violations"]
        if isinstance(v, dict)
    )
    return str(detail.get("message", reason)), violations
