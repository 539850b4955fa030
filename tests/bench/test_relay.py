"""``nemesys bench relay`` (issue 24's figure): send -> acknowledgement through the relay beside
a direct send, two console processes on one PostgreSQL database; its report names both, their
ratio and the relay's cost beside the target."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from bench import relay
from tests.pg_server import PgServer

pytestmark = pytest.mark.slow  # two `nemesys console` processes


def test_both_series_are_acknowledged_and_the_report_compares_them(
    pg_server: PgServer, tmp_path: Path
) -> None:
    name = pg_server.new_database()
    try:
        runs = relay.measure(pg_server.url(name), relay.ROUND, tmp_path)
    finally:
        pg_server.drop_database(name)
    direct, relayed = runs
    assert not direct.failures and not relayed.failures
    assert len(direct.ack_ms) == len(relayed.ack_ms) == relay.ROUND
    # an acknowledgement comes after the answer to the POST, on both paths
    assert all(a <= b for a, b in zip(direct.answer_ms, direct.ack_ms, strict=True))
    assert all(a <= b for a, b in zip(relayed.answer_ms, relayed.ack_ms, strict=True))
    report = relay.format_report(runs, "test")
    assert "send -> ack p50" in report and "relay/direct" in report and "< 1000" in report


def test_it_says_what_it_needs_without_a_database(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("NEMESYS_DATABASE_URL", raising=False)
    out = io.StringIO()
    assert relay.run(out) == 2
    assert "NEMESYS_DATABASE_URL=postgresql://" in out.getvalue()
