"""The vehicle's track in the shared 3D scene: decimated by distance, drawn in chunks.

Nodes: ``/track/chunk_0000 ...`` (full chunks, sent once), ``/track/live`` (the newest
chunk, resent on a redraw) and ``/track/tail`` (one segment from the last drawn point to the
vehicle). Not thread-safe: the :class:`backend.viewer.viewer.Viewer` holds its lock.
"""

from __future__ import annotations

import math
import time

import numpy as np

from backend.viewer.draw import TRACK_RGB, Canvas, FloatArray, ned_to_view

Point = tuple[float, float, float]


class Track:
    """The track's points (NED metres) and their drawing on ``canvas``.

    Args:
        max_points: at most this many points; when full, thinned to every second point
            (older parts end up coarser).
        min_step_m: a pose adds a point only once the vehicle has moved more than this (m).
        redraw_interval_s: the line is redrawn at most this often (s).
        chunk_segments: the line is drawn in chunks of this many segments.
    """

    def __init__(
        self,
        canvas: Canvas,
        *,
        max_points: int,
        min_step_m: float,
        redraw_interval_s: float,
        chunk_segments: int,
    ) -> None:
        self._canvas = canvas
        self._max_points = max_points
        self._min_step_m = min_step_m
        self._redraw_interval_s = redraw_interval_s
        self._chunk_segments = chunk_segments
        self.points: list[Point] = []
        self._frozen_end = 0  # index of the last point of the frozen chunks
        self._chunks = 0
        self._drawn = 0  # number of points the line shows
        self._last_redraw_s = -math.inf

    @property
    def ned_m(self) -> FloatArray:
        """The kept points, shape ``(N, 3)``, NED metres (a copy)."""
        return np.array(self.points, dtype=np.float64).reshape(-1, 3)

    def add(self, p: Point, pose: Point) -> bool:
        """Add ``p`` (if far enough from the last point), redraw when due (then True), draw
        the tail to the vehicle at ``pose``."""
        self._append(p)
        due = time.monotonic() - self._last_redraw_s >= self._redraw_interval_s
        if due:
            self.redraw()
        self.tail(pose)
        return due

    def reset(self) -> None:
        self._canvas.remove_group("/track")
        self.points.clear()
        self._undraw()

    def _undraw(self) -> None:
        """Nothing of the track counts as drawn: the next redraw draws it all."""
        self._frozen_end = 0
        self._chunks = 0
        self._drawn = 0
        self._last_redraw_s = -math.inf

    def _append(self, p: Point) -> None:
        track = self.points
        if track:
            last = track[-1]
            d2 = (p[0] - last[0]) ** 2 + (p[1] - last[1]) ** 2 + (p[2] - last[2]) ** 2
            if d2 <= self._min_step_m**2:
                return
        track.append(p)
        if len(track) > self._max_points:
            # thin to every second point, keeping the newest; frozen chunks are redrawn
            self.points = [*track[-2::-2][::-1], track[-1]]
            for name in self._canvas.node_names("/track/chunk_"):
                self._canvas.remove(name)
            self._undraw()

    def redraw(self) -> None:
        track, canvas = self.points, self._canvas
        self._last_redraw_s = time.monotonic()
        if not track:
            return
        if "/track" not in canvas.nodes:
            canvas.group("/track")
        # freeze full chunks: drawn once, never resent
        while len(track) - 1 - self._frozen_end >= self._chunk_segments:
            end = self._frozen_end + self._chunk_segments
            chunk = np.array(track[self._frozen_end : end + 1])
            canvas.polyline(
                f"/track/chunk_{self._chunks:04d}",
                ned_to_view(chunk[:, 0], chunk[:, 1], chunk[:, 2]),
                TRACK_RGB,
            )
            self._chunks += 1
            self._frozen_end = end
        live = np.array(track[self._frozen_end :])
        self._drawn = len(track)
        if len(live) < 2:
            canvas.remove("/track/live")
            return
        canvas.polyline("/track/live", ned_to_view(live[:, 0], live[:, 1], live[:, 2]), TRACK_RGB)

    def tail(self, pose: Point | None) -> None:
        """One segment from the last drawn track point to the vehicle at ``pose``."""
        if pose is None or self._drawn == 0:
            return
        a = self.points[self._drawn - 1]
        b = pose
        self._canvas.polyline(
            "/track/tail", ned_to_view([a[0], b[0]], [a[1], b[1]], [a[2], b[2]]), TRACK_RGB
        )
