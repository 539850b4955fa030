"""``nemesys bench durations`` prints the three durations of every case, and meets its targets
(the estimate within 20 % of the prediction, the prediction within 5 % of the run)."""

from __future__ import annotations

import io

import pytest

from bench import durations


@pytest.mark.slow  # every pattern through the twin three times, ~7 s
def test_every_case_has_its_three_durations_and_the_targets_are_met() -> None:
    out = io.StringIO()
    assert durations.run(out) == 0, out.getvalue()
    lines = out.getvalue().splitlines()
    for label, _, _ in durations.CASES:
        row = next(ln for ln in lines if ln.startswith(f"{label}  "))
        planned, est, pred, run, est_pred, pred_run = (float(c) for c in row.split()[-6:])
        assert min(planned, est, pred, run) > 0
        assert abs(est_pred - 1) <= 0.2 and abs(pred_run - 1) <= 0.05
    assert lines[-1].endswith(": met")
