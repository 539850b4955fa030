"""How many copies a command gets, a Surface pressed again joining the one on its way, and the
schedule of every copy still to go out (the airtime budget reads it).
:class:`backend.commands.manager.CommandManager` builds on it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

from backend.commands.acks import CommandAcks
from backend.commands.airtime import Queued
from backend.commands.delivery import MIN_SURFACE_COPIES, Delivery, planned_copies
from backend.commands.vehicles import ALL_VEHICLES
from backend.mission_log.store import LogWriteError
from codec import FRAME_BITS

__all__ = ["CopyPlanning", "OnTheWay"]


class OnTheWay(NamedTuple):
    """A delivery still going out: its records, their vehicles, its pattern, its schedule."""

    records: tuple[int, ...]
    vehicles: tuple[str, ...]
    pattern: str
    queued: Queued


class CopyPlanning(CommandAcks):
    """Copies per vehicle, a Surface joined, the schedule (see the module's doc)."""

    delivery_target: float
    link_ber: Callable[[], tuple[float, float]]
    _link_ber_of: Callable[[str], tuple[float, float]] | None

    # --- how many copies -------------------------------------------------------------------

    def _ber(self, name: str) -> tuple[float, float]:
        """(bit-error rate, whole-frame loss) the copies to vehicle ``name`` follow."""
        return self._link_ber_of(name) if self._link_ber_of is not None else self.link_ber()

    def copies_now(self, vehicle: str | None = None) -> int:
        """Copies a command to ``vehicle`` gets now (one on a two-way link)."""
        v = self.addressee(vehicle)
        copies = planned_copies("command", v.acknowledges, *self._ber(v.name), self.delivery_target)
        assert copies is not None
        return copies

    def surface_copies_now(self, vehicle: str | None = None) -> int | None:
        """Copies a Surface to ``vehicle`` gets now; ``None``: until acknowledged (two-way
        link). To :data:`ALL_VEHICLES`: until every vehicle acknowledged when every one can,
        else the most any of them needs."""
        if vehicle == ALL_VEHICLES:
            counts = [self.surface_copies_now(name) for name in self.vehicles]
            bounded = [c for c in counts if c is not None]
            return max(bounded) if bounded else None
        v = self.addressee(vehicle)
        return planned_copies("surface", v.acknowledges, *self._ber(v.name), self.delivery_target)

    # --- a Surface pressed again -----------------------------------------------------------

    def _join_surface(self, vehicle: str | None) -> list[dict[str, Any]]:
        """A Surface pressed while one to the same vehicle (or to all, for all) is on its
        way: the same records, sent again now, with their full count of copies to go."""
        to_all = vehicle == ALL_VEHICLES
        name = None if to_all else self.addressee(vehicle).name
        first = next(iter(self.vehicles))
        for d in reversed(self._deliveries()):
            carried = self._carries(d)
            if d.kind != "surface" or (to_all and not d.to_all):
                continue
            if not to_all and all(self._vehicle_of.get(c, first) != name for c in carried):
                continue
            return self._join(d, carried, vehicle)
        return []

    def _join(self, d: Delivery, carried: list[int], vehicle: str | None) -> list[dict[str, Any]]:
        records = [self.log.command(cid) for cid in carried]
        if d.copies is not None:
            more = d.tried + (self.surface_copies_now(vehicle) or MIN_SURFACE_COPIES) - d.copies
            try:  # logged first: no copy leaves that the log does not count
                with self._atomic():
                    records = [
                        self._update(cid, copies=((r or {}).get("copies") or 0) + more)
                        for cid, r in zip(carried, records, strict=True)
                    ]
            except LogWriteError as err:
                err.outcome = "no copy was added to the Surface already on its way"
                raise
            d.copies += more
        d.next_s = self.clock.monotonic()
        d.wake.set()
        first = next(iter(self.vehicles))
        if vehicle is not None and vehicle != ALL_VEHICLES:
            mine = [
                r
                for r, c in zip(records, carried, strict=True)
                if self._vehicle_of.get(c, first) == vehicle
            ]
            records = mine or records
        return [r for r in records if r is not None]

    # --- the transmitter's schedule ---------------------------------------------------------

    def on_the_way(self) -> list[OnTheWay]:
        """Every delivery still going out, with its schedule (:func:`backend.commands.airtime.
        airtime_budget_s` reads it)."""
        now = self.clock.monotonic()
        first = next(iter(self.vehicles))
        out = []
        for d in self._deliveries():
            carried = self._carries(d)
            left = None if d.copies is None else max(0, d.copies - d.tried)
            out.append(
                OnTheWay(
                    tuple(carried),
                    tuple(self._vehicle_of.get(c, first) for c in carried),
                    d.enc.command.pattern.name,
                    Queued(
                        left,
                        max(0.0, d.next_s - now),
                        d.interval_s,
                        self.airtime_s * len(d.enc.frame.bits) / FRAME_BITS,
                        d.kind == "surface",
                    ),
                )
            )
        return out
