"""The believed position in the shared 3D view (backend/viewer/belief.py): a ring of radius
``sigma_m`` at its depth, a point and a label; none of it when the fix is fresh."""

from __future__ import annotations

import math

import numpy as np
import pytest

from backend.viewer.belief import (
    BELIEF_RGB,
    RING_SEGMENTS,
    belief_drawing,
    clear_belief,
    ring_points,
)
from backend.viewer.viewer import Viewer, ned_to_view
from tests.backend.viewer.test_viewer import label, lines, polyline, viewer

__all__ = ["viewer"]  # the fixture


def test_the_ring_is_sigma_about_the_position_at_its_depth() -> None:
    pts = ring_points(3.0, 4.0, 2.5, 1.5)
    assert pts.shape == (RING_SEGMENTS + 1, 3)
    np.testing.assert_allclose(pts[0], pts[-1])  # closed
    centre = ned_to_view(3.0, 4.0, 2.5)
    np.testing.assert_allclose(np.hypot(pts[:, 0] - centre[0], pts[:, 1] - centre[1]), 1.5)
    np.testing.assert_allclose(pts[:, 2], -2.5)


@pytest.mark.parametrize(("where", "radius"), [((math.nan, 0, 0), 1.0), ((0, 0, 0), 0.0)])
def test_a_bad_ring_is_refused(where: tuple[float, float, float], radius: float) -> None:
    with pytest.raises(ValueError, match="belief ring"):
        ring_points(*where, radius)


def test_drawn_and_cleared_in_the_shared_scene(viewer: Viewer) -> None:
    viewer.draw_shared(belief_drawing(3.0, 4.0, 2.5, 1.5, "believed (dead reckoning, +-1.5 m)"))
    ring = lines(viewer, "/belief/ring")
    assert tuple(ring.colors) == BELIEF_RGB
    np.testing.assert_allclose(polyline(ring), ring_points(3.0, 4.0, 2.5, 1.5), atol=1e-5)
    assert label(viewer, "/belief/label") == "believed (dead reckoning, +-1.5 m)"
    viewer.draw_shared(belief_drawing(0.0, 0.0, 2.0, None, "believed (assumed)"))
    assert viewer.node("/belief/ring") is None  # an assumed start: no uncertainty to draw
    assert label(viewer, "/belief/label") == "believed (assumed)"
    viewer.draw_shared(clear_belief)
    assert viewer.node_names("/belief") == []
