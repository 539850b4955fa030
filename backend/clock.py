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
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
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
