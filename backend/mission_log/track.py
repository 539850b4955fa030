"""The track buffer: the vehicle's track points on their way to the mission log.

Points arrive with the telemetry, several a second. Each is buffered and written with the
others in one commit within :data:`TRACK_FLUSH_S` of the first point buffered, at
:data:`TRACK_BATCH` points, on a read of the log and on close: a killed console loses less
than :data:`TRACK_FLUSH_S`. A write that fails is logged once and tried again by the timer;
meanwhile the points are kept in memory (at most :data:`TRACK_BUFFER_MAX`, the oldest dropped
beyond), and nothing is raised into the telemetry path.
"""

from __future__ import annotations

import json
import logging
import threading
from collections.abc import Callable, Mapping
from typing import Any

from backend.mission_log.errors import LogWriteError
from backend.mission_log.series import commanded_depth_m
from vehicle_contract.messages import number

#: The mission log's messages, under the store's name.
logger = logging.getLogger("backend.mission_log.store")

#: Track points are buffered at most this long after the first of them arrived (s)...
TRACK_FLUSH_S = 0.5
#: ... or until this many are buffered.
TRACK_BATCH = 10
#: Points kept while the log cannot be written (the oldest are dropped beyond).
TRACK_BUFFER_MAX = 3600

#: A row of the log's ``track`` table: dive, t_s, x_m, y_m, z_m, heading_deg (None: a point
#: made from a status without navigation), then what the status said (depth_m, speed_mps,
#: battery_pct, mode; None: not said), the active command the vehicle reported (JSON text,
#: None: none or not said), the station's clock (ISO, :data:`backend.clock.CONSOLE_UTC`), the
#: depth that command asks for, whether the navigation was valid (1/0) and its age (s), and the
#: fleet's vehicle it is of (None without a fleet).
TrackPoint = tuple[
    int,
    float,
    float | None,
    float | None,
    float | None,
    float | None,
    float | None,
    float | None,
    float | None,
    str | None,
    str | None,
    str,
    float | None,
    int | None,
    float | None,
    str | None,
]
#: The track table's columns a dive is read back with, in :data:`TrackPoint`'s order (its
#: vehicle, :data:`TRACK_WRITE_COLUMNS`' last, is read as a filter).
TRACK_COLUMNS = (
    "dive",
    "t_s",
    "x_m",
    "y_m",
    "z_m",
    "heading_deg",
    "depth_m",
    "speed_mps",
    "battery_pct",
    "mode",
    "active",
    "at",
    "commanded_depth_m",
    "nav_valid",
    "nav_age_s",
)
#: Every column a track point is written with, in :data:`TrackPoint`'s order.
TRACK_WRITE_COLUMNS = (*TRACK_COLUMNS, "vehicle")
#: A point's position: t_s, then x_m, y_m, z_m, heading_deg (None: no navigation).
Position = tuple[float, float | None, float | None, float | None, float | None]


def track_point(
    dive: int, position: Position, status: Mapping[str, Any], at: str, vehicle: str | None = None
) -> TrackPoint:
    """The row of one point: ``position`` (t_s, x_m, y_m, z_m, heading_deg), what ``status``
    says (a number it does not hold, or a mode that is not text: null; an ``active`` that is
    not a command object: null; a ``nav_valid`` that is not a boolean: null, a 1.x vehicle's
    "taken as true"; a boolean is kept as 0/1, on PostgreSQL too: one schema for both), the
    commanded depth of its ``active`` command
    (:func:`~backend.mission_log.series.commanded_depth_m`), the station's clock ``at`` and the
    fleet's ``vehicle`` it is of."""
    t_s, x_m, y_m, z_m, heading_deg = position
    mode = status.get("mode")
    active = status.get("active")
    nav_valid = status.get("nav_valid")
    return (
        dive,
        t_s,
        x_m,
        y_m,
        z_m,
        heading_deg,
        number(status.get("depth_m")),
        number(status.get("speed_mps")),
        number(status.get("battery_pct")),
        mode if isinstance(mode, str) else None,
        json.dumps(active) if isinstance(active, dict) else None,
        at,
        commanded_depth_m(active if isinstance(active, dict) else None),
        int(nav_valid) if isinstance(nav_valid, bool) else None,
        number(status.get("nav_age_s")),
        vehicle,
    )


class TrackBuffer:
    """Track points not written yet.

    ``lock`` is the log's (every write to the log holds it; the buffer's timer takes it too),
    and ``write`` commits points in one transaction or raises :class:`LogWriteError`.
    """

    def __init__(self, lock: threading.RLock, write: Callable[[list[TrackPoint]], None]) -> None:
        self._lock = lock
        self._write = write
        self._points: list[TrackPoint] = []
        self._timer: threading.Timer | None = None
        self._failing = False
        self._closed = False

    def add(self, point: TrackPoint) -> None:
        """Buffer one point; written as the module says (never raises a write failure)."""
        with self._lock:
            self._points.append(point)
            del self._points[:-TRACK_BUFFER_MAX]
            if len(self._points) >= TRACK_BATCH and not self._failing:
                self.flush()
            elif self._timer is None and not self._closed:
                self._timer = threading.Timer(TRACK_FLUSH_S, self._flush_due)
                self._timer.daemon = True
                self._timer.start()

    def flush(self) -> None:
        """Write the buffered points now; a failure is logged (once while it lasts)."""
        with self._lock:
            try:
                self._flush()
            except LogWriteError as err:
                if not self._failing:  # once, not at every point
                    logger.error("track points are kept in memory only: %s", err)
                self._failing = True

    def close(self) -> None:
        """No timer from now on; the buffered points are written (or the failure logged)."""
        with self._lock:
            self._closed = True
            if self._timer is not None:
                self._timer.cancel()
            self.flush()

    def _flush_due(self) -> None:
        with self._lock:
            self._timer = None
            if not self._closed:
                self.flush()

    def _flush(self) -> None:
        if self._points:
            self._write(self._points)
            self._points = []
            if self._failing:
                logger.warning("track points are written to the mission log again")
                self._failing = False
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
