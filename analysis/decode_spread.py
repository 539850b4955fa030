"""How much the reconfiguration bench's decode figure moves between reruns.

``nemesys bench reconfig`` (:func:`bench.reconfig.measure`) gives one decode latency per run:
the median over rounds of each round's mean of 30 decodes. On a shared machine one run can
land on a quiet or a busy minute, so a single run's figure (and its ratio to the paper's
27 us, or to bchlib's bare BCH decode timed in the same run) says little about the next one.
:func:`reruns` calls the bench ``runs`` times, unchanged, one after the other in this process,
and :class:`DecodeSpread` keeps every run's figures so the page can state min / median / max.
"""

from __future__ import annotations

import statistics
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from bench.reconfig import PAPER_DECODE_MS, ReconfigReport, measure

#: Reruns of the bench for the spread (the page's table shows the first).
RERUNS = 5


def bchlib_ratio(report: ReconfigReport) -> float | None:
    """The run's whole onboard decode over bchlib's bare BCH decode timed in the same run
    (``None`` without bchlib)."""
    return report.decode_bchlib_ratio


def receiver_us(report: ReconfigReport) -> float | None:
    """The run's whole onboard decode (13 bytes -> checked command), mean over 0-2 errors."""
    timing = report.onboard_decode
    return None if timing is None else timing.receiver_mean_us


def bchlib_us(report: ReconfigReport) -> float | None:
    """bchlib's bare BCH decode in the same run, mean over 0-2 errors."""
    timing = report.onboard_decode
    return None if timing is None else timing.bchlib_mean_us


@dataclass(frozen=True, slots=True)
class Spread:
    """min / median / max of one figure over the reruns."""

    values: tuple[float, ...]

    @property
    def low(self) -> float:
        return min(self.values)

    @property
    def median(self) -> float:
        return statistics.median(self.values)

    @property
    def high(self) -> float:
        return max(self.values)


@dataclass(frozen=True, slots=True)
class DecodeSpread:
    reports: tuple[ReconfigReport, ...]

    @property
    def runs(self) -> int:
        return len(self.reports)

    @property
    def decode_us(self) -> Spread:
        """Each run's decode latency (us)."""
        return Spread(tuple(r.decode_ms * 1e3 for r in self.reports))

    @property
    def paper_ratio(self) -> Spread:
        """Each run's paper / ours (above 1: ours is faster)."""
        return Spread(tuple(PAPER_DECODE_MS / r.decode_ms for r in self.reports))

    @property
    def bchlib(self) -> Spread | None:
        """Each run's whole onboard decode / bchlib ratio, if the bench measures bchlib."""
        return _spread([bchlib_ratio(r) for r in self.reports])

    @property
    def receiver_us(self) -> Spread | None:
        """Each run's whole onboard decode (us)."""
        return _spread([receiver_us(r) for r in self.reports])


def _spread(values: Sequence[float | None]) -> Spread | None:
    if not values or any(v is None for v in values):
        return None
    return Spread(tuple(v for v in values if v is not None))


def reruns(
    runs: int = RERUNS,
    *,
    quick: bool = False,
    first: ReconfigReport | None = None,
    bench: Callable[[bool], ReconfigReport] = measure,
) -> DecodeSpread:
    """``runs`` runs of the bench (``first``, if given, counts as one of them)."""
    reports: list[ReconfigReport] = [] if first is None else [first]
    while len(reports) < runs:
        reports.append(bench(quick))
    return DecodeSpread(tuple(reports))


def spread_text(s: Spread, fmt: Callable[[float], str]) -> str:
    """``min / median / max`` of a spread."""
    return f"{fmt(s.low)} / {fmt(s.median)} / {fmt(s.high)}"


def values_text(values: Sequence[float], fmt: Callable[[float], str]) -> str:
    return ", ".join(fmt(v) for v in values)


__all__ = [
    "RERUNS",
    "DecodeSpread",
    "Spread",
    "bchlib_ratio",
    "bchlib_us",
    "receiver_us",
    "reruns",
    "spread_text",
    "values_text",
]
