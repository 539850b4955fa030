"""A dive's series read back from its track (backend/mission_log/series.py)."""

from __future__ import annotations

from typing import Any

from backend.mission_log.series import commanded_depth_m, dive_series, thin


def row(t_s: float, **fields: Any) -> dict[str, Any]:
    base = {"t_s": t_s, "x_m": 0.0, "y_m": 0.0, "z_m": 2.0, "heading_deg": 0.0}
    return {
        **base,
        "depth_m": None,
        "speed_mps": None,
        "battery_pct": None,
        "active": None,
        **fields,
    }


def test_commanded_depth_is_the_depth_or_a_helix_end_depth() -> None:
    assert commanded_depth_m({"pattern": "circle", "params": {"depth": 3}}) == 3.0
    assert commanded_depth_m({"pattern": "helix", "params": {"end_depth": 8.5}}) == 8.5
    for none in (None, {"pattern": "surface", "params": {}}, {"params": {"depth": True}}, {}):
        assert commanded_depth_m(none) is None


def test_thin_keeps_the_first_and_last_and_at_most_most() -> None:
    assert thin(5, 10) == [0, 1, 2, 3, 4]
    kept = thin(1000, 7)
    assert kept[0] == 0 and kept[-1] == 999 and len(kept) == 7
    assert thin(3, 2) == [0, 2]


def test_the_series_counts_from_the_first_sample() -> None:
    rows = [
        row(100.0),
        row(101.0, depth_m=2.5, battery_pct=99.5, speed_mps=0.2),
        row(102.0, depth_m=2.6, active={"pattern": "circle", "params": {"depth": 3.0}}),
    ]
    s = dive_series(rows, 3600)
    assert s["start_t_s"] == 100.0 and s["interval_s"] == 1.0
    assert s["t_s"] == [0.0, 1.0, 2.0]
    assert s["depth_m"] == [2.0, 2.5, 2.6]  # the sensor, else the pose's z
    assert s["commanded_depth_m"] == [None, None, 3.0]
    assert s["battery_pct"] == [None, 99.5, None]
    assert s["speed_mps"] == [None, 0.2, None]
    empty = dive_series([], 10)
    assert empty["start_t_s"] is None and empty["t_s"] == [] and empty["interval_s"] is None
