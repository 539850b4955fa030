"""The track buffer: the vehicle's track points on their way to the mission log.

Points arrive with the telemetry, several a second. Each is buffered and written with the
others in one commit within :data:`TRACK_FLUSH_S` of the first point buffered, at
:data:`TRACK_BATCH` points, on a read of the log and on close: a killed console loses less
than :data:`TRACK_FLUSH_S`. A write that fails is logged once and tried again by the timer;
meanwhile the points are kept in memory (at most :data:`TRACK_BUFFER_MAX`, the oldest dropped
beyond), and nothing is raised into the telemetry path.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

from backend.mission_log.errors import LogWriteError

#: The mission log's messages, under the store's name.
logger = logging.getLogger("backend.mission_log.store")

#: Track points are buffered at most this long after the first of them arrived (s)...
TRACK_FLUSH_S = 0.5
#: ... or until this many are buffered.
TRACK_BATCH = 10
#: Points kept while the log cannot be written (the oldest are dropped beyond).
TRACK_BUFFER_MAX = 3600

#: A row of the log's ``track`` table: dive, t_s, x_m, y_m, z_m, heading_deg.
TrackPoint = tuple[int, float, float, float, float, float]


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
