"""The believed position in the shared 3D view, when it is not the last fix: a ring of its
uncertainty (``sigma_m``) at its depth and a label, dead-reckoned or assumed. Node names::

    /belief/ring, /belief/point, /belief/label

With telemetry fresh the group is removed: the vehicle model is the fix.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Final

import numpy as np

from backend.viewer.draw import WAYPOINT_M, Canvas, Rgb, ned_to_view

#: The believed position and its ring.
BELIEF_RGB: Final[Rgb] = (255, 110, 110)
#: Segments of the ring.
RING_SEGMENTS: Final = 64

#: Draws on the shared canvas (under the viewer's lock).
SharedDrawing = Callable[[Canvas], None]


def ring_points(x_m: float, y_m: float, z_m: float, radius_m: float) -> np.ndarray:
    """A horizontal circle of ``radius_m`` about the NED point, in the view frame
    (``RING_SEGMENTS + 1`` points, closed).

    Raises:
        ValueError: a non-finite coordinate, or a radius that is not a finite number > 0.
    """
    if not all(math.isfinite(v) for v in (x_m, y_m, z_m)):
        raise ValueError("belief ring: the position must be finite numbers")
    if not (math.isfinite(radius_m) and radius_m > 0):
        raise ValueError(f"belief ring: the radius must be a finite number > 0 m, got {radius_m}")
    a = np.linspace(0.0, 2.0 * math.pi, RING_SEGMENTS + 1)
    return ned_to_view(x_m + radius_m * np.cos(a), y_m + radius_m * np.sin(a), np.full_like(a, z_m))


def belief_drawing(
    x_m: float, y_m: float, z_m: float, sigma_m: float | None, label: str
) -> SharedDrawing:
    """The believed position (NED m) with its uncertainty ring (none when ``sigma_m`` is
    None: unknown) and ``label``.

    Raises:
        ValueError: as :func:`ring_points`.
    """
    ring = None if sigma_m is None else ring_points(x_m, y_m, z_m, max(sigma_m, 0.01))
    at = ned_to_view(x_m, y_m, z_m)

    def draw(c: Canvas) -> None:
        c.group("/belief")
        if ring is not None:
            c.polyline("/belief/ring", ring, BELIEF_RGB)
        c.points("/belief/point", at[None, :], BELIEF_RGB, 3 * WAYPOINT_M)
        c.label("/belief/label", label, at)

    return draw


def clear_belief(c: Canvas) -> None:
    """Remove the believed position (telemetry is fresh: the vehicle model is the fix)."""
    c.remove_group("/belief")
