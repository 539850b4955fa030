"""The transmitting console's end of the relay: the outbox taken, each command checked again
and sent through this console's own command service.

On a shared (PostgreSQL) log every console with a transmitter runs a :class:`RelayWorker`. It
takes the waiting rows for its vehicles oldest first, when a row's notification wakes it and
at least every :data:`BEAT_S` (a sweep: a notification missed, rows left while it was down).
Each row is one transaction (:meth:`backend.commands.records.CommandRecords.atomic`):

1. the claim: ``SELECT ... FOR UPDATE SKIP LOCKED`` (:func:`backend.mission_log.outbox.claim`);
2. a row older than ``relay_max_age_s`` (the database's clock) is refused as stale (504);
3. else the command goes through :meth:`backend.commands.service.CommandService.send` as any
   other send here: this console's checks (its vehicle profile, its limits, where it knows the
   vehicle to be), the operator's override as the row gives it, the gate judging the console
   the command came from (it must be in control; a Surface from anyone passes), the rate
   limit; the record is written ``queued`` (``origin`` ``relay:<console>``, the operator who
   asked, this console as ``console``) and its delivery begun;
4. the row is marked ``taken`` with the record's id, or ``refused`` with the refusal's status,
   words and violations (and an event, kind ``relay``, that every console's pages get);
5. the commit: the record and the row's decision together, before the first copy can leave
   (the delivery's task runs only once this returns to the event loop; nothing in between
   yields). A rollback (a write that failed) cancels the delivery before its first copy and
   leaves the row waiting, for the next sweep.

So a console killed before the commit leaves the row waiting (its transaction dies with its
connection) and nothing sent; killed after, a ``taken`` row and a record the next start makes
``interrupted``, as any command on its way: never sent twice. A log out of reach (the gate's
503, a failed write) leaves the row waiting too.

Every :data:`BEAT_S` the worker also says in the ``transmitters`` table that this console holds
a transmitter, with its link's health and its vehicles, for the relaying consoles' pages
("relay via ...").

The rows it claims are its vehicles', ``"all"`` (a fleet's Surface to all: one frame to
address 0, one record per vehicle, all their ids kept on the row; and, for the vehicles other
transmitting consoles seen lately have, one waiting Surface row each, written in the same
transaction, so a Surface to all from a relaying console reaches every ship's vehicles),
and, once a row waited :data:`FOREIGN_AFTER_S`, any other vehicle's that no other transmitting
console seen lately says it has: checked here as any row, the service refuses it naming this
console's vehicles (a relaying console with another fleet is told so, never left to time out).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Final, Literal

from backend.commands.delivery import RateLimited
from backend.commands.manager import CommandManager
from backend.commands.service import (
    ORIGINS,
    CommandService,
    Origin,
    Relayed,
    SendRefused,
    SendRequest,
    refusal_detail,
)
from backend.commands.vehicles import ALL_VEHICLES
from backend.dives import Dives
from backend.messages import EventMessage
from backend.mission_log import outbox
from backend.mission_log.outbox import OutboxRow
from backend.mission_log.records import log_event
from backend.mission_log.store import LogWriteError, MissionLog
from backend.relay.link import FRESH_S
from backend.telemetry import TelemetryHub
from codec import CodecError
from planner import PlanError

logger = logging.getLogger("backend.relay")

#: The worker's beat (s): it sweeps the outbox and says it holds a transmitter this often.
BEAT_S: Final = 1.0
#: Rows taken in one go before the worker looks at the clock again.
ROUND_MAX: Final = 20
#: The events' kind (a relayed command refused).
EVENT_KIND: Final = "relay"
#: The status of a row refused as stale.
STALE_STATUS: Final = 504
#: A row for a vehicle this console does not have (nor any other transmitting console seen
#: within :data:`backend.relay.link.FRESH_S`) is taken, to be refused, once it waited this
#: long (s): a transmitting console that just started has said what it has by then.
FOREIGN_AFTER_S: Final = 2 * BEAT_S


@dataclass(frozen=True)
class Decision:
    """What the worker did with one row."""

    row: int
    state: Literal["taken", "refused"]
    command_id: int | None = None
    status: int | None = None
    reason: str | None = None
    #: A refusal's JSON when the checks refused (its violations).
    detail: Any = None
    #: Every record it made (a Surface to all: one per vehicle, ``command_id`` the first).
    command_ids: tuple[int, ...] = ()


class RelayWorker:
    """The outbox worker of console ``console`` (see the module's doc). ``health``: this
    console's link health now, as JSON (what the relaying consoles show)."""

    def __init__(
        self,
        log: MissionLog,
        service: CommandService,
        manager: CommandManager,
        dives: Dives,
        hub: TelemetryHub,
        *,
        console: str,
        vehicles: tuple[str, ...],
        target: str,
        max_age_s: float,
        health: Callable[[], Mapping[str, Any]],
    ) -> None:
        self.log = log
        self.service = service
        self.manager = manager
        self.dives = dives
        self.hub = hub
        self.console = console
        self.vehicles = vehicles
        self.target = target
        self.max_age_s = max_age_s
        self.health = health
        self._wake = asyncio.Event()
        self._beat_at: float | None = None
        #: Every decision, in order (for the tests and the bench).
        self.decisions: list[Decision] = []

    def wake(self, _row_id: int) -> None:
        """A row was written (another console's notification): look now."""
        self._wake.set()

    async def run(self) -> None:
        """Beat and sweep until cancelled (a failure is said, and tried again)."""
        while True:
            now = time.monotonic()
            if self._beat_at is None or now - self._beat_at >= BEAT_S:
                self._beat_at = now
                self.beat()
            await self.take_waiting()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._wake.wait(), BEAT_S)
            self._wake.clear()

    def beat(self) -> None:
        """Say this console holds a transmitter, with its link's health (a failure is said)."""
        try:
            outbox.beat_transmitter(self.log, self.console, self.target, self.health())
        except LogWriteError as err:
            logger.warning("the transmitter's presence not written: %s", err)

    async def take_waiting(self) -> list[Decision]:
        """Take the rows waiting now (at most :data:`ROUND_MAX`), oldest first."""
        done: list[Decision] = []
        try:
            others = self.others()
        except LogWriteError as err:
            logger.warning("the relay's outbox not taken from: %s", err)
            return done
        while len(done) < ROUND_MAX:
            try:
                decision = await self.take_one(others)
            except LogWriteError as err:  # rolled back: the row waits for the next sweep
                logger.warning("the relay's outbox not taken from: %s", err)
                break
            if decision is None:
                break
            done.append(decision)
        return done

    def others(self) -> tuple[str, ...]:
        """The vehicles the other transmitting consoles seen lately say they have (their rows
        are theirs, never refused here).

        Raises:
            LogWriteError: the log could not be read.
        """
        found, now_s = outbox.transmitters(self.log)
        names: set[str] = set()
        for t in found:
            said = t.health.get("vehicles")
            if t.console != self.console and now_s - t.seen_s <= FRESH_S and isinstance(said, list):
                names.update(str(n) for n in said)
        return tuple(sorted(names - {*self.vehicles, ALL_VEHICLES}))

    async def take_one(self, others: tuple[str, ...] = ()) -> Decision | None:
        """Claim, check, record and decide one row in one transaction (the module's doc);
        None: no row waits. ``others``: :meth:`others`.

        Raises:
            LogWriteError: the log could not be read or written (rolled back, the row still
                waits, nothing sent).
        """
        event: dict[str, Any] | None = None
        with self.manager.atomic():
            got = outbox.claim(
                self.log,
                (*self.vehicles, ALL_VEHICLES),
                foreign_after_s=FOREIGN_AFTER_S,
                others=others,
            )
            if got is None:
                return None
            row, now_s = got
            decision = await self._decide(row, now_s - row.created_s)
            if decision.state == "taken":
                assert decision.command_id is not None
                handed = self._hand_on(row, others) if row.vehicle == ALL_VEHICLES else ()
                outbox.taken(
                    self.log,
                    row.id,
                    decision.command_id,
                    self.console,
                    decision.command_ids,
                    handed_on=handed,
                )
            else:
                assert decision.status is not None and decision.reason is not None
                outbox.refused(
                    self.log,
                    row.id,
                    self.console,
                    decision.status,
                    decision.reason,
                    decision.detail,
                )
                event = self.dives.event(EVENT_KIND, self._told(row, decision), self._data(row))
        self.decisions.append(decision)
        if event is not None:
            logger.warning("%s", event["detail"])
            self.hub.publish(EventMessage(event=log_event(event)))
        else:
            logger.info("outbox row %d sent as command %s", row.id, decision.command_id)
        return decision

    def _hand_on(self, row: OutboxRow, others: tuple[str, ...]) -> tuple[int, ...]:
        """A Surface to all reaches the vehicles of every transmitting console, not only this
        one's: one waiting row per vehicle the others have (:meth:`others`), as the relaying
        console asked it, written in this transaction; each is taken by the console that has
        that vehicle. Returns the rows' ids."""
        return tuple(
            outbox.put(
                self.log,
                console=row.console,
                operator=row.operator,
                vehicle=name,
                origin=row.origin,
                kind=row.kind,
                pattern=row.pattern,
                params=row.params,
                override=False,
                copies=row.copies,
                retry_of=None,
            ).id
            for name in others
        )

    async def _decide(self, row: OutboxRow, age_s: float) -> Decision:
        """The row through this console's command service (no yield to the event loop: the
        service's send does not wait for anything)."""
        if age_s > self.max_age_s:
            reason = (
                f"stale: it waited {age_s:.1f} s in the outbox, longer than the "
                f"{self.max_age_s:g} s a relayed command may (relay_max_age_s); never sent late, "
                "send it again"
            )
            return Decision(row.id, "refused", status=STALE_STATUS, reason=reason)
        try:
            outcome = await self.service.send(request_of(row))
        except SendRefused as err:
            detail = refusal_detail(err) if err.violations else None
            return Decision(row.id, "refused", status=err.status, reason=str(err), detail=detail)
        except (CodecError, PlanError) as err:
            return Decision(row.id, "refused", status=422, reason=str(err))
        except RateLimited as err:
            return Decision(row.id, "refused", status=429, reason=str(err))
        ids = tuple(r.id for r in outcome.records)
        return Decision(row.id, "taken", command_id=outcome.record.id, command_ids=ids)

    def _told(self, row: OutboxRow, d: Decision) -> str:
        what = "Surface" if row.pattern == "surface" else f"a {row.pattern}"
        return (
            f"{what} relayed by console {row.console!r} (operator {row.operator!r}) refused by "
            f"console {self.console!r}, holding the transmitter ({d.status}): {d.reason}"
        )

    @staticmethod
    def _data(row: OutboxRow) -> dict[str, Any]:
        return {"outbox": row.id, "console": row.console, "operator": row.operator}


def request_of(row: OutboxRow) -> SendRequest:
    """The outbox row as this console's send request (the shore's path kept as ``origin``;
    the record's will be ``relay:<console>``)."""
    origin: Origin = next((o for o in ORIGINS if o == row.origin), "api")
    kind: Literal["command", "script"] = "script" if row.kind == "script" else "command"
    return SendRequest(
        row.pattern,
        row.params,
        origin,
        override=row.override,
        # an override covers what its operator was shown (none said: nothing of ours)
        accepted=(row.accepted or frozenset()) if row.override else None,
        copies=row.copies,
        kind=kind,
        retry_of=row.retry_of,
        relayed=Relayed(row.console, row.operator, row.id),
        vehicle=row.vehicle,  # checked here as any request's (the single vehicle's name too)
    )
