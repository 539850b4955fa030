"""A dive's telemetry series, read back from its track (the plots after a reload).

The track keeps a point a second of the vehicle's clock with what the status said then
(:mod:`backend.mission_log.track`), a point without a position while the navigation was not
valid. The series puts those on the dive's own clock: seconds
since its first track point (the vehicle first heard in the dive, :mod:`backend.dives`), the
same zero the page's live plots count from.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

#: Most samples a series returns by default (an hour at 1 Hz); more are thinned evenly.
DEFAULT_MAX_POINTS = 3600


def commanded_depth_m(active: Mapping[str, Any] | None) -> float | None:
    """The depth an active command asks for (m): its ``depth``, or a helix's ``end_depth``;
    None without one (no command, a Surface, a pattern without a depth)."""
    params = (active or {}).get("params")
    if not isinstance(params, Mapping):
        return None
    value = params.get("depth", params.get("end_depth"))
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        return None
    return float(value)


def thin(n: int, most: int) -> list[int]:
    """Indices of at most ``most`` (>= 2) of ``n`` samples, evenly spread, first and last
    kept."""
    if n <= most:
        return list(range(n))
    step = (n - 1) / (most - 1)
    return sorted({round(k * step) for k in range(most)})


def dive_series(rows: Sequence[Mapping[str, Any]], max_points: int) -> dict[str, Any]:
    """The series of a dive's track rows (``MissionLog.track_rows``, time order, the points
    without a position included): ``start_t_s`` (the vehicle's clock at the first row; None
    without rows), ``interval_s`` (the samples' typical spacing) and the columns ``t_s`` (s
    since the start), ``depth_m`` (the depth sensor, else the pose's z), ``commanded_depth_m``
    (as logged; an older row's from its ``active``), ``battery_pct``, ``speed_mps``,
    ``heading_deg``, ``mode``, ``nav_valid`` (None: not said) and ``nav_age_s``."""
    keep = [rows[i] for i in thin(len(rows), max_points)]
    start = float(rows[0]["t_s"]) if rows else None
    t = [float(r["t_s"]) - (start or 0.0) for r in keep]
    span = t[-1] - t[0] if len(t) > 1 else 0.0
    return {
        "start_t_s": start,
        "interval_s": span / (len(t) - 1) if len(t) > 1 else None,
        "t_s": t,
        "depth_m": [r["depth_m"] if r["depth_m"] is not None else r["z_m"] for r in keep],
        "commanded_depth_m": [_commanded(r) for r in keep],
        "battery_pct": [r["battery_pct"] for r in keep],
        "speed_mps": [r["speed_mps"] for r in keep],
        "heading_deg": [r.get("heading_deg") for r in keep],
        "mode": [r.get("mode") for r in keep],
        "nav_valid": [r.get("nav_valid") for r in keep],
        "nav_age_s": [r.get("nav_age_s") for r in keep],
    }


def _commanded(row: Mapping[str, Any]) -> float | None:
    logged = row.get("commanded_depth_m")
    return float(logged) if logged is not None else commanded_depth_m(row["active"])
