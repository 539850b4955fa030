"""The supersede rule, written once for this console's own sends
(:meth:`backend.commands.manager.CommandManager.submit_all`) and another console's commands
seen on a shared log (:mod:`backend.control.sync`): a newer command to a vehicle ends every
older record to that vehicle whose copies are still going out, ``superseded``, and none of
their frames leaves after; a Surface to all that still carries other vehicles' records goes on
addressed to each of them alone, so its address-0 frame never reaches a vehicle after that
vehicle's newer command. :class:`backend.commands.manager.CommandManager` builds on it.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable

from backend.commands.copies import CopyPlanning
from backend.commands.delivery import Delivery
from backend.commands.lifecycle import Event
from codec import encode_frame

__all__ = ["Superseding"]

logger = logging.getLogger("backend.commands.manager")


class Superseding(CopyPlanning):
    """The supersede rule (see the module's doc)."""

    def _start(self, d: Delivery) -> None:
        """Begin delivering ``d``: its copies on the one transmitter (the manager's)."""
        raise NotImplementedError

    def superseded_elsewhere(self, by: int, console: str | None, vehicle: str | None) -> list[int]:
        """Another console sharing the log wrote command ``by`` (a Surface from anyone, or a
        command of the console now in control) to ``vehicle`` (a fleet's; None: without a
        fleet, the one vehicle): the one rule across consoles, every older command of this
        one to that vehicle whose copies are still going out ends ``superseded`` by it, and
        none of their frames leaves after (a Surface to all goes on for the other vehicles,
        addressed to each alone); returns their ids (LogWriteError: not all were written)."""
        return self._supersede(
            lambda name: by if vehicle is None or name == vehicle else None,
            f" from console {console!r}",
            f"command {by} of console {console!r} went to {vehicle}",
        )

    def _supersede(self, newer: Callable[[str], int | None], whence: str, why: str) -> list[int]:
        """The supersede rule, written once: every record still going out whose vehicle has a
        newer command (``newer(name)``: its id; None: none, or not newer) ends ``superseded``
        by it (``whence``: where it came from, in the reason); a Surface to all left carrying
        other vehicles' records goes on addressed to each alone (``why``). Returns the ids
        ended."""
        first = next(iter(self.vehicles))
        stopped: list[int] = []
        for d in self._deliveries():
            ended = False
            for cid in self._carries(d):
                by = newer(self._vehicle_of.get(cid, first))
                if by is not None and cid < by:
                    reason = f"superseded by command {by}{whence}"
                    self._end(cid, Event.SUPERSEDED, "sent", reason=reason, superseded_by=by)
                    stopped.append(cid)
                    ended = True
            if ended and d.to_all and self._carries(d):
                self._split(d, why)
        return stopped

    def _split(self, d: Delivery, why: str) -> None:
        """A Surface to all whose frame must not reach one vehicle any more (it was sent a
        newer command): its other records go on each alone, addressed to its own vehicle,
        with the copies the Surface had left."""
        if d.task is not None and d.task is not asyncio.current_task():
            d.task.cancel()
        for cid in self._carries(d):
            v = self.vehicles[self._vehicle_of[cid]]
            alone = Delivery(
                cid,
                encode_frame(d.enc.command, address=v.address),
                d.kind,
                d.members[cid],
                None if d.copies is None else max(1, d.copies - d.tried),
                d.interval_s,
                d.ber,
                d.loss,
                members={cid: d.members[cid]},
                next_s=d.next_s,
            )
            self._live[cid] = alone
            self._update(
                cid,
                reason=f"the Surface to all goes on addressed to {v.name} alone "
                f"({why}): frame {alone.enc.frame.hex}",
            )
            logger.info("command %s: the Surface to all goes on addressed to %s", cid, v.name)
            self._start(alone)
