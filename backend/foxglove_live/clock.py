"""Time in the live Foxglove view: the dive's clock, in nanoseconds.

The dive's clock counts seconds from the dive's start on the vehicle's clock: the vehicle's
``t_s`` less its first track point's (:mod:`backend.dives`), as the page's plots and the
replay's time slider count (:mod:`backend.mission_log.timeline`). Every message the view
publishes carries it, as its log time and as its ``timestamp`` field:

* a pose (and anything else the vehicle stamped) at its own ``t_s``;
* anything the console heard without a vehicle time (a command's state, the link's health,
  a log line, a preview) at the vehicle's clock now: the last pose's ``t_s`` run forward by
  the station's monotonic clock at the vehicle clock's recent rate (vehicle seconds per
  station second over the last second or more: the training simulator's time scale, which
  the operator may change), much as the replay places the link's events;
* before the dive's first pose (a one-way modem, no telemetry): station seconds since the
  dive began; before any dive, since the view started.

A new dive starts the clock again at 0. Nanoseconds are never negative (a pose stamped
before the dive's start, a vehicle restarted, is at 0).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import NamedTuple

NS_PER_S = 1_000_000_000
#: Shortest station time over which the vehicle clock's rate is measured (s); 1.0 before.
MIN_RATE_SPAN_S = 1.0


def to_ns(seconds: float) -> int:
    """Seconds on the dive's clock as nanoseconds (never negative)."""
    return max(0, round(seconds * NS_PER_S))


class _State(NamedTuple):
    """The clock's state, replaced whole (a log line on another thread reads it anytime)."""

    zero: float | None  # the dive's start on the vehicle's clock (s), once known
    began: float  # when the dive (or the view) began, station clock (s)
    ref: tuple[float, float] | None  # the vehicle time the rate is measured from, station time
    last: tuple[float, float] | None  # the last vehicle time heard, station time
    rate: float  # vehicle seconds per station second


class DiveClock:
    """Nanoseconds on the current dive's clock. ``start`` answers the dive's start on the
    vehicle's clock (:attr:`backend.dives.Dives.start_t_s`; None: no track point yet, when
    the first vehicle time heard in the dive stands in); ``monotonic`` is the station's
    clock (s)."""

    def __init__(
        self,
        start: Callable[[], float | None],
        monotonic: Callable[[], float] = time.monotonic,
    ) -> None:
        self._start = start
        self._monotonic = monotonic
        #: The dive the clock counts (None: none yet).
        self.dive: int | None = None
        self._state = _State(None, monotonic(), None, None, 1.0)

    def follow(self, dive: int | None) -> bool:
        """The telemetry names ``dive``: True when it is a new one (the clock starts again)."""
        if dive == self.dive:
            return False
        self.dive = dive
        self._state = _State(None, self._monotonic(), None, None, 1.0)
        return True

    def heard(self, t_s: float) -> int:
        """A vehicle time heard now (a pose): its nanoseconds on the dive's clock; it
        anchors :meth:`now`."""
        zero, began, ref, _last, rate = self._state
        mono = self._monotonic()
        if zero is None:
            zero = self._start()
            zero = t_s if zero is None else zero
        if ref is None or t_s < ref[0]:  # the first, or a vehicle clock that went back
            ref = (t_s, mono)
        elif mono - ref[1] >= MIN_RATE_SPAN_S:
            rate = (t_s - ref[0]) / (mono - ref[1])
            ref = (t_s, mono)
        self._state = _State(zero, began, ref, (t_s, mono), rate)
        return to_ns(t_s - zero)

    def at(self, t_s: float) -> int:
        """A vehicle time (an estimate's) on the dive's clock, without anchoring :meth:`now`;
        before the dive's first pose, :meth:`now`."""
        zero = self._state.zero
        return self.now() if zero is None else to_ns(t_s - zero)

    def now(self) -> int:
        """The dive's clock now (see the module's docstring)."""
        zero, began, _ref, last, rate = self._state
        mono = self._monotonic()
        if zero is None or last is None:
            return to_ns(mono - began)
        return to_ns(last[0] + (mono - last[1]) * rate - zero)


__all__ = ["NS_PER_S", "DiveClock", "to_ns"]
