"""A fleet's vehicles in the shared 3D view (backend/viewer/fleet.py): each vehicle's marker at
where the console believes it is, a ring when that is not the fix, and a label naming it, its
address, the command it is believed to run with p, and its position; drawn by each vehicle's
belief tracker. Without a fleet nothing is drawn under /fleet (the single vehicle's model and
/belief are as they were: test_belief.py, test_viewer.py)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import viser
from fastapi.testclient import TestClient

from backend.app import create_app
from backend.settings import Settings
from backend.viewer.belief import ring_points
from backend.viewer.fleet import FLEET_RGB, LABEL_UP_M, fleet_drawing
from backend.viewer.viewer import Viewer, ned_to_view
from tests.agent_link import TARGET, agent_fleet
from tests.backend.conftest import CIRCLE, TOKEN, wait_until
from tests.backend.viewer.test_viewer import cloud, label, lines, polyline, position, viewer
from vehicle_contract.fleet import parse_vehicles

__all__ = ["viewer"]  # the fixture


def test_each_vehicle_is_drawn_in_its_own_group_and_its_label_is_kept_clear_of(
    viewer: Viewer,
) -> None:
    viewer.draw_shared(fleet_drawing("auv1", "auv1 (address 1): hover", 0.0, 0.0, 2.0, None))
    viewer.draw_shared(fleet_drawing("auv2", "auv2 (address 2): circle", 3.0, 20.0, 1.0, 2.0))
    marker = cloud(viewer, "/fleet/auv1/marker")
    np.testing.assert_allclose(marker.points[0], ned_to_view(0.0, 0.0, 2.0))
    assert viewer.node("/fleet/auv1/ring") is None  # the fix: no ring
    assert label(viewer, "/fleet/auv1/label") == "auv1 (address 1): hover"
    ring = lines(viewer, "/fleet/auv2/ring")
    assert tuple(ring.colors) == FLEET_RGB
    np.testing.assert_allclose(polyline(ring), ring_points(3.0, 20.0, 1.0, 2.0), atol=1e-5)
    above = ned_to_view(3.0, 20.0, 1.0) + np.array([0.0, 0.0, LABEL_UP_M])
    np.testing.assert_allclose(position(viewer, "/fleet/auv2/label"), above)
    # a page's own labels keep clear of every vehicle's label
    shared = viewer.shared_label_positions()
    np.testing.assert_allclose(shared["/fleet/auv2/label"], above)
    assert "/fleet/auv1/label" in shared
    # drawn again: replaced, not added to
    viewer.draw_shared(fleet_drawing("auv2", "auv2 (address 2): surface", 4.0, 20.0, 0.0, None))
    redrawn = viewer.node_names("/fleet/auv2")
    assert redrawn == ["/fleet/auv2", "/fleet/auv2/label", "/fleet/auv2/marker"]
    assert label(viewer, "/fleet/auv2/label") == "auv2 (address 2): surface"


def test_a_position_that_is_not_finite_is_refused() -> None:
    with pytest.raises(ValueError, match="auv1"):
        fleet_drawing("auv1", "auv1", math.nan, 0.0, 0.0, None)


def fleet_labels(v: Viewer) -> dict[str, str]:
    out = {}
    for name in v.node_names("/fleet/"):
        node = v.node(name)
        if isinstance(node, viser.LabelHandle):
            out[name.split("/")[2]] = node.text
    return out


def test_a_fleet_console_draws_every_vehicle_where_it_is_believed_to_be(tmp_path: Path) -> None:
    """Five in-memory vehicles, 20 m apart eastwards: five markers and labels, each at its own
    vehicle's fix; a command to one changes only that one's label."""
    fleet = parse_vehicles("5")
    link = agent_fleet(fleet)
    settings = Settings(
        token=TOKEN,
        db_path=tmp_path / "log.sqlite3",
        viewer_port=0,
        target=TARGET,
        vehicles="5",
        allowed_hosts=["testserver"],
    )
    with TestClient(create_app(settings, viewer=True, link=link)) as client:
        console = client.app.state.console  # type: ignore[attr-defined]
        v: Viewer = console.viewer
        names = [f.name for f in fleet]
        drawn = wait_until(lambda: len(fleet_labels(v)) == 5 and fleet_labels(v))
        assert sorted(drawn) == names
        for i, f in enumerate(fleet):
            assert drawn[f.name].startswith(f"{f.name} (address {f.address})\nholding p 100 %\n")
            assert drawn[f.name].endswith(f"x 0.0 y {20.0 * i:.1f} m, depth 2.0 m (fix)")
            at = cloud(v, f"/fleet/{f.name}/marker").points[0]
            np.testing.assert_allclose(at, ned_to_view(0.0, 20.0 * i, 2.0), atol=1e-5)
        assert v.node_names("/belief") == []  # a fleet's beliefs are drawn per vehicle
        r = client.post(
            "/api/commands",
            json={"pattern": "circle", "params": CIRCLE, "vehicle": "auv3"},
            headers={"Authorization": f"Bearer {TOKEN}"},
        )
        assert r.status_code == 202, r.text
        wait_until(lambda: "auv3 (address 3)\ncircle p 100 %\n" in fleet_labels(v)["auv3"])
        others = fleet_labels(v)
        assert all("\nholding p" in others[n] for n in names if n != "auv3"), others
