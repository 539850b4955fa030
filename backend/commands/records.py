"""The records side of command delivery: how a record's state is written, announced and
ended, and how a send's writes are committed together.
:class:`backend.commands.manager.CommandManager`
builds the delivery (copies, supersede rule, acknowledgements) on top of it."""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections import OrderedDict
from collections.abc import Iterator
from typing import Any

from pydantic import ValidationError

from backend.clock import Timer
from backend.commands.delivery import Delivery
from backend.commands.ledger import FrameLedger, Outcome
from backend.commands.lifecycle import Event, IllegalTransition, advance
from backend.messages import CommandMessage
from backend.mission_log.records import command_record
from backend.mission_log.store import LogWriteError, MissionLog
from backend.telemetry import TelemetryHub
from codec import Encoded

logger = logging.getLogger("backend.commands.manager")


class CommandRecords:
    """The records of the commands on their way: deliveries running, acknowledgements awaited,
    their timers and frames; every state change written, then announced."""

    def __init__(self, log: MissionLog, hub: TelemetryHub) -> None:
        self.log = log
        self.hub = hub
        #: Copies still going out, by record (a Surface to all: its records share one).
        self._live: dict[int, Delivery] = {}
        self._awaiting: OrderedDict[int, Encoded] = OrderedDict()  # id -> frame, oldest first
        self._timeouts: dict[int, Timer] = {}  # acknowledgement timeouts
        #: The vehicle of each record this manager began (a fleet's; absent: the first one).
        self._vehicle_of: dict[int, str] = {}
        #: Each vehicle's frames and their fate, by name (the manager fills it).
        self._ledgers: dict[str, FrameLedger] = {}
        self._held: list[dict[str, Any]] | None = None  # announcements awaiting a commit

    def _ledger_of(self, command_id: int) -> FrameLedger:
        """The ledger of the vehicle a record is for."""
        name = self._vehicle_of.get(command_id)
        if name is None:
            return next(iter(self._ledgers.values()))
        return self._ledgers[name]

    def _carries(self, d: Delivery) -> list[int]:
        """The records ``d`` still delivers (those no other event ended)."""
        return [cid for cid in d.members if self._live.get(cid) is d]

    def _end(self, command_id: int, event: Event, outcome: Outcome, **fields: Any) -> None:
        """The one way a record ends: its repetition stops, its timer goes, its frames are
        settled in the ledger and its terminal state is written."""
        d = self._live.pop(command_id, None)
        # a Surface to all goes on while it carries another vehicle's record
        alone = d is not None and not self._carries(d)
        if alone and d is not None and d.task is not None and d.task is not asyncio.current_task():
            d.task.cancel()
        self._awaiting.pop(command_id, None)
        handle = self._timeouts.pop(command_id, None)
        if handle is not None:
            handle.cancel()
        self._ledger_of(command_id).settle(command_id, outcome)
        record = self.log.command(command_id)
        assert record is not None
        try:
            state = advance(record["state"], event)
        except IllegalTransition as err:  # a bookkeeping bug: say so, keep the record
            logger.error("command %s: %s", command_id, err)
            return
        self._update(command_id, state=state, **fields)

    def _update(self, command_id: int, **fields: Any) -> dict[str, Any]:
        record = self.log.update_command(command_id, **fields)
        self._announce(record)
        return record

    def _announce(self, record: dict[str, Any]) -> None:
        if self._held is not None:
            self._held.append(record)
        else:
            try:
                message = CommandMessage(command=command_record(record))
            except ValidationError as err:  # a bookkeeping bug: say so, keep delivering
                logger.error("command %s not announced: %s", record.get("id"), err)
                return
            self.hub.publish(message)

    def atomic(self) -> contextlib.AbstractContextManager[None]:
        """A send and the caller's own writes committed together (the relay: the claim of an
        outbox row, the command record, the row marked taken): see :meth:`_atomic`. The body
        must not yield to the event loop (another task's writes would join the transaction)."""
        return self._atomic()

    @contextlib.contextmanager
    def _atomic(self) -> Iterator[None]:
        """The log writes inside are committed together (a crash leaves all or none) and
        announced after the commit. Inside another, it is part of that one. Rolled back (a
        write failed, or anything else raised), the deliveries begun inside are cancelled
        before their first copy."""
        if self._held is not None:  # nested: the outer one commits, announces, rolls back
            yield
            return
        held: list[dict[str, Any]] = []
        self._held = held
        live = dict(self._live)
        try:
            with self.log.transaction():
                yield
        except BaseException as err:
            self._held = None
            why = err if isinstance(err, LogWriteError) else LogWriteError(repr(err))
            self._rolled_back(live, why)
            raise
        finally:
            self._held = None
        for record in held:
            self._announce(record)

    def _rolled_back(self, live: dict[int, Delivery], err: LogWriteError) -> None:
        """The log writes of a send failed (none is committed): the deliveries it began are
        cancelled before their first copy (their tasks have not run yet), and those it
        superseded stay stopped: interrupted, if the log can still be written."""
        err.outcome = "nothing was transmitted"
        for cid, d in list(self._live.items()):
            if live.get(cid) is not d and d.task is not None:
                d.task.cancel()
                del self._live[cid]
        for cid in sorted(live.keys() - self._live.keys()):
            why = f"stopped by a send the mission log could not record ({err.reason})"
            logger.error("command %s: %s", cid, why)
            record = self.log.command(cid)
            with contextlib.suppress(LogWriteError, IllegalTransition):
                if record is not None:
                    state = advance(record["state"], Event.INTERRUPTED)
                    self._update(cid, state=state, reason=why)
