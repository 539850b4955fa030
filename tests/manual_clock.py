"""A :class:`backend.clock.Clock` that moves only when a test moves it.

Timers fire in the order of their due time (then of their scheduling), each at its own time,
and the event loop runs what a timer woke before the next one fires: "three copies 1 s apart"
are three frames at exactly t, t+1, t+2, and "nothing more goes out" is proved by moving the
clock past every timer that could send it, with no real waiting.
"""

from __future__ import annotations

import asyncio
import heapq
import itertools
from collections.abc import Callable
from dataclasses import dataclass, field

#: Event-loop turns given to the woken tasks after each timer (and before the first): an
#: in-memory delivery (wake, take the lock, hand a frame to the link, log it) takes a handful.
SETTLE_TURNS = 50


@dataclass(order=True)
class ManualTimer:
    due_s: float
    seq: int
    callback: Callable[[], object] = field(compare=False)
    cancelled: bool = field(default=False, compare=False)

    def cancel(self) -> None:
        self.cancelled = True


class ManualClock:
    """Monotonic time that starts at ``start_s`` and moves by :meth:`advance`."""

    def __init__(self, start_s: float = 1000.0) -> None:
        self.now_s = start_s
        self._timers: list[ManualTimer] = []
        self._seq = itertools.count()

    def monotonic(self) -> float:
        return self.now_s

    def call_later(self, delay_s: float, callback: Callable[[], object]) -> ManualTimer:
        timer = ManualTimer(self.now_s + max(0.0, delay_s), next(self._seq), callback)
        heapq.heappush(self._timers, timer)
        return timer

    def pending(self) -> list[float]:
        """Due times (s from now) of the timers not cancelled, soonest first."""
        return sorted(t.due_s - self.now_s for t in self._timers if not t.cancelled)

    async def settle(self) -> None:
        """Let the event loop run what is ready (no time passes)."""
        for _ in range(SETTLE_TURNS):
            await asyncio.sleep(0)

    async def advance(self, seconds: float) -> None:
        """Move time ``seconds`` forward, firing every timer due on the way at its time."""
        end_s = self.now_s + seconds
        await self.settle()
        while (timer := self._next(end_s)) is not None:
            self.now_s = max(self.now_s, timer.due_s)
            timer.callback()
            await self.settle()
        self.now_s = end_s

    async def advance_until(self, probe: Callable[[], bool], within_s: float) -> float:
        """Fire timers one at a time until ``probe()`` holds; the seconds that took. Fails if
        it does not hold within ``within_s`` seconds of clock time."""
        start_s, end_s = self.now_s, self.now_s + within_s
        await self.settle()
        while not probe():
            timer = self._next(end_s)
            if timer is None:
                raise AssertionError(f"not so within {within_s} s of clock time")
            self.now_s = max(self.now_s, timer.due_s)
            timer.callback()
            await self.settle()
        return self.now_s - start_s

    def _next(self, end_s: float) -> ManualTimer | None:
        """The soonest live timer due by ``end_s``, taken off the heap."""
        while self._timers and self._timers[0].cancelled:
            heapq.heappop(self._timers)
        if self._timers and self._timers[0].due_s <= end_s:
            return heapq.heappop(self._timers)
        return None
