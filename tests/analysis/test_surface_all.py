"""``nemesys analyze surface-all``: the copies of one Surface-all frame that reach every one of
N vehicles at p >= 0.999 on a one-way link, from the codec's per-frame loss (the same as the
addressing analysis's lost-frame figure), checked by a Monte Carlo through the codec."""

from __future__ import annotations

import io

import numpy as np
import pytest

from analysis.addressing import CODEC_DESIGN, design, figures
from analysis.ber_analytic import wilson
from analysis.surface_all import (
    BER,
    FLEET_SIZES,
    TARGET,
    addressed_loss,
    copies_for_all,
    format_report,
    monte_carlo,
    p_all,
    run,
)
from cli.main import main


@pytest.mark.parametrize("ber", [1e-3, 1e-2, 3e-2])
def test_the_loss_is_the_addressing_analysis_lost_frame_figure(ber: float) -> None:
    lost = figures(design(CODEC_DESIGN), ber, w_exact=2).lost  # lost needs no enumeration
    assert addressed_loss(ber) == pytest.approx(lost, rel=1e-9)
    assert addressed_loss(1e-2) == pytest.approx(0.048, abs=5e-4)  # docs/protocol.md: 4.8 %


@pytest.mark.parametrize("vehicles", FLEET_SIZES)
def test_the_copies_are_the_fewest_that_reach_every_vehicle(vehicles: int) -> None:
    q = addressed_loss(BER)
    k = copies_for_all(q, vehicles)
    assert p_all(q, k, vehicles) >= TARGET
    assert k == 1 or p_all(q, k - 1, vehicles) < TARGET
    assert copies_for_all(q, vehicles) <= copies_for_all(q, vehicles + 5)


def test_bad_targets_and_hopeless_links_are_refused() -> None:
    with pytest.raises(ValueError, match=r"target must be in \(0, 1\)"):
        copies_for_all(0.1, 3, 1.0)
    with pytest.raises(ValueError, match="vehicles must be at least 1"):
        copies_for_all(0.1, 0)
    with pytest.raises(ValueError, match="copies do not reach"):
        copies_for_all(1.0, 3)


def test_the_monte_carlo_per_frame_loss_is_the_codecs() -> None:
    trials = 100_000
    got = monte_carlo(BER, 1, 1, trials, np.random.default_rng(3))
    low, high = wilson(got, trials, z=3.29)
    assert low <= 1 - addressed_loss(BER) <= high


def test_the_report_compares_surface_all_with_a_surface_per_vehicle() -> None:
    report = run(trials=2_000, seed=1)
    assert [r.vehicles for r in report.rows] == list(FLEET_SIZES)
    for r in report.rows:
        assert r.copies == copies_for_all(report.loss, r.vehicles)
        assert r.per_vehicle_frames == r.vehicles * r.copies
        assert r.seconds == pytest.approx(r.copies * 108 / 36_000)
        assert 0 < r.mc_delivered <= r.trials
    text = format_report(report)
    assert "| 10 | " in text and "q = 0.0482" in text


def test_nemesys_analyze_surface_all_prints_the_figure(capsys: pytest.CaptureFixture[str]) -> None:
    out = io.StringIO()
    assert main(["analyze", "surface-all", "--trials", "3000"], out=out) == 0
    lines = out.getvalue().splitlines()
    rows = [ln for ln in lines if ln.startswith("| ") and ln[2].isdigit()]
    assert [int(ln.split("|")[1]) for ln in rows] == list(FLEET_SIZES)
    assert main(["analyze", "surface-all", "--trials", "0"], out=io.StringIO()) == 2
    assert "--trials must be at least 1" in capsys.readouterr().err
