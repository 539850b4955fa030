"""``nemesys bench sim`` prints its rows with their targets (figures are not asserted: timings
belong to the benchmark, not the tests)."""

from __future__ import annotations

import io

import pytest

from bench import sim as bench_sim
from codec import DICTIONARY


@pytest.mark.slow  # a benchmark run, ~2.5 s
def test_quick_run_prints_speed_fleet_and_latency_rows() -> None:
    out = io.StringIO()
    assert bench_sim.run(out, quick=True) == 0
    lines = out.getvalue().splitlines()
    one = next(ln for ln in lines if ln.startswith("1 vehicle, one core"))
    assert float(one.split()[4].rstrip("x").replace(",", "")) > 0
    assert ">= 100x" in one and ("met" in one or "MISSED" in one)
    fleet = next(ln for ln in lines if ln.startswith("20 vehicles, 2 processes"))
    assert ">= 1x" in fleet
    for n in (1, 5, 10):  # a fleet on one link, every vehicle in one loop
        row = next(ln for ln in lines if ln.startswith(f"fleet of {n} on one link"))
        assert ">= 100x" in row and ("met" in row or "MISSED" in row)
    for name in DICTIONARY:
        row = next(ln for ln in lines if ln.startswith(f"{name} (defaults)"))
        median_ms, max_ms = (float(c) for c in row.split()[2:4])
        assert 0 < median_ms <= max_ms
    for label in ("wreck retask", "panel retask", "pod retask"):
        assert any(ln.startswith(label) for ln in lines)


def test_fleet_factor_counts_every_vehicle_once() -> None:
    # one worker, two vehicles, a short run: a positive, finite real-time factor
    factor = bench_sim.fleet_factor(2, 2.0, 1)
    assert 0 < factor < float("inf")
    assert bench_sim.fleet_shares(20, 2) == [10, 10]
    assert bench_sim.fleet_shares(7, 3) == [3, 2, 2]


def test_one_link_factor_runs_the_whole_fleet() -> None:
    factor = bench_sim.one_link_factor(3, 4.0)
    assert 0 < factor < float("inf")
