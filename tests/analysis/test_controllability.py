"""The thruster configuration matrix of the four-thruster layout: rank 4, sway and pitch not
actuated, and the matrix is the twin's own."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from analysis import controllability as ctl
from sim.model import VehicleParams


def test_rank_is_four_with_surge_heave_roll_yaw() -> None:
    c = ctl.analyse()
    assert c.matrix.shape == (6, 4)
    assert c.rank == 4 == np.linalg.matrix_rank(c.matrix)
    assert c.actuated == ("X surge", "Z heave", "K roll", "N yaw")
    assert c.redundant == 0  # no thrust mix without effect


def test_null_directions_are_sway_and_pitch() -> None:
    c = ctl.analyse()
    assert c.unactuated == ("Y sway", "M pitch")
    b = c.matrix
    for row in ("Y sway", "M pitch"):
        e = np.zeros(6)
        e[ctl.WRENCH.index(row)] = 1.0
        assert np.allclose(e @ b, 0.0)  # no thrust makes a sway force or a pitch moment
        assert np.linalg.matrix_rank(np.column_stack([b, e])) == 5  # not in B's range
    assert set(ctl.WHY_NOT_ACTUATED) == set(c.unactuated)


def test_matrix_is_the_models_thrust_mapping() -> None:
    for params in (VehicleParams(), replace(VehicleParams(), arm_h_m=0.2, arm_v_m=0.07)):
        b = ctl.allocation_matrix(params)
        assert np.abs(ctl.model_matrix(params) - b).max() < 1e-4
        assert b[5, 0] == pytest.approx(params.arm_h_m)  # N = l_h (T1 - T2)
        assert b[3, 3] == pytest.approx(params.arm_v_m)  # K = l_v (T4 - T3)


def test_reachable_wrench_uses_the_thrust_limits() -> None:
    q = VehicleParams()
    c = ctl.analyse(q)
    assert c.max_wrench["X surge"] == pytest.approx((2 * q.thrust_min_n, 2 * q.thrust_max_n))
    assert c.max_wrench["K roll"][1] == pytest.approx(q.arm_v_m * (q.thrust_max_n - q.thrust_min_n))
    assert set(c.max_wrench) == set(c.actuated)
