"""``nemesys bench export`` prints the export's time, peak memory and size per hour beside
their targets, for a short and a long synthetic dive; the synthetic dive is what it says."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from backend.mission_log.store import MissionLog
from bench import export
from bench._dive_log import NAV_FAULT_S, ManualUtc, fill_dive


@pytest.mark.slow  # a benchmark run: two dives, two forms, a fresh process each (~20 s)
def test_quick_run_prints_the_figures_beside_their_targets() -> None:
    out = io.StringIO()
    status = export.run(out, quick=True)
    text = out.getvalue()
    assert "export s" in text and "peak RSS+ MiB" in text and "MB/h" in text
    for form in export.FORMS:
        assert text.count(f"  {form}: ") == 4  # time, peak, flatness, size: each with a verdict
    assert text.count("(target ") == 8
    assert status == (0 if "MISSED" not in text else 1)


def test_the_synthetic_dive_is_written_through_the_store_on_its_own_clock(tmp_path: Path) -> None:
    clock = ManualUtc()
    log = MissionLog(tmp_path / "log.sqlite3", now=clock)
    try:
        filled = fill_dive(log, 1300, clock)
        rows = log.track_rows(filled.dive, positioned=False)
        commands = log.commands(dive=filled.dive, limit=100, oldest_first=True)
        assert filled.track == len(rows) == 1300
        assert filled.positioned == 1300 - NAV_FAULT_S == sum(r["x_m"] is not None for r in rows)
        assert filled.commands == len(commands) == 3 == filled.sent == filled.acks
        assert filled.events == len(log.events(filled.dive))
        # the log's stamps span the dive as a real one's would (a point a second)
        assert rows[0]["at"] == "2025-06-15T15:06:40.000+00:00"
        assert rows[-1]["at"] == "2025-06-15T15:28:19.000+00:00"
    finally:
        log.close()
