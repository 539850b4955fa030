"""``nemesys bench control_sync`` (issue 24's figure): two console processes on one
PostgreSQL database, the ship's command changes timed from its page to the shore's; its
report names p50 and p99 beside the target, and every change reaches the shore."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from bench import control_sync
from tests.pg_server import PgServer

pytestmark = pytest.mark.slow  # two `nemesys console` processes


def test_every_change_reaches_the_other_console_and_the_report_says_how_soon(
    pg_server: PgServer, tmp_path: Path
) -> None:
    name = pg_server.new_database()
    try:
        lat, missed, count = control_sync.measure(pg_server.url(name), 40, tmp_path)
    finally:
        pg_server.drop_database(name)
    assert count == 40 and len(lat) + missed == count
    assert missed == 0
    # stamps are whole milliseconds on clocks anchored to one system clock: not before it
    assert all(-5 < ms < control_sync.TARGET_P99_MS for ms in lat), lat
    report = control_sync.format_report(lat, missed, count, "test")
    assert "p50" in report and "p99" in report and "< 1000" in report


def test_it_says_what_it_needs_without_a_database(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("NEMESYS_DATABASE_URL", raising=False)
    out = io.StringIO()
    assert control_sync.run(out) == 2
    assert "NEMESYS_DATABASE_URL=postgresql://" in out.getvalue()
