"""The clock command delivery reads: the time (monotonic seconds) and timers on it.

:class:`CommandManager <backend.commands.manager.CommandManager>` spaces copies, repeats a Surface,
times out acknowledgements and counts the rate limit on a :class:`Clock`. The console uses
:data:`SYSTEM_CLOCK` (``time.monotonic`` and the event loop's timers); a test passes a clock
it moves by hand (``tests/manual_clock.py``), so that "three copies 1 s apart" or "no
acknowledgement within 30 s" happen at once and in a known order, and "nothing more went out"
is proved by moving the clock past every timer rather than by waiting in real time.

Timers, not ``sleep``: both waits of a delivery are "until this time, unless woken sooner" (the
next copy, or a Surface pressed again) and "call this if nothing settled it first" (the
acknowledgement timeout), which a cancellable timer says directly.

The console's UTC (:data:`CONSOLE_UTC`) is the other clock: the wall clock read once, then moved
by the monotonic one. Every time the console writes into the mission log is on it (a command
created, sent, acknowledged; an event; the arrival of a track point), so the dive's stamps never
go back and their differences are true seconds even if the system clock is stepped meanwhile.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from datetime import UTC, datetime
from typing import Protocol


class Timer(Protocol):
    """A pending call that can be called off (``asyncio.TimerHandle`` is one)."""

    def cancel(self) -> None: ...


class Clock(Protocol):
    """Monotonic time (s) and timers on it, called on the running event loop."""

    def monotonic(self) -> float:
        """Seconds on a clock that never goes back (only differences mean anything)."""
        ...

    def call_later(self, delay_s: float, callback: Callable[[], object]) -> Timer:
        """Call ``callback`` on the event loop ``delay_s`` seconds from now, unless the
        returned timer is cancelled first."""
        ...


class SystemClock:
    """The real clock: ``time.monotonic`` and the running loop's ``call_later``."""

    def monotonic(self) -> float:
        return time.monotonic()

    def call_later(self, delay_s: float, callback: Callable[[], object]) -> Timer:
        return asyncio.get_running_loop().call_later(delay_s, callback)


#: The clock of a running console.
SYSTEM_CLOCK: Clock = SystemClock()


class AnchoredUtc:
    """UTC on the monotonic clock: ``wall_s`` (POSIX seconds) read once at construction, the
    anchor, then moved by ``monotonic_s``. Within a run its times never go back and differ by
    the elapsed seconds; NTP's gradual corrections reach both clocks, a step of the system
    clock reaches neither (it shows at the next start, when the anchor is read again)."""

    def __init__(
        self,
        wall_s: Callable[[], float] = time.time,
        monotonic_s: Callable[[], float] = time.monotonic,
    ) -> None:
        self._monotonic_s = monotonic_s
        self._anchor_wall_s = wall_s()
        self._anchor_mono_s = monotonic_s()

    def now_s(self) -> float:
        """Now, as POSIX seconds (UTC)."""
        return self._anchor_wall_s + (self._monotonic_s() - self._anchor_mono_s)

    def now(self) -> datetime:
        """Now, as an aware UTC datetime."""
        return datetime.fromtimestamp(self.now_s(), UTC)


#: The console's UTC: every stamp the mission log holds (``backend.mission_log.store.now_iso``).
CONSOLE_UTC = AnchoredUtc()
