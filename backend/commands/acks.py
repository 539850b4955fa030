"""The answers side of command delivery: each copy written down as it leaves, the wait for a
vehicle's acknowledgement, its timeout, and the acknowledgement itself, matched among the
records of the vehicle that sent it. :class:`backend.commands.manager.CommandManager` builds
the sending (copies, the supersede rule, the one transmitter) on top of it.

A fleet's vehicles answer each for itself (its own link, :mod:`backend.commands.vehicles`). A
vehicle that heard a frame addressed to another answers ``other_vehicle``: that says what it
runs (its echo) and nothing of any of its commands, so it settles none.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from typing import Any

from backend.clock import Clock
from backend.commands.delivery import DAMAGE_REASONS, Delivery, best_match
from backend.commands.ledger import FrameLedger
from backend.commands.lifecycle import ON_ITS_WAY, Event, advance
from backend.commands.mirror import VehicleMirror
from backend.commands.records import CommandRecords
from backend.commands.vehicles import Addressee
from backend.messages import VehicleMessage, for_vehicle
from backend.mission_log.store import now_iso
from codec import Encoded, RejectReason, delivery_probability
from onboard.agent import command_json
from planner import Plan

logger = logging.getLogger("backend.commands.manager")

#: An acknowledgement from a fleet's vehicle that heard a frame for another.
OTHER_VEHICLE = RejectReason.OTHER_VEHICLE.value


class CommandAcks(CommandRecords):
    """Copies written down, acknowledgements awaited and taken, per vehicle."""

    clock: Clock
    ack_timeout_s: float
    airtime_s: float
    _link_delay_s: Callable[[], float]
    #: The vehicles delivered to, by name (the first: the single vehicle, or the fleet's first).
    vehicles: dict[str, Addressee]
    #: Frames are addressed (a fleet), and records and news name their vehicle.
    fleet: bool

    def addressee(self, name: str | None) -> Addressee:
        """The vehicle ``name`` (None: the first, the single vehicle's)."""
        if name is None:
            return next(iter(self.vehicles.values()))
        return self.vehicles[name]

    # --- the single vehicle (a fleet's first), as the console has always read it ----------

    @property
    def vehicle(self) -> VehicleMirror:
        return self.addressee(None).mirror

    @property
    def ledger(self) -> FrameLedger:
        return self.addressee(None).ledger

    @property
    def last_sent(self) -> dict[str, Any] | None:
        """The command whose first copy left most recently (wire order), from the log at
        start (a fleet: the first vehicle's; each vehicle's is its :class:`Addressee`'s)."""
        return self.addressee(None).last_sent

    @property
    def last_ack_s(self) -> float | None:
        """Arrival of the last acknowledgement (clock s)."""
        return self.addressee(None).last_ack_s

    @property
    def mirror(self) -> Plan | None:
        return self.vehicle.plan

    @property
    def vehicle_active(self) -> dict[str, Any] | None:
        return self.vehicle.active

    @property
    def echo_mismatch(self) -> bool:
        return self.vehicle.echo_mismatch

    def _deliveries(self) -> list[Delivery]:
        """Every delivery still going out, oldest first, each once."""
        return list({id(d): d for d in self._live.values()}.values())

    # --- a copy out -------------------------------------------------------------------------

    def _copy_out(self, d: Delivery, cid: int, reason: str | None) -> None:
        """Write down a copy of record ``cid`` handed to the link (``reason``: why it did not
        leave)."""
        record = self.log.command(cid)
        assert record is not None
        fields: dict[str, Any] = {"attempts": record["attempts"] + 1}
        if reason is not None:
            d.last_failure = reason
            self._update(cid, **fields, reason=f"copy {d.tried} did not leave: {reason}")
            return
        live = self._live.get(cid) is d
        two_way = d.members.get(cid, d.two_way)
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
        self._ledger_of(cid).frame_out(cid, answer_expected=live and two_way)
        if first:
            vehicle = self.addressee(self._vehicle_of.get(cid))
            vehicle.last_sent = {"id": cid, **command_json(d.enc.command)}
        self._update(cid, **fields)
        if live and two_way:
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
        for cid in self._carries(d):
            del self._live[cid]
            record = self.log.command(cid)
            assert record is not None
            if record["state"] == "queued":  # not one copy left in this attempt
                self._end(cid, Event.NO_COPY_LEFT, "sent", reason=f"not sent: {d.last_failure}")
            elif record["state"] == "transmitted" and not d.members.get(cid, d.two_way):
                self._end(cid, Event.COPIES_OUT, "sent")
            # two-way: the acknowledgement or the timeout of the last copy ends it

    def _timed_out(self, command_id: int) -> None:
        self._timeouts.pop(command_id, None)
        if command_id in self._live:  # copies still going out (a Surface until acknowledged)
            self._ledger_of(command_id).settle(command_id, "timed_out")
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

    def _awaited_from(self, name: str) -> Mapping[int, Encoded]:
        """The records of vehicle ``name`` awaiting an acknowledgement, oldest first."""
        if len(self.vehicles) == 1:
            return self._awaiting
        first = next(iter(self.vehicles))
        return {
            cid: enc
            for cid, enc in self._awaiting.items()
            if self._vehicle_of.get(cid, first) == name
        }

    def on_mission(self, ack: dict[str, Any], vehicle: str | None = None) -> None:
        """An acknowledgement from ``vehicle`` (None: the single vehicle): settle the command
        of that vehicle's it answers."""
        v = self.addressee(vehicle)
        v.last_ack_s = self.clock.monotonic()
        v.ledger.channel.observe(ack)  # every acknowledgement is a frame the vehicle heard
        record = None
        misaddressed = ack.get("outcome") == "rejected" and ack.get("reason") == OTHER_VEHICLE
        command_id = None if misaddressed else best_match(self._awaited_from(v.name), ack)
        if command_id is not None:
            accepted = ack.get("outcome") == "accepted"
            d = self._live.get(command_id)
            damaged = not accepted and ack.get("reason") in DAMAGE_REASONS
            if damaged and d is not None and d.more():
                # the channel damaged this copy; the next one may get through
                self._ledger_of(command_id).settle(command_id, "rejected")
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
        v.mirror.on_ack(ack, record)
        message = VehicleMessage(active=v.mirror.active, echo_mismatch=v.mirror.echo_mismatch)
        self.hub.publish(for_vehicle(message, v.name if self.fleet else None))


__all__ = ["OTHER_VEHICLE", "CommandAcks"]
