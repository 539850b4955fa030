"""The one transmitter's time: whose frame goes next, and how long until every copy is out.

A fleet shares one ME transmitter (docs/protocol.md, "Addressing"): a frame at a time. Each
command's copies keep their own spacing (:class:`backend.commands.delivery.Delivery`: the
copy interval, for independent errors), so the copies of different vehicles interleave on
the wire in the order they fall due. When several are due at once, :class:`TransmitTurns`
hands the transmitter to a Surface first, then in the order they asked. Sans-IO but for the
waiting (asyncio futures); :func:`airtime_budget_s` is plain arithmetic on the schedule.
"""

from __future__ import annotations

import asyncio
import contextlib
import heapq
import itertools
from collections.abc import AsyncIterator, Sequence
from dataclasses import dataclass
from typing import Final

#: Turn priorities: a Surface goes ahead of every other frame that waits.
SURFACE_FIRST: Final = 0
IN_TURN: Final = 1


class TransmitTurns:
    """The transmitter, one frame at a time: who waits is served by priority
    (:data:`SURFACE_FIRST` before :data:`IN_TURN`), then in the order they asked."""

    def __init__(self) -> None:
        self._busy = False
        self._waiting: list[tuple[int, int, asyncio.Future[None]]] = []
        self._order = itertools.count()

    def locked(self) -> bool:
        """A frame is on its way to the link (as :meth:`asyncio.Lock.locked`)."""
        return self._busy

    @contextlib.asynccontextmanager
    async def turn(self, priority: int = IN_TURN) -> AsyncIterator[None]:
        """Hold the transmitter for one frame, after every waiter of a higher priority and
        every earlier one of the same."""
        if self._busy:
            future: asyncio.Future[None] = asyncio.get_running_loop().create_future()
            heapq.heappush(self._waiting, (priority, next(self._order), future))
            try:
                await future
            except asyncio.CancelledError:
                if future.done() and not future.cancelled():
                    self._release()  # the turn came as this waiter was cancelled: pass it on
                else:
                    future.cancel()  # left in the heap, skipped when its turn comes
                raise
        else:
            self._busy = True
        try:
            yield
        finally:
            self._release()

    def _release(self) -> None:
        while self._waiting:
            _, _, future = heapq.heappop(self._waiting)
            if not future.done():
                future.set_result(None)  # handed over: the transmitter stays busy
                return
        self._busy = False


@dataclass(frozen=True, slots=True)
class Queued:
    """A command's copies still to go out, as the schedule sees them.

    Attributes:
        copies_left: copies still to leave (``None``: repeated until acknowledged).
        due_in_s: until its next copy may leave (0: now).
        interval_s: the spacing of its copies.
        airtime_s: one frame's time on the link.
        surface: a Surface (served first when several are due).
    """

    copies_left: int | None
    due_in_s: float
    interval_s: float
    airtime_s: float
    surface: bool = False


@dataclass(slots=True)
class _Pending:
    due_s: float
    order: tuple[int, int]  # a Surface first, then as given
    left: int
    q: Queued


def copies_out_s(queued: Sequence[Queued]) -> list[float]:
    """For each of ``queued``, seconds from now until its last copy has left the transmitter
    (0: none to count), as the manager schedules them: each command's next copy at its due
    time, ``interval_s`` after the end of its previous one; one frame at a time, a Surface
    first among those due, then the one due longest. Copies repeated until acknowledged are
    not counted (they have no end).
    """
    ends = [0.0] * len(queued)
    pending = [
        _Pending(q.due_in_s, (0 if q.surface else 1, i), q.copies_left, q)
        for i, q in enumerate(queued)
        if q.copies_left is not None and q.copies_left > 0
    ]
    t = 0.0
    while pending:
        due = [p for p in pending if p.due_s <= t]
        if not due:
            t = min(p.due_s for p in pending)
            continue
        pick = min(due, key=lambda p: (p.order[0], p.due_s, p.order[1]))
        t += pick.q.airtime_s
        ends[pick.order[1]] = t
        pick.left -= 1
        if pick.left <= 0:
            pending.remove(pick)
        else:
            pick.due_s = t + pick.q.interval_s
    return ends


def airtime_budget_s(queued: Sequence[Queued]) -> float:
    """Seconds from now until every bounded copy of ``queued`` has left the transmitter
    (:func:`copies_out_s`' latest; 0: none queued)."""
    return max(copies_out_s(queued), default=0.0)


__all__ = [
    "IN_TURN",
    "SURFACE_FIRST",
    "Queued",
    "TransmitTurns",
    "airtime_budget_s",
    "copies_out_s",
]
