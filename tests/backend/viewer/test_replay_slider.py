"""The replay in a page's 3D view: its labels kept apart at the dive's own scale, and the
slider's marker (backend/viewer/paths.py, views.py, viewer.py)."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest

from backend.viewer.labels import min_separation_m
from backend.viewer.paths import REPLAY_LABELS_ACROSS
from backend.viewer.viewer import Viewer
from tests.backend.viewer.test_viewer import In, cloud, label, lines
from tests.backend.viewer.test_views import FakePage

VIEW = "replay-slider-view-01"


@pytest.fixture
def page() -> Iterator[In]:
    v = Viewer(port=0, track_redraw_interval_s=0.0)
    p = FakePage(v, VIEW)
    try:
        yield In(v, VIEW)
    finally:
        p.close()
        v.stop()


def test_a_long_dives_labels_are_thinned_to_its_scale(page: In) -> None:
    # 200 m east, a command every 5 m: at the 3 m of the shared declutter they would all stay
    track = [(float(t), 0.0, float(t), 2.0, 90.0) for t in range(201)]
    cmds = [(float(t), 0.0, float(t), 2.0, f"#{k}") for k, t in enumerate(range(0, 200, 5))]
    page.viewer.show_replay(VIEW, track, cmds)
    own = page.viewer.view_labels(VIEW)
    assert min_separation_m([s.position for s in own]) >= 200 / REPLAY_LABELS_ACROSS - 1e-9
    assert not any(s.merged for s in own)  # thinned, not merged into long texts
    # every command keeps its marker; the start label says how many labels were left out
    assert len(cloud(page, "/replay/commands").points) == 40
    kept = sum(1 for s in own if s.name.startswith("/replay/cmd_"))
    assert label(page, "/replay/start") == f"replay start ({40 - kept} commands unlabelled)"
    assert label(page, "/replay/end") == "end, 200 s"


def test_a_small_dive_has_one_label_for_its_start_and_end(page: In) -> None:
    track = [(float(t), 0.5 * math.sin(t / 5), 0.5 * math.cos(t / 5), 2.0, 0.0) for t in range(60)]
    page.viewer.show_replay(VIEW, track, [(10.0, 0.1, 0.4, 2.0, "#1")])
    names = {s.name: s.shown for s in page.viewer.view_labels(VIEW)}
    assert names == {"/replay/start": "replay, 0-59 s (1 command unlabelled)"}


def test_the_slider_marker_moves_without_touching_the_labels(page: In) -> None:
    track = [(float(t), float(t), 0.0, 2.0, 0.0) for t in range(30)]
    page.viewer.show_replay(VIEW, track, [(5.0, 5.0, 0.0, 2.0, "#1")])
    labels = {s.name: s.position for s in page.viewer.view_labels(VIEW)}
    page.viewer.show_replay_at(VIEW, 10.0, 2.0, 3.0, 90.0)
    marker = cloud(page, "/replay_at/vehicle")
    np.testing.assert_allclose(marker.points, [(2.0, 10.0, -3.0)])
    nose = lines(page, "/replay_at/heading").points[0]
    np.testing.assert_allclose(nose[1] - nose[0], (2.0, 0.0, 0.0), atol=1e-6)  # east: 90 deg
    page.viewer.show_replay_at(VIEW, 20.0, 0.0, 1.0, 0.0)  # moved: replaced, not added
    np.testing.assert_allclose(cloud(page, "/replay_at/vehicle").points, [(0.0, 20.0, -1.0)])
    assert page.node_names("/replay_at") == [
        "/replay_at",
        "/replay_at/heading",
        "/replay_at/vehicle",
    ]
    assert {s.name: s.position for s in page.viewer.view_labels(VIEW)} == labels
    with pytest.raises(ValueError, match="finite"):
        page.viewer.show_replay_at(VIEW, math.nan, 0.0, 0.0, 0.0)
    assert page.viewer.clear_replay(VIEW) is True  # the marker goes with the replay
    assert page.node_names("/replay") == [] and page.node_names("/replay_at") == []
