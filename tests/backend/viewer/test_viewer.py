"""The 3D viewer: NED -> view conversion, the vehicle's attitude quaternion, and a real viser
server on an OS-chosen port whose scene nodes are checked through their handle properties.
Previews, scripts and replays are drawn in a page's own view: here one connected page
(:class:`tests.backend.viewer.test_views.FakePage`), its nodes looked up through :class:`In`."""

from __future__ import annotations

import inspect
import math
import socket
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import numpy.typing as npt
import pytest
import viser
import viser.transforms as vtf

import backend.viewer.client_page
import backend.viewer.draw
import backend.viewer.labels
import backend.viewer.paths
import backend.viewer.scene
import backend.viewer.track
import backend.viewer.viewer
import backend.viewer.views
from backend.viewer.client_page import client_html_path
from backend.viewer.viewer import (
    ACTIVE_RGB,
    PREVIEW_BODY_RGB,
    PREVIEW_JOIN_RGB,
    REPLAY_COMMAND_RGB,
    REPLAY_RGB,
    SCRIPT_RGB,
    TRACK_RGB,
    Viewer,
    attitude_to_view_wxyz,
    ned_to_view,
)
from tests.backend.viewer.test_views import FakePage

VIEW = "unit-test-view-01"

# --- frames -------------------------------------------------------------------------------


def test_ned_to_view_north_east_depth() -> None:
    np.testing.assert_array_equal(ned_to_view(1.0, 0.0, 0.0), [0.0, 1.0, 0.0])  # north: +y
    np.testing.assert_array_equal(ned_to_view(0.0, 1.0, 0.0), [1.0, 0.0, 0.0])  # east: +x
    np.testing.assert_array_equal(ned_to_view(0.0, 0.0, 3.0), [0.0, 0.0, -3.0])  # depth: -z
    np.testing.assert_array_equal(ned_to_view(2.0, -5.0, 1.5), [-5.0, 2.0, -1.5])


def test_ned_to_view_is_vectorised() -> None:
    xs, ys, zs = (1.0, 2.0, 3.0, 4.0), (10.0, 20.0, 30.0, 40.0), (0.0, 0.5, 1.0, 2.0)
    view = ned_to_view(xs, ys, zs)
    assert view.shape == (4, 3)
    np.testing.assert_array_equal(view[:, 0], ys)
    np.testing.assert_array_equal(view[:, 1], xs)
    np.testing.assert_array_equal(view[:, 2], [0.0, -0.5, -1.0, -2.0])
    assert not np.signbit(view[0, 2])  # the surface is +0.0, not -0.0
    assert ned_to_view(np.zeros((2, 5)), np.ones((2, 5)), np.ones((2, 5))).shape == (2, 5, 3)


def nose_and_starboard(
    heading_deg: float, roll_deg: float = 0.0
) -> tuple[npt.NDArray[np.floating], npt.NDArray[np.floating]]:
    """Where the body's nose (+x) and starboard side (-y) point in the view frame."""
    rot = vtf.SO3(wxyz=np.array(attitude_to_view_wxyz(heading_deg, roll_deg)))
    return rot.apply(np.array([1.0, 0.0, 0.0])), rot.apply(np.array([0.0, -1.0, 0.0]))


def level_ned(heading_deg: float) -> tuple[float, float, float]:
    """A level unit vector in NED pointing along ``heading_deg`` (clockwise from north)."""
    h = math.radians(heading_deg)
    return math.cos(h), math.sin(h), 0.0


@pytest.mark.parametrize(
    ("heading_deg", "nose_view"),
    [
        (0.0, (0.0, 1.0, 0.0)),  # north: view +y
        (90.0, (1.0, 0.0, 0.0)),  # east: view +x
        (180.0, (0.0, -1.0, 0.0)),  # south: view -y
        (270.0, (-1.0, 0.0, 0.0)),  # west: view -x
        (45.0, (math.sqrt(0.5), math.sqrt(0.5), 0.0)),  # north-east
    ],
)
def test_heading_points_the_nose(heading_deg: float, nose_view: tuple[float, float, float]) -> None:
    q = attitude_to_view_wxyz(heading_deg)
    assert math.isclose(sum(c * c for c in q), 1.0)
    nose, starboard = nose_and_starboard(heading_deg)
    np.testing.assert_allclose(nose, nose_view, atol=1e-12)
    np.testing.assert_allclose(nose, ned_to_view(*level_ned(heading_deg)), atol=1e-12)
    # starboard is 90 degrees clockwise of the nose, level
    np.testing.assert_allclose(starboard, ned_to_view(*level_ned(heading_deg + 90.0)), atol=1e-12)


def test_heading_quaternions_0_90_180() -> None:
    s = math.sqrt(0.5)
    np.testing.assert_allclose(attitude_to_view_wxyz(0.0), (s, 0.0, 0.0, s), atol=1e-12)
    np.testing.assert_allclose(attitude_to_view_wxyz(90.0), (1.0, 0.0, 0.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(attitude_to_view_wxyz(180.0), (s, 0.0, 0.0, -s), atol=1e-12)


def test_positive_roll_puts_starboard_down_and_keeps_the_nose() -> None:
    nose, starboard = nose_and_starboard(0.0, 30.0)
    np.testing.assert_allclose(nose, (0.0, 1.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(starboard, (math.cos(math.radians(30)), 0.0, -0.5), atol=1e-12)


# --- the server ---------------------------------------------------------------------------


@pytest.fixture
def viewer() -> Iterator[Viewer]:
    v = Viewer(port=0, track_redraw_interval_s=0.0, track_chunk_segments=5)
    try:
        yield v
    finally:
        v.stop()


class Nodes(Protocol):
    def node(self, name: str) -> viser.SceneNodeHandle | None: ...


@dataclass
class In:
    """One page's own view of the viewer (its preview, script, replay)."""

    viewer: Viewer
    view: str

    def node(self, name: str) -> viser.SceneNodeHandle | None:
        return self.viewer.view_node(self.view, name)

    def node_names(self, prefix: str = "/") -> list[str]:
        return self.viewer.view_node_names(self.view, prefix)


@pytest.fixture
def page(viewer: Viewer) -> Iterator[In]:
    p = FakePage(viewer, VIEW)
    try:
        yield In(viewer, VIEW)
    finally:
        p.close()


def lines(v: Nodes, name: str) -> viser.LineSegmentsHandle:
    h = v.node(name)
    assert isinstance(h, viser.LineSegmentsHandle), name
    return h


def cloud(v: Nodes, name: str) -> viser.PointCloudHandle:
    h = v.node(name)
    assert isinstance(h, viser.PointCloudHandle), name
    return h


def label(v: Nodes, name: str) -> str:
    h = v.node(name)
    assert isinstance(h, viser.LabelHandle), name
    return h.text


def position(v: Nodes, name: str) -> npt.NDArray[np.float64]:
    h = v.node(name)
    assert h is not None, name
    return h.position


def polyline(h: viser.LineSegmentsHandle) -> npt.NDArray[np.float32]:
    """The points of a polyline drawn as consecutive segments (checks they join up)."""
    pts = h.points
    np.testing.assert_array_equal(pts[1:, 0], pts[:-1, 1])
    return np.concatenate([pts[:, 0], pts[-1:, 1]])


def test_server_port_url_and_client_page(viewer: Viewer) -> None:
    assert viewer.port > 0
    assert viewer.url == f"http://127.0.0.1:{viewer.port}"
    assert viewer.websocket_url == f"ws://127.0.0.1:{viewer.port}"
    page = client_html_path()
    assert page.name == "index.html" and page.parent.name == "build" and page.is_file()
    assert Viewer.client_html_path() == page
    # the static scene is there; the vehicle waits for its first pose
    for name in ("/surface/grid", "/scale/axes", "/scale/depth", "/vehicle/hull"):
        assert viewer.node(name) is not None, name
    assert label(viewer, "/scale/north") == "N" and label(viewer, "/scale/east") == "E"
    np.testing.assert_array_equal(position(viewer, "/scale/north"), (0.0, 11.0, 0.0))
    assert label(viewer, "/scale/depth_10m") == "10 m"
    vehicle = viewer.node("/vehicle")
    assert vehicle is not None and not vehicle.visible


def test_stop_frees_the_port_and_threads() -> None:
    before = set(threading.enumerate())
    v = Viewer()
    port = v.port
    v.stop()
    v.stop()  # idempotent
    with socket.socket() as s:
        s.bind(("127.0.0.1", port))
    deadline = time.monotonic() + 2.0
    while set(threading.enumerate()) - before and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not set(threading.enumerate()) - before
    v.update_pose(0.0, 1.0, 1.0, 1.0, 0.0, 0.0)  # ignored once stopped


def test_show_preview_draws_join_body_waypoints_and_depth(viewer: Viewer, page: In) -> None:
    xs = (0.0, 2.0, 4.0, 4.0, 8.0, 8.0)
    ys = (0.0, 0.0, 1.0, 5.0, 5.0, 1.0)
    zs = (0.0, 1.0, 2.0, 2.0, 3.0, 3.0)
    viewer.show_preview(VIEW, xs, ys, zs, body_start=2, label="square")
    view = ned_to_view(xs, ys, zs).astype(np.float32)
    assert viewer.node_names("/preview") == []  # not in the shared scene

    join, body = lines(page, "/preview/join"), lines(page, "/preview/body")
    assert join.points.dtype == np.float32 and join.points.shape == (2, 2, 3)
    assert body.points.shape == (3, 2, 3)
    np.testing.assert_array_equal(polyline(join), view[:3])
    np.testing.assert_array_equal(polyline(body), view[2:])
    assert tuple(join.colors) == PREVIEW_JOIN_RGB and tuple(body.colors) == PREVIEW_BODY_RGB
    assert join.thickness_units == "screen" and body.thickness_units == "screen"
    assert 2.0 <= body.thickness <= 4.0

    wp = cloud(page, "/preview/waypoints")
    assert wp.precision == "float32" and wp.points.dtype == np.float32
    np.testing.assert_array_equal(wp.points, view)
    assert tuple(wp.colors[0]) == PREVIEW_JOIN_RGB and tuple(wp.colors[-1]) == PREVIEW_BODY_RGB

    # drop lines from the surface to every waypoint below it (a short path: all of them)
    drops = lines(page, "/preview/drops").points
    assert len(drops) == 5
    np.testing.assert_array_equal(drops[:, 0, 2], 0.0)
    np.testing.assert_array_equal(drops[:, 1], view[1:])

    # labels 3 m apart at least (no vehicle yet: the start keeps its own)
    assert label(page, "/preview/start") == "square start, depth 0.0 m"
    assert label(page, "/preview/end") == "square end, depth 3.0 m"
    assert label(page, "/preview/pattern") == "pattern, depth 2.0 m"
    np.testing.assert_array_equal(position(page, "/preview/end"), view[-1])


def test_preview_is_replaced_and_cleared(viewer: Viewer, page: In) -> None:
    viewer.show_preview(VIEW, (0.0, 1.0, 2.0), (0.0, 0.0, 0.0), (1.0, 1.0, 1.0), body_start=1)
    assert page.node("/preview/join") is not None
    # no join this time: the old join and pattern label must not survive
    many = np.linspace(0.0, 99.0, 100)
    viewer.show_preview(VIEW, many, np.zeros(100), np.full(100, 2.0), body_start=0, label="line")
    assert page.node("/preview/join") is None
    assert page.node("/preview/pattern") is None
    assert lines(page, "/preview/body").points.shape == (99, 2, 3)
    assert cloud(page, "/preview/waypoints").points.shape == (100, 3)
    assert len(lines(page, "/preview/drops").points) <= 25  # decimated
    body = page.node("/preview/body")
    assert viewer.clear_preview(VIEW) is True
    assert page.node_names("/preview") == []
    assert body is not None
    assert viewer.clear_preview(VIEW) is False  # nothing left: a no-op


def test_preview_rejects_bad_input(viewer: Viewer, page: In) -> None:
    with pytest.raises(ValueError, match="equal length"):
        viewer.show_preview(VIEW, (0.0, 1.0), (0.0,), (0.0, 0.0))
    with pytest.raises(ValueError, match="equal length"):
        viewer.show_preview(VIEW, (), (), ())
    with pytest.raises(ValueError, match="finite"):
        viewer.show_preview(VIEW, (0.0, math.nan), (0.0, 0.0), (0.0, 0.0))
    with pytest.raises(ValueError, match="body_start"):
        viewer.show_preview(VIEW, (0.0, 1.0), (0.0, 0.0), (0.0, 0.0), body_start=2)
    assert page.node_names() == []  # nothing drawn by a refused preview
    viewer.show_preview(VIEW, (5.0,), (5.0,), (1.0,))  # one waypoint: a marker, no line
    assert page.node("/preview/body") is None
    assert cloud(page, "/preview/waypoints").points.shape == (1, 3)


def test_show_active(viewer: Viewer) -> None:
    viewer.show_active((0.0, 10.0, 10.0), (0.0, 0.0, 10.0), (1.0, 2.0, 2.0), label="lawnmower")
    path = lines(viewer, "/active/path")
    assert tuple(path.colors) == ACTIVE_RGB
    np.testing.assert_array_equal(
        polyline(path), ned_to_view((0.0, 10.0, 10.0), (0.0, 0.0, 10.0), (1.0, 2.0, 2.0))
    )
    assert label(viewer, "/active/label") == "lawnmower (depth 1.0-2.0 m)"
    viewer.clear_active()
    assert viewer.node_names("/active") == []


def test_update_pose_moves_the_vehicle(viewer: Viewer) -> None:
    viewer.update_pose(12.0, 3.0, 4.0, 2.5, 10.0, 90.0)
    vehicle = viewer.node("/vehicle")
    assert vehicle is not None and vehicle.visible
    np.testing.assert_allclose(vehicle.position, (4.0, 3.0, -2.5))
    np.testing.assert_allclose(vehicle.wxyz, attitude_to_view_wxyz(90.0, 10.0))
    hull = viewer.node("/vehicle/hull")
    assert isinstance(hull, viser.BoxHandle)
    np.testing.assert_allclose(hull.dimensions, (0.6, 0.3, 0.25))
    assert label(viewer, "/vehicle/info") == "t 12 s, depth 2.5 m, hdg 90"
    viewer.update_pose(13.0, 1.0, 2.0, 0.0, 0.0, 180.0)
    np.testing.assert_allclose(vehicle.position, (2.0, 1.0, 0.0))
    np.testing.assert_allclose(vehicle.wxyz, attitude_to_view_wxyz(180.0), atol=1e-12)
    viewer.update_pose(14.0, math.nan, 2.0, 0.0, 0.0, 180.0)  # ignored
    np.testing.assert_allclose(vehicle.position, (2.0, 1.0, 0.0))


def test_track_decimates_by_distance(viewer: Viewer) -> None:
    for i in range(200):  # 200 moves of 1 mm: under the 5 cm step
        viewer.update_pose(i * 0.05, i * 0.001, 0.0, 1.0, 0.0, 0.0)
    assert len(viewer.track_ned_m) == 4  # 0, 0.051, 0.102, 0.153 m
    viewer.update_pose(10.0, 20.0, 0.0, 1.0, 0.0, 0.0)  # one long move: one more point
    track = viewer.track_ned_m
    assert len(track) == 5
    np.testing.assert_allclose(track[-1], (20.0, 0.0, 1.0))
    np.testing.assert_array_equal(polyline(lines(viewer, "/track/live"))[-1], (0.0, 20.0, -1.0))
    # the tail joins the last drawn point to the vehicle
    np.testing.assert_array_equal(lines(viewer, "/track/tail").points[0, 1], (0.0, 20.0, -1.0))
    assert tuple(lines(viewer, "/track/live").colors) == TRACK_RGB


def test_track_is_drawn_in_chunks_that_join_up(viewer: Viewer) -> None:
    for i in range(13):  # 12 segments, chunks of 5
        viewer.update_pose(float(i), float(i), 0.0, 2.0, 0.0, 0.0)
    assert viewer.node_names("/track/") == [
        "/track/chunk_0000", "/track/chunk_0001", "/track/live", "/track/tail",
    ]  # fmt: skip
    drawn = [
        polyline(lines(viewer, name))
        for name in ("/track/chunk_0000", "/track/chunk_0001", "/track/live")
    ]
    assert [len(p) for p in drawn] == [6, 6, 3]
    np.testing.assert_array_equal(drawn[0][-1], drawn[1][0])
    np.testing.assert_array_equal(drawn[1][-1], drawn[2][0])
    whole = np.concatenate([drawn[0], drawn[1][1:], drawn[2][1:]])
    np.testing.assert_array_equal(
        whole, ned_to_view(np.arange(13.0), np.zeros(13), np.full(13, 2.0))
    )


def test_track_redraw_is_throttled_but_the_tail_follows() -> None:
    with Viewer(track_redraw_interval_s=3600.0) as v:
        for i in range(10):
            v.update_pose(float(i), float(i), 0.0, 1.0, 0.0, 0.0)
        assert len(v.track_ned_m) == 10
        assert v.node("/track/live") is None  # only the first point was drawn so far
        tail = lines(v, "/track/tail").points
        np.testing.assert_array_equal(tail[0], [(0.0, 0.0, -1.0), (0.0, 9.0, -1.0)])
        v.flush_track()
        assert len(polyline(lines(v, "/track/live"))) == 10


def test_track_keeps_at_most_max_points() -> None:
    with Viewer(max_track_points=10, track_redraw_interval_s=0.0) as v:
        for i in range(50):
            v.update_pose(float(i), float(i), 0.0, 1.0, 0.0, 0.0)
        track = v.track_ned_m
        assert 4 <= len(track) <= 10
        np.testing.assert_array_equal(track[-1], (49.0, 0.0, 1.0))
        assert (np.diff(track[:, 0]) > 0).all()  # still in order
        assert len(polyline(lines(v, "/track/live"))) == len(track)


def test_reset_track(viewer: Viewer) -> None:
    for i in range(8):
        viewer.update_pose(float(i), float(i), 1.0, 1.0, 0.0, 0.0)
    assert viewer.node_names("/track/")
    viewer.reset_track()
    assert viewer.node_names("/track") == []
    assert len(viewer.track_ned_m) == 0
    viewer.update_pose(9.0, 30.0, 1.0, 1.0, 0.0, 0.0)  # a fresh track starts here
    np.testing.assert_array_equal(viewer.track_ned_m, [(30.0, 1.0, 1.0)])
    vehicle = viewer.node("/vehicle")
    assert vehicle is not None and vehicle.visible  # the vehicle stays


def test_concurrent_poses_are_safe(viewer: Viewer) -> None:
    def fly(k: int) -> None:
        for i in range(100):
            viewer.update_pose(float(i), float(i), float(k), 1.0, 0.0, 0.0)

    threads = [threading.Thread(target=fly, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    viewer.flush_track()
    drawn = sum(
        len(lines(viewer, n).points) for n in viewer.node_names("/track/") if n != "/track/tail"
    )
    assert drawn == len(viewer.track_ned_m) - 1


def test_show_replay(viewer: Viewer, page: In) -> None:
    track = [(float(t), float(t), 2.0, 3.0, 0.0) for t in range(30)]
    commands = [(5.0, 5.0, 2.0, 3.0, "square"), (20.0, 20.0, 2.0, 3.0, "surface")]
    viewer.show_replay(VIEW, track, commands)
    line = lines(page, "/replay/track")
    assert line.points.shape == (29, 2, 3) and tuple(line.colors) == REPLAY_RGB
    markers = cloud(page, "/replay/commands")
    assert markers.points.dtype == np.float32 and tuple(markers.colors) == REPLAY_COMMAND_RGB
    np.testing.assert_array_equal(markers.points, [(2.0, 5.0, -3.0), (2.0, 20.0, -3.0)])
    assert label(page, "/replay/cmd_000") == "square"
    assert label(page, "/replay/cmd_001") == "surface"
    assert label(page, "/replay/start") == "replay start"
    assert label(page, "/replay/end") == "end, 29 s"
    viewer.show_replay(VIEW, track[:2])  # replaces: no commands this time
    assert page.node("/replay/commands") is None and page.node("/replay/cmd_000") is None
    assert viewer.clear_replay(VIEW) is True
    assert page.node_names("/replay") == []


def test_long_replay_is_subsampled() -> None:
    with Viewer(max_track_points=100) as v:
        p = FakePage(v, VIEW)
        v.show_replay(VIEW, [(float(t), float(t), 0.0, 1.0, 0.0) for t in range(1000)])
        pts = polyline(lines(In(v, VIEW), "/replay/track"))
        p.close()
        assert len(pts) == 100
        np.testing.assert_array_equal(pts[0], (0.0, 0.0, -1.0))
        np.testing.assert_array_equal(pts[-1], (0.0, 999.0, -1.0))


def test_show_script(viewer: Viewer, page: In) -> None:
    viewer.show_script(
        VIEW, (0.0, 10.0, 10.0, 0.0), (0.0, 0.0, 10.0, 10.0), (1.0, 1.0, 4.0, 4.0),
        [(0, "1 straight"), (2, "2 hover")],
    )  # fmt: skip
    assert tuple(lines(page, "/script/path").colors) == SCRIPT_RGB
    np.testing.assert_array_equal(
        cloud(page, "/script/steps").points, [(0.0, 0.0, -1.0), (10.0, 10.0, -4.0)]
    )
    assert label(page, "/script/step_000") == "1 straight (1.0 m)"
    assert label(page, "/script/step_001") == "2 hover (4.0 m)"
    with pytest.raises(ValueError, match="step start"):
        viewer.show_script(VIEW, (0.0,), (0.0,), (0.0,), [(3, "x")])
    assert viewer.clear_script(VIEW) is True
    assert page.node_names("/script") == []


VIEWER_MODULES = (
    backend.viewer.viewer, backend.viewer.draw, backend.viewer.labels, backend.viewer.paths,
    backend.viewer.scene, backend.viewer.track, backend.viewer.views, backend.viewer.client_page,
)  # fmt: skip


@pytest.mark.parametrize("module", VIEWER_MODULES, ids=lambda m: m.__name__)
def test_the_viewer_registers_no_callbacks(module: object) -> None:
    """Display only (viser's port has no authentication): a guard on the modules' source. Only
    viewer_views hears of clients connecting and leaving (to know which page is which view)."""
    source = inspect.getsource(module)  # type: ignore[arg-type]
    forbidden = [
        "on_click", "on_update", "on_drag", "on_client_connect", "on_client_disconnect",
        "add_button", "add_transform_controls", "add_text(", "add_number", "add_checkbox",
        "add_slider", "add_dropdown", "add_upload", "request_share_url", "on_camera_update",
        "on_scene_pointer", "register_handler",
    ]  # fmt: skip
    if module is backend.viewer.views:
        forbidden.remove("on_client_connect")
        forbidden.remove("on_client_disconnect")
    for word in forbidden:
        assert word not in source, word
