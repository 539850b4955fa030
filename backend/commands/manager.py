"""Command delivery: copies spaced in time, one rule for superseding, acknowledgements and
timeouts. The states and their transitions are the table in :mod:`backend.commands.lifecycle`.

Every command is written to the mission log (``queued``) before anything is transmitted, and
every change is written before it is announced. A command goes out as ``copies`` frames spaced
``copy_interval_s`` apart (time diversity against bursts):

* on a **one-way** link (no acknowledgements) the number of copies is chosen from the link's
  bit-error rate to reach ``delivery_target`` (:func:`codec.copies_for`), and the command ends
  ``sent`` once they are out;
* on a **two-way** link one copy by default; it ends ``acknowledged`` / ``rejected`` by the
  vehicle's acknowledgement (matched by frame: :func:`station.transmit.ack_match`), or
  ``timed_out`` ``ack_timeout_s`` after its last copy.

**Superseding, the one rule.** A newer command, a Surface or a retry replaces every command
whose copies are still going out: they end ``superseded``, naming the newer record, and none of
their frames leaves after the newer one's first (frames leave one at a time, under one lock,
and a replaced command's turn is skipped). A Surface pressed while another is on its way joins
it (one record, more copies). Surface repeats every ``surface_repeat_s``: until acknowledged on
a two-way link; on a one-way link :data:`MIN_SURFACE_COPIES` times or more, enough for
:data:`SURFACE_DELIVERY_TARGET`, then it ends ``sent``. A training reset and shutdown stop
every repetition (``interrupted``).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable
from typing import Any

from backend.clock import SYSTEM_CLOCK, Clock
from backend.commands.delivery import (
    DAMAGE_REASONS,
    MIN_SURFACE_COPIES,
    SURFACE_DELIVERY_TARGET,
    Delivery,
    RateLimited,
    RateLimiter,
    best_match,
    delivery_kind,
    planned_copies,
)
from backend.commands.lifecycle import ON_ITS_WAY, Event, advance
from backend.commands.mirror import VehicleMirror
from backend.commands.records import CommandRecords
from backend.messages import VehicleMessage
from backend.mission_log.store import LogWriteError, MissionLog, now_iso
from backend.telemetry import TelemetryHub
from codec import Encoded, delivery_probability
from onboard.agent import command_json
from planner import Plan
from station.link import Link

logger = logging.getLogger("backend.commands.manager")

__all__ = ["MIN_SURFACE_COPIES", "SURFACE_DELIVERY_TARGET", "CommandManager", "RateLimited"]


class CommandManager(CommandRecords):
    """Owns transmissions, acknowledgements, timeouts, and the vehicle's mirror."""

    def __init__(
        self,
        log: MissionLog,
        link: Link,
        hub: TelemetryHub,
        *,
        dive: Callable[[], int],
        operator: str,
        ack_timeout_s: float,
        surface_repeat_s: float,
        max_sends_per_minute: int,
        copy_interval_s: float = 1.0,
        delivery_target: float = 0.999,
        link_ber: Callable[[], tuple[float, float]] = lambda: (1e-3, 0.0),
        link_delay_s: Callable[[], float] = lambda: 0.0,
        airtime_s: float = 100 / 36000,
        target: str | None = None,
        clock: Clock = SYSTEM_CLOCK,
    ) -> None:
        super().__init__(log, hub)
        #: Copy spacing, Surface repeats, acknowledgement timeouts and the rate limit run on
        #: it (a test's clock moves by hand: :mod:`backend.clock`).
        self.clock = clock
        self.link = link
        #: What the log records as the target (the settings' name for it, e.g. "sim").
        self.target = target or link.target
        self._dive = dive
        self.operator = operator
        self.ack_timeout_s = ack_timeout_s
        self.surface_repeat_s = surface_repeat_s
        self.copy_interval_s = copy_interval_s
        self.delivery_target = delivery_target
        #: (bit-error rate, whole-frame loss) the copies are chosen from.
        self.link_ber = link_ber
        self._link_delay_s = link_delay_s
        self.airtime_s = airtime_s
        self._rate = RateLimiter(max_sends_per_minute, clock)
        self._tx_lock = asyncio.Lock()
        self.last_ack_s: float | None = None  # arrival of the last acknowledgement (clock s)
        #: The command whose first copy left most recently (wire order), from the log at start.
        self.last_sent: dict[str, Any] | None = log.last_sent()
        self.vehicle = VehicleMirror(hub, dive)

    # --- the vehicle mirror, as the console reads it ---------------------------------------

    @property
    def mirror(self) -> Plan | None:
        return self.vehicle.plan

    @property
    def vehicle_active(self) -> dict[str, Any] | None:
        return self.vehicle.active

    @property
    def echo_mismatch(self) -> bool:
        return self.vehicle.echo_mismatch

    # --- how many copies -------------------------------------------------------------------

    def copies_now(self) -> int:
        """Copies a command gets on this link now (one on a two-way link)."""
        copies = planned_copies(
            "command", self.link.acknowledges, *self.link_ber(), self.delivery_target
        )
        assert copies is not None
        return copies

    def surface_copies_now(self) -> int | None:
        """Copies a Surface gets now; ``None``: until acknowledged (two-way link)."""
        return planned_copies(
            "surface", self.link.acknowledges, *self.link_ber(), self.delivery_target
        )

    # --- stopping ---------------------------------------------------------------------------

    async def close(self) -> None:
        """Shutdown: every repetition stops; what was on its way is ``interrupted``."""
        tasks = [d.task for d in self._live.values() if d.task is not None]
        self._stop_all("the console was shut down")
        for task in tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task

    def reset_vehicle(self) -> None:
        """The vehicle started afresh (training reset): every repetition stops, what was on
        its way is ``interrupted``, the mirror and the frame counts start again."""
        self._stop_all("the training vehicle was reset (a new dive)")
        self.vehicle.reset()
        self.ledger.reset()
        self.last_ack_s = None

    def _stop_all(self, why: str) -> None:
        for cid in [*self._live, *(c for c in self._awaiting if c not in self._live)]:
            try:
                self._end(cid, Event.INTERRUPTED, "sent", reason=why)
            except LogWriteError as err:  # stopped all the same; the log keeps its last state
                logger.error("command %s stopped (%s), but %s", cid, why, err)

    # --- sending ----------------------------------------------------------------------------

    async def submit(
        self,
        enc: Encoded,
        kind: str = "command",
        copies: int | None = None,
        *,
        origin: str = "api",
        retry_of: int | None = None,
        overrides: dict[str, Any] | None = None,
        operator: str | None = None,
    ) -> dict[str, Any]:
        """Log the command (queued) with the values asked for (``enc.snaps``), then deliver it
        in the background, replacing whatever is still being repeated; returns the record.
        ``copies``: the operator's count (1..20), else chosen from the link. ``origin``,
        ``retry_of`` and ``overrides`` are written into the record as the command service
        gives them (:mod:`backend.commands.service` is the only caller in the console);
        ``operator``: who asked, when not this console's operator (a relayed command's).

        Raises:
            RateLimited: too many transmissions in the last minute (never for surface).
        """
        record_kind = kind
        # a surface frame is a Surface however it was sent (button, /api/commands, a script)
        kind = delivery_kind(kind, enc.command.pattern.name)
        if kind == "surface":
            joined = self._join_surface()
            if joined is not None:
                return joined
        else:
            self._rate.take()
        two_way = self.link.acknowledges
        if copies is None:
            copies = self.surface_copies_now() if kind == "surface" else self.copies_now()
        ber, _loss = self.link_ber()
        with self._atomic():  # the new record and what it supersedes, or nothing
            record = self.log.insert_command(
                self._dive(),
                {
                    "operator": operator or self.operator,
                    "target": self.target,
                    "kind": record_kind,
                    **command_json(enc.command),
                    "requested": {s.field: s.requested for s in enc.snaps},
                    "bits": enc.frame.bits,
                    "hex": enc.frame.hex,
                    "copies": copies,
                    "ber": ber,
                    "two_way": two_way,
                    "origin": origin,
                    "retry_of": retry_of,
                    "overrides": overrides,
                },
            )
            self._announce(record)
            self._begin(record["id"], enc, kind, copies)
        return record

    def _join_surface(self) -> dict[str, Any] | None:
        """A Surface pressed while another is on its way: the same record, sent again now,
        with its full count of copies to go."""
        pending = [d for d in self._live.values() if d.kind == "surface"]
        if not pending:
            return None
        d = pending[-1]
        record = self.log.command(d.command_id)
        assert record is not None
        if d.copies is not None:
            more = d.tried + (self.surface_copies_now() or MIN_SURFACE_COPIES) - d.copies
            try:  # logged first: no copy leaves that the log does not count
                record = self._update(d.command_id, copies=(record["copies"] or 0) + more)
            except LogWriteError as err:
                err.outcome = "no copy was added to the Surface already on its way"
                raise
            d.copies += more
        d.wake.set()
        return record

    def _begin(self, command_id: int, enc: Encoded, kind: str, copies: int | None) -> None:
        for other in [c for c in self._live if c != command_id]:
            self._end(
                other,
                Event.SUPERSEDED,
                "sent",
                reason=f"superseded by command {command_id}",
                superseded_by=command_id,
            )
        # a record awaiting its acknowledgement from an earlier attempt starts afresh
        self._awaiting.pop(command_id, None)
        ber, loss = self.link_ber()
        d = Delivery(
            command_id,
            enc,
            kind,
            self.link.acknowledges,
            copies,
            self.surface_repeat_s if kind == "surface" else self.copy_interval_s,
            ber,
            loss,
        )
        self._live[command_id] = d
        d.task = asyncio.create_task(self._deliver(d), name=f"command {command_id}")

    async def _deliver(self, d: Delivery) -> None:
        while d.more():
            # shielded: a copy handed to the link is written down even if this is cancelled
            await asyncio.shield(self._send_copy(d))
            if self._live.get(d.command_id) is not d or not d.more():
                break
            # the next copy at the interval, or sooner when woken (a Surface pressed again)
            timer = self.clock.call_later(d.interval_s, d.wake.set)
            try:
                await d.wake.wait()
            finally:
                timer.cancel()
            d.wake.clear()
        if self._live.get(d.command_id) is d:
            try:
                self._copies_done(d)
            except LogWriteError as err:
                logger.error("command %s: its copies are out, but %s", d.command_id, err)

    async def _send_copy(self, d: Delivery) -> None:
        async with self._tx_lock:  # frames leave one at a time, in the order of the rule
            if self._live.get(d.command_id) is not d:
                return  # replaced while waiting its turn: nothing goes out
            d.tried += 1
            reason = await self.link.transmit(d.enc.frame)
            try:
                self._copy_out(d, reason)
            except LogWriteError as err:  # the copy is accounted for here; no more leave
                how = f"left at {now_iso()}" if reason is None else f"did not leave ({reason})"
                what = f"copy {d.tried} (frame {d.enc.frame.hex}) {how}"
                logger.error("command %s: %s, but %s: delivery stopped", d.command_id, what, err)
                if self._live.get(d.command_id) is d:
                    del self._live[d.command_id]

    def _copy_out(self, d: Delivery, reason: str | None) -> None:
        """Write down a copy handed to the link (``reason``: why it did not leave)."""
        cid = d.command_id
        record = self.log.command(cid)
        assert record is not None
        fields: dict[str, Any] = {"attempts": record["attempts"] + 1}
        if reason is not None:
            d.last_failure = reason
            self._update(cid, **fields, reason=f"copy {d.tried} did not leave: {reason}")
            return
        live = self._live.get(cid) is d
        sent = record["copies_sent"] + 1
        stamp = now_iso()
        fields.update(
            copies_sent=sent,
            p_delivered=delivery_probability(d.ber, sent, loss=d.loss),
            sent_at=stamp,
        )
        first = record["first_sent_at"] is None
        if first:  # wire order: "last sent", the list and the CSV follow the first copy out
            fields["first_sent_at"] = stamp
        if live and record["state"] in ON_ITS_WAY:
            fields.update(state=advance(record["state"], Event.COPY_SENT), reason=None)
        self.ledger.frame_out(cid, answer_expected=live and d.two_way)
        if first:
            self.last_sent = {"id": cid, **command_json(d.enc.command)}
        self._update(cid, **fields)
        if live and d.two_way:
            self._await_ack(cid, d.enc)

    def _await_ack(self, command_id: int, enc: Encoded) -> None:
        self._awaiting[command_id] = enc
        self._awaiting.move_to_end(command_id)
        old = self._timeouts.pop(command_id, None)
        if old is not None:
            old.cancel()
        wait = self.ack_timeout_s + self.airtime_s + self._link_delay_s()
        self._timeouts[command_id] = self.clock.call_later(
            wait, lambda: self._timed_out(command_id)
        )

    def _copies_done(self, d: Delivery) -> None:
        cid = d.command_id
        del self._live[cid]
        record = self.log.command(cid)
        assert record is not None
        if record["state"] == "queued":  # not one copy left in this attempt
            self._end(cid, Event.NO_COPY_LEFT, "sent", reason=f"not sent: {d.last_failure}")
        elif record["state"] == "transmitted" and not d.two_way:
            self._end(cid, Event.COPIES_OUT, "sent")
        # two-way: the acknowledgement or the timeout of the last copy ends it

    def _timed_out(self, command_id: int) -> None:
        self._timeouts.pop(command_id, None)
        if command_id in self._live:  # copies still going out (a Surface until acknowledged)
            self.ledger.settle(command_id, "timed_out")
            return
        if command_id in self._awaiting:
            wait = self.ack_timeout_s + self.airtime_s + self._link_delay_s()
            self._end(
                command_id,
                Event.ACK_TIMEOUT,
                "timed_out",
                reason=f"no acknowledgement within {wait:.1f} s of the last copy: the frame "
                "was lost or damaged, the vehicle is out of range, or it did not answer",
            )

    # --- acknowledgements -------------------------------------------------------------------

    def on_mission(self, ack: dict[str, Any]) -> None:
        """An acknowledgement from the vehicle: settle the command it answers."""
        self.last_ack_s = self.clock.monotonic()
        self.ledger.channel.observe(ack)  # every acknowledgement is a frame the vehicle heard
        command_id = best_match(self._awaiting, ack)
        record = None
        if command_id is not None:
            accepted = ack.get("outcome") == "accepted"
            d = self._live.get(command_id)
            damaged = not accepted and ack.get("reason") in DAMAGE_REASONS
            if damaged and d is not None and d.more():
                # the channel damaged this copy; the next one may get through
                self.ledger.settle(command_id, "rejected")
                self._update(
                    command_id,
                    ack=ack,
                    reason=f"a copy arrived damaged ({ack.get('reason')}); more copies follow",
                )
            else:
                self._end(
                    command_id,
                    Event.ACCEPTED if accepted else Event.REJECTED,
                    "acknowledged" if accepted else "rejected",
                    acked_at=now_iso(),
                    ack=ack,
                    reason=None if accepted else f"{ack.get('reason')}: {ack.get('detail')}",
                )
                record = self.log.command(command_id)
        self.vehicle.on_ack(ack, record)
        self.hub.publish(
            VehicleMessage(active=self.vehicle.active, echo_mismatch=self.echo_mismatch)
        )
