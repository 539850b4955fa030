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

**A fleet on one link** (:mod:`backend.commands.vehicles`): every command names its vehicle,
and its frame carries that vehicle's address. The one transmitter sends a frame at a time
(:class:`backend.commands.airtime.TransmitTurns`): each command's copies keep their spacing,
so different vehicles' copies interleave, and a Surface's copy goes first among those due.
The supersede rule holds per vehicle: a newer command for one vehicle replaces only that
vehicle's commands still going out. A Surface to all (one address-0 frame, one record per
vehicle) replaces every vehicle's; a later command for one vehicle ends that vehicle's record
of it, and the Surface's remaining copies go on addressed to each other vehicle alone (an
address-0 copy would reach that vehicle after its newer command's first).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

from backend.clock import SYSTEM_CLOCK, Clock
from backend.commands.airtime import IN_TURN, SURFACE_FIRST, TransmitTurns
from backend.commands.copies import OnTheWay
from backend.commands.delivery import (
    MIN_SURFACE_COPIES,
    SURFACE_DELIVERY_TARGET,
    Delivery,
    RateLimited,
    RateLimiter,
    delivery_kind,
)
from backend.commands.lifecycle import Event
from backend.commands.mirror import VehicleMirror
from backend.commands.supersede import Superseding
from backend.commands.vehicles import ALL_VEHICLES, SINGLE_VEHICLE, Addressee
from backend.mission_log.store import LogWriteError, MissionLog, now_iso
from backend.telemetry import TelemetryHub
from codec import Encoded
from onboard.agent import command_json
from station.link import Link

logger = logging.getLogger("backend.commands.manager")

__all__ = [
    "MIN_SURFACE_COPIES",
    "SURFACE_DELIVERY_TARGET",
    "CommandManager",
    "FleetMember",
    "OnTheWay",
    "RateLimited",
]


class FleetMember(NamedTuple):
    """A fleet's vehicle as the console hands it to the manager: its name and address, the
    link it reports back over and the hub holding its status (its echo check reads it)."""

    name: str
    address: int
    link: Link
    hub: TelemetryHub


class CommandManager(Superseding):
    """Owns transmissions, acknowledgements, timeouts, and each vehicle's mirror."""

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
        fleet: Sequence[FleetMember] = (),
        link_ber_of: Callable[[str], tuple[float, float]] | None = None,
    ) -> None:
        """``fleet``: the vehicles of a fleet on ``link`` (its one transmitter), each
        addressed; none: the single vehicle, on ``link`` (today's frames). ``link_ber_of``: a
        vehicle's (bit-error rate, loss) where it is its own (else ``link_ber``'s)."""
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
        self._link_ber_of = link_ber_of
        self._link_delay_s = link_delay_s
        #: A 100-bit frame's time on the link (s); an addressed frame's is in proportion.
        self.airtime_s = airtime_s
        self._rate = RateLimiter(max_sends_per_minute, clock)
        #: The one transmitter: a frame at a time, a Surface first (the tests look at it).
        self._tx_lock = TransmitTurns()
        self.fleet = bool(fleet)
        if fleet:
            self.vehicles = {
                m.name: Addressee(
                    m.name,
                    m.address,
                    m.link,
                    VehicleMirror(m.hub, dive),
                    last_sent=log.last_sent(vehicle=m.name),
                )
                for m in fleet
            }
        else:
            single = Addressee(
                SINGLE_VEHICLE, None, link, VehicleMirror(hub, dive), last_sent=log.last_sent()
            )
            self.vehicles = {SINGLE_VEHICLE: single}
        self._ledgers = {name: v.ledger for name, v in self.vehicles.items()}

    # --- stopping ---------------------------------------------------------------------------

    async def close(self) -> None:
        """Shutdown: every repetition stops; what was on its way is ``interrupted``."""
        tasks = [d.task for d in self._deliveries() if d.task is not None]
        self._stop_all("the console was shut down")
        for task in tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task

    def reset_vehicle(self) -> None:
        """The vehicle started afresh (training reset): every repetition stops, what was on
        its way is ``interrupted``, the mirror and the frame counts start again."""
        self._stop_all("the training vehicle was reset (a new dive)")
        for v in self.vehicles.values():
            v.mirror.reset()
            v.ledger.reset()
            v.last_ack_s = None

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
        vehicle: str | None = None,
    ) -> dict[str, Any]:
        """:meth:`submit_all` for one vehicle: its record."""
        records = await self.submit_all(
            enc,
            kind,
            copies,
            origin=origin,
            retry_of=retry_of,
            overrides=overrides,
            operator=operator,
            vehicle=vehicle,
        )
        return records[0]

    async def submit_all(
        self,
        enc: Encoded,
        kind: str = "command",
        copies: int | None = None,
        *,
        origin: str = "api",
        retry_of: int | None = None,
        overrides: dict[str, Any] | None = None,
        operator: str | None = None,
        vehicle: str | None = None,
    ) -> list[dict[str, Any]]:
        """Log the command (queued) with the values asked for (``enc.snaps``), then deliver it
        in the background, replacing whatever is still being repeated to its vehicle; returns
        the records (one; a Surface to all: one per vehicle). ``enc``'s frame is the one sent
        (addressed to ``vehicle`` in a fleet: the command service makes it). ``vehicle``: the
        name (None: the single vehicle; :data:`ALL_VEHICLES`: a fleet's Surface to all).
        ``copies``: the operator's count (1..20), else chosen from the link. ``origin``,
        ``retry_of`` and ``overrides`` are written into the record as the command service
        gives them (:mod:`backend.commands.service` is the only caller in the console);
        ``operator``: who asked, when not this console's operator (a relayed command's).

        Raises:
            RateLimited: too many transmissions in the last minute (never for surface).
            KeyError: a vehicle this manager does not deliver to.
            ValueError: anything but a Surface to all vehicles.
        """
        record_kind = kind
        # a surface frame is a Surface however it was sent (button, /api/commands, a script)
        kind = delivery_kind(kind, enc.command.pattern.name)
        to_all = vehicle == ALL_VEHICLES
        if to_all and kind != "surface":
            raise ValueError(f"only Surface goes to {ALL_VEHICLES!r} vehicles")
        names = list(self.vehicles) if to_all else [self.addressee(vehicle).name]
        if kind == "surface":
            joined = self._join_surface(vehicle)
            if joined:
                return joined
        else:
            self._rate.take()
        if copies is None:
            if kind == "surface":
                copies = self.surface_copies_now(vehicle)
            else:
                copies = self.copies_now(vehicle)
        records: list[dict[str, Any]] = []
        with self._atomic():  # the new records and what they supersede, or nothing
            for name in names:
                v = self.vehicles[name]
                ber, _loss = self._ber(name)
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
                        "two_way": v.acknowledges,
                        "origin": origin,
                        "retry_of": retry_of,
                        "overrides": overrides,
                        **({"vehicle": name} if self.fleet else {}),
                    },
                )
                self._announce(record)
                records.append(record)
            ids = {r["id"]: n for r, n in zip(records, names, strict=True)}
            self._begin(ids, enc, kind, copies, to_all=to_all)
        return records

    def _begin(
        self, ids: dict[int, str], enc: Encoded, kind: str, copies: int | None, *, to_all: bool
    ) -> None:
        """Deliver the new records ``ids`` (id -> vehicle), one frame for them all (``to_all``:
        a Surface to all), after ending what they supersede (see the module's doc)."""
        newest = {name: cid for cid, name in ids.items()}
        self._supersede(
            lambda name: newest.get(name, min(ids)) if to_all or name in newest else None,
            "",
            f"command {min(ids)} went to {', '.join(newest)}",
        )
        self._vehicle_of.update(ids)
        members = {}
        for cid in ids:
            # a record awaiting its acknowledgement from an earlier attempt starts afresh
            self._awaiting.pop(cid, None)
            members[cid] = self.vehicles[ids[cid]].acknowledges
        cid = min(ids)
        ber, loss = self._ber(ids[cid])
        d = Delivery(
            cid,
            enc,
            kind,
            all(members.values()),
            copies,
            self.surface_repeat_s if kind == "surface" else self.copy_interval_s,
            ber,
            loss,
            members=members,
            to_all=to_all,
            next_s=self.clock.monotonic(),
        )
        for cid in ids:
            self._live[cid] = d
        self._start(d)

    def _start(self, d: Delivery) -> None:
        d.task = asyncio.create_task(self._deliver(d), name=f"command {d.command_id}")

    async def _deliver(self, d: Delivery) -> None:
        while d.more():
            # shielded: a copy handed to the link is written down even if this is cancelled
            await asyncio.shield(self._send_copy(d))
            if not self._carries(d) or not d.more():
                break
            # the next copy at the interval, or sooner when woken (a Surface pressed again)
            d.next_s = self.clock.monotonic() + d.interval_s
            timer = self.clock.call_later(d.interval_s, d.wake.set)
            try:
                await d.wake.wait()
            finally:
                timer.cancel()
            d.wake.clear()
        if self._carries(d):
            try:
                self._copies_done(d)
            except LogWriteError as err:
                logger.error("command %s: its copies are out, but %s", d.command_id, err)

    async def _send_copy(self, d: Delivery) -> None:
        turn = SURFACE_FIRST if d.kind == "surface" else IN_TURN
        async with self._tx_lock.turn(turn):  # frames leave one at a time, by the rule
            carried = self._carries(d)
            if not carried:
                return  # replaced while waiting its turn: nothing goes out
            d.tried += 1
            reason = await self.link.transmit(d.enc.frame)
            try:
                for cid in carried:
                    self._copy_out(d, cid, reason)
            except LogWriteError as err:  # the copy is accounted for here; no more leave
                how = f"left at {now_iso()}" if reason is None else f"did not leave ({reason})"
                what = f"copy {d.tried} (frame {d.enc.frame.hex}) {how}"
                logger.error("command %s: %s, but %s: delivery stopped", carried[0], what, err)
                for cid in carried:
                    if self._live.get(cid) is d:
                        del self._live[cid]
