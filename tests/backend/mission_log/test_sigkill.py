"""SIGKILL recovery on both back-ends (``log_backend``): ten consoles killed at random moments
of a burst of sends (commands of many copies and Surface presses from two threads, a one-way
TCP link to a loopback listener), each restarted on the same log: 0 lost (every record the
console answered 202 for is in the log as answered), 0 stuck (nothing queued or transmitted
once the restarted console answers), 0 half-written (every required field of every record
present and readable), and at every kill what was on its way is exactly what the restart made
interrupted and printed. The cycles are ``nemesys bench recovery``'s (bench/recovery.py)."""

from __future__ import annotations

import pytest

from bench import recovery
from tests.backend.log_backend import LogBackend

#: `nemesys console` subprocesses, killed and restarted: make test, not make test-fast.
pytestmark = pytest.mark.slow

KILLS = 10


def test_ten_kills_lose_nothing_leave_nothing_stuck_or_half_written(
    log_backend: LogBackend,
) -> None:
    workdir = log_backend.path.parent  # the SQLite log is workdir/missions.sqlite3
    workdir.mkdir(parents=True, exist_ok=True)
    cycles, listener, wall_s = recovery.measure(
        KILLS, seed=24, workdir=workdir, database_url=log_backend.url
    )
    report = recovery.format_report(cycles, listener, recovery.counts(log_backend.where)[0], wall_s)
    assert len(cycles) == KILLS, report
    assert all(c.accepted >= 1 for c in cycles), report  # every kill came during sends
    assert sum(c.lost for c in cycles) == 0, report
    assert sum(c.non_terminal for c in cycles) == 0, report
    assert sum(c.half_written for c in cycles) == 0, report
    assert all(c.interrupted == c.left == c.printed for c in cycles), report
    assert recovery.met(cycles), report
    # the frames the listener got all decoded (nothing garbled on the way out)
    assert listener.count() >= 1 and not listener.rejected, report
