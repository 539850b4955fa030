"""Each vehicle of a fleet in the shared 3D view (issue 23): a marker where the console believes
it is, the ring of that position's uncertainty when it is not the fix, and a label naming the
vehicle, its address, the command it is believed to run (with its probability) and where it
is. Node names, per vehicle::

    /fleet/<name>/marker, /fleet/<name>/ring, /fleet/<name>/label

Each vehicle's belief tracker (:mod:`backend.belief.tracker`) draws its own on every push, from
the belief alone: the view claims no more than the console believes. Without a fleet nothing
is drawn here: the single vehicle's model, track and ``/belief`` are as they always were.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np

from backend.viewer.belief import SharedDrawing, ring_points
from backend.viewer.draw import Canvas, Rgb, ned_to_view

__all__ = ["FLEET_RGB", "LABEL_UP_M", "MARKER_M", "fleet_drawing", "group_of"]

#: A fleet vehicle's marker, ring and label.
FLEET_RGB: Final[Rgb] = (90, 200, 255)
#: The marker's size (m): a point that reads at a few tens of metres.
MARKER_M: Final = 0.5
#: The label, above the marker (m, view frame): clear of the marker, and of the hull model's
#: own label (a fleet's first vehicle has the model too).
LABEL_UP_M: Final = 1.2

#: Where the position comes from, in the label's words.


def group_of(name: str) -> str:
    """The scene group of vehicle ``name`` (a fleet's name: ``[a-z][a-z0-9_]*``)."""
    return f"/fleet/{name}"


def fleet_drawing(
    name: str, label: str, x_m: float, y_m: float, z_m: float, sigma_m: float | None
) -> SharedDrawing:
    """Vehicle ``name``'s marker at the NED point, its ring of ``sigma_m`` (none: the fix, or
    unknown) and ``label`` (replaces what was drawn of it).

    Raises:
        ValueError: a non-finite position.
    """
    if not all(math.isfinite(v) for v in (x_m, y_m, z_m)):
        raise ValueError(f"fleet vehicle {name}: the position must be finite numbers")
    ring = None if sigma_m is None else ring_points(x_m, y_m, z_m, max(sigma_m, 0.01))
    at = ned_to_view(x_m, y_m, z_m)
    group = group_of(name)
    above = at + np.array([0.0, 0.0, LABEL_UP_M])

    def draw(c: Canvas) -> None:
        c.group(group)
        c.points(f"{group}/marker", at[None, :], FLEET_RGB, MARKER_M)
        if ring is not None:
            c.polyline(f"{group}/ring", ring, FLEET_RGB)
        c.label(f"{group}/label", label, above)

    return draw
