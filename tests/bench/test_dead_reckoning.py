"""``nemesys bench dead_reckoning`` prints, for each pattern and current, the error against
sigma over the minute without telemetry, and the cost beside the simulated twin's."""

from __future__ import annotations

import io

import pytest

from bench import dead_reckoning


@pytest.mark.slow  # a benchmark run, ~5 s quick
def test_quick_run_prints_error_against_sigma() -> None:
    out = io.StringIO()
    status = dead_reckoning.run(out, quick=True)
    text = out.getvalue()
    for name in dead_reckoning.CASES:
        for label in dead_reckoning.CURRENTS:
            assert f"{name}, {label}: telemetry stops at" in text
    assert text.count("worst error/sigma over fix times") == 4
    assert "ms per simulated second" in text
    assert status == (0 if "MISSED" not in text else 1)


def test_a_case_has_a_row_every_5_s_for_a_minute() -> None:
    pattern, params, fix_t_s = dead_reckoning.CASES["circle"]
    rows = dead_reckoning.run_case(pattern, params, (0.0, 0.0), fix_t_s)
    assert [t for t, _, _ in rows] == [5.0 * k for k in range(13)]
    assert all(e <= s for _, e, s in rows)
