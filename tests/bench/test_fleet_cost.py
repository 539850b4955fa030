"""``nemesys bench fleet_cost`` starts a single-vehicle and a 10-vehicle console, prints each
one's figures with 20 pages against none beside their targets, and stops both servers (the
figures are not asserted: timings belong to the benchmark, not the tests)."""

from __future__ import annotations

import io
import os
import re

import pytest

from bench import fleet_cost

#: Two `nemesys console` subprocesses and a child of 20 pages: make test, not make test-fast.
pytestmark = pytest.mark.slow

NUMBER = r"-?\d+(?:\.\d+)?"
SIZES = fleet_cost.Sizes(sends=2, preview_s=0.6)


def test_a_run_prints_both_consoles_figures_as_ratios_and_stops_them() -> None:
    out = io.StringIO()
    assert fleet_cost.run(out, sizes=SIZES) == 0
    text = out.getvalue()
    lines = text.splitlines()
    pids = [int(p) for p in re.findall(r"Console with \d+ vehicle\(s\): pid (\d+)", text)]
    assert len(pids) == 2
    for pid in pids:
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)

    # the graded table: per console, the excess (target +10 ms) and the preview's ratios
    for console in ("1 vehicle ", "10 vehicles"):
        at = next(i for i, ln in enumerate(lines) if ln.startswith(console) and "excess" in ln)
        excess, p50, p99 = lines[at : at + 3]
        assert re.search(
            rf"excess median ms\s+{NUMBER}\s+{NUMBER}\s+[+-]{NUMBER} ms \({NUMBER}x\)\s+"
            r"<= \+10 ms\s+(met|MISSED)",
            excess,
        ), excess
        assert re.search(rf"preview p50 ms\s+{NUMBER}\s+{NUMBER}\s+{NUMBER}x\s+<= 1.2x", p50), p50
        assert re.search(rf"preview p99 ms\s+{NUMBER}\s+{NUMBER}\s+{NUMBER}x\s+<= 3x", p99), p99
        assert all(ln.rstrip().endswith(("met", "MISSED")) for ln in (p50, p99))

    # the phases: 0, 20, 0 pages each; every send acknowledged; the pages got telemetry,
    # ten vehicles' worth with the fleet
    phases = [ln for ln in lines if re.search(r"\b\d+ pages \((before|with|after)\)", ln)]
    assert len(phases) == 6
    for row in phases:
        assert re.search(rf"\s{SIZES.sends}/{SIZES.sends}\s", row), row
        assert re.search(r"\s0\s+[\d-]+ / \d+ / [\d-]+ %", row), row  # no errors, CPU
    single, fleet = phases[1], phases[4]
    hz = [float(re.findall(rf"({NUMBER})\s+({NUMBER})\s+0\s", r)[0][0]) for r in (single, fleet)]
    assert hz[0] > 0 and hz[1] > 3 * hz[0], (single, fleet)
