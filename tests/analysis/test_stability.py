"""Passive stability on the twin (the paper's Fig. fig:stability_comparison): a negative GM
capsizes, a positive one rights itself, zero stays where it was pushed."""

from __future__ import annotations

import itertools
import math
from dataclasses import replace
from pathlib import Path

import pytest

from analysis import stability
from sim.model import VehicleParams

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def runs() -> dict[str, stability.StabilityRun]:
    return {r.name: r for r in stability.compare()}


def test_the_three_configurations_are_the_papers_gms(
    runs: dict[str, stability.StabilityRun],
) -> None:
    assert {n: r.gm_mm for n, r in runs.items()} == {"Cfg #1": 0.0, "Cfg #2": -2.0, "Cfg #3": 6.5}


def test_negative_gm_diverges_and_ends_upside_down(runs: dict[str, stability.StabilityRun]) -> None:
    cfg2 = runs["Cfg #2"]
    assert cfg2.outcome == "capsizes"
    assert cfg2.capsize_s is not None and 0 < cfg2.capsize_s < 10
    assert cfg2.peak_deg > 170
    assert abs(cfg2.final_deg - 180) < 2  # at rest upside down (stable inverted)
    # diverges: once past the push's first swing, |roll| keeps growing until it passes 90 deg
    k_push = cfg2.times_s.index(stability.PUSH_AT_S)
    k90 = next(k for k, r in enumerate(cfg2.roll_deg) if abs(r) > 90)
    rising = cfg2.roll_deg[k_push : k90 + 1]
    assert all(b > a for a, b in itertools.pairwise(rising))


def test_negative_gm_capsizes_from_a_tiny_push() -> None:
    run = stability.simulate(-2.0, push_dps=0.5, duration_s=40.0)
    assert run.outcome == "capsizes" and run.peak_deg > 170


def test_positive_gm_stays_bounded_and_returns(runs: dict[str, stability.StabilityRun]) -> None:
    cfg3 = runs["Cfg #3"]
    assert cfg3.outcome == "rights itself"
    assert cfg3.capsize_s is None
    assert cfg3.peak_deg < 20  # bounded
    assert cfg3.upright_s is not None and cfg3.upright_s < 15
    assert abs(cfg3.final_deg) < 0.5  # returned
    tail = [abs(r) for t, r in zip(cfg3.times_s, cfg3.roll_deg, strict=True) if t > 20]
    assert max(tail) < stability.UPRIGHT_BAND_DEG


def test_positive_gm_rights_even_a_hard_push() -> None:
    run = stability.simulate(6.5, push_dps=200.0)
    assert run.outcome == "rights itself" and run.peak_deg < 90


def test_zero_gm_is_neutral(runs: dict[str, stability.StabilityRun]) -> None:
    cfg1 = runs["Cfg #1"]
    assert cfg1.outcome == "neutral"
    assert 10 < cfg1.final_deg < 90  # stopped by damping where the push left it
    assert cfg1.final_deg == pytest.approx(cfg1.peak_deg, abs=0.1)


def test_linear_modes() -> None:
    cfg3 = stability.roll_mode(6.5)
    assert cfg3.period_s is not None and 2.5 < cfg3.period_s < 3.5  # docs/simulator.md: ~3 s
    assert cfg3.damping_ratio is not None and 0 < cfg3.damping_ratio < 1
    cfg2 = stability.roll_mode(-2.0)
    assert cfg2.growth_per_s is not None and cfg2.growth_per_s > 0
    q = VehicleParams()
    m44 = q.ix_kgm2 + q.a44_kgm2
    s = cfg2.growth_per_s
    assert m44 * s * s + q.kp * s + cfg2.stiffness_nm_per_rad == pytest.approx(0, abs=1e-9)
    assert stability.roll_mode(0.0).stiffness_nm_per_rad == 0
    assert stability.push_impulse_nms() == pytest.approx(m44 * math.radians(30))


def test_config_params_admit_negative_gm_only() -> None:
    assert stability.config_params(-2.0).gm_m == pytest.approx(-0.002)
    assert stability.config_params(-2.0, replace(VehicleParams(), mass_kg=5.0)).mass_kg == 5.0
    with pytest.raises(ValueError, match="mass_kg"):
        stability.ConfigParams(mass_kg=-1.0, gm_m=-0.002)
    with pytest.raises(ValueError, match="gm_m"):
        stability.config_params(float("nan"))


def test_plot_is_a_png(tmp_path: Path, runs: dict[str, stability.StabilityRun]) -> None:
    out = stability.plot_stability(list(runs.values()), tmp_path / "a" / "stab.png")
    assert out.read_bytes()[:8] == PNG
