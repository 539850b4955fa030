"""Per-page 3D views: each page's preview, script preview and replay are drawn in its own viser
client's scene only, and labels are decluttered.

Pages are real websocket clients of a real viser server (:class:`FakePage`): they connect with
``/view/<id>`` as a page does, and every scene message they receive is decoded, so a test sees
what each page's 3D view was sent, beside the viewer's own per-view node listing.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator

import msgspec
import numpy as np
import pytest
import viser
import zstandard
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect

from backend.viewer.ids import view_id_from_path
from backend.viewer.labels import (
    MAX_VIEW_LABELS,
    MIN_LABEL_SEPARATION_M,
    LabelSpec,
    declutter,
    min_separation_m,
)
from backend.viewer.viewer import Viewer, ned_to_view
from backend.viewer.views import websocket_path
from tests.backend.conftest import wait_until

#: The camera message a browser sends first: viser counts a client as connected after it.
CAMERA = {
    "type": "ViewerCameraMessage",
    "wxyz": [1.0, 0.0, 0.0, 0.0],
    "position": [0.0, -18.0, 17.0],
    "fov": 1.0,
    "near": 0.01,
    "far": 1000.0,
    "image_height": 600,
    "image_width": 800,
    "look_at": [0.0, 0.0, 0.0],
    "up_direction": [0.0, 0.0, 1.0],
}
OPERATOR, OBSERVER = "operator-view-0001", "observer-view-0002"
LAWNMOWER = (
    [0.0, 10.0, 10.0, 0.0, 0.0, 10.0],
    [0.0, 0.0, 2.0, 2.0, 4.0, 4.0],
    [0.0, 3.0, 3.0, 3.0, 3.0, 3.0],
)
SPIRAL = ([0.0, 3.0, 0.0, -6.0, 0.0], [0.0, 0.0, 6.0, 0.0, -9.0], [0.0, 2.0, 2.0, 2.0, 2.0])


def decode(raw: bytes) -> list[dict[str, object]]:
    """viser's server -> client frame: [8 B size][8 B compressed size][zstd msgpack]..."""
    size = int.from_bytes(raw[0:8], "little")
    packed = int.from_bytes(raw[8:16], "little")
    body = zstandard.ZstdDecompressor().decompress(raw[16 : 16 + packed], max_output_size=size)
    window = msgspec.msgpack.decode(body)
    messages: list[dict[str, object]] = window["messages"]
    return messages


class FakePage:
    """A page's 3D view: a viser client on ``ws://host:port/view/<view_id>`` that keeps the
    scene it was sent (node name -> the message that made it)."""

    def __init__(self, viewer: Viewer, view_id: str) -> None:
        self.view_id = view_id
        self.scene: dict[str, dict[str, object]] = {}
        self._lock = threading.Lock()
        self._ws: ClientConnection = connect(
            f"{viewer.websocket_url}/view/{view_id}",
            subprotocols=[f"viser-v{viser.__version__}"],  # type: ignore[list-item]
        )
        self._ws.send(msgspec.msgpack.encode(CAMERA))
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        wait_until(lambda: view_id in viewer.view_ids(), what=f"view {view_id} connected")

    def _read(self) -> None:
        try:
            for raw in self._ws:
                if isinstance(raw, bytes):
                    for m in decode(raw):
                        self._apply(m)
        except ConnectionClosed:
            pass

    def _apply(self, m: dict[str, object]) -> None:
        name = m.get("name")
        if not isinstance(name, str):
            return
        with self._lock:
            if m.get("type") == "RemoveSceneNodeMessage":
                for n in [n for n in self.scene if n == name or n.startswith(name + "/")]:
                    del self.scene[n]
            elif "props" in m:
                self.scene[name] = m

    def names(self, prefix: str) -> list[str]:
        with self._lock:
            return sorted(n for n in self.scene if n.startswith(prefix))

    def label_names(self) -> set[str]:
        """The labels the page shows (its own and the shared scene's)."""
        with self._lock:
            return {n for n, m in self.scene.items() if m.get("type") == "LabelMessage"}

    def text(self, name: str) -> str:
        with self._lock:
            props = self.scene[name]["props"]
        assert isinstance(props, dict)
        return str(props["text"])

    def close(self) -> None:
        self._ws.close()
        self._reader.join(5.0)


@pytest.fixture
def viewer() -> Iterator[Viewer]:
    v = Viewer(port=0, track_redraw_interval_s=0.0)
    try:
        yield v
    finally:
        v.stop()


@pytest.fixture
def pages(viewer: Viewer) -> Iterator[tuple[FakePage, FakePage]]:
    a, b = FakePage(viewer, OPERATOR), FakePage(viewer, OBSERVER)
    try:
        yield a, b
    finally:
        a.close()
        b.close()


# --- the view id, and viser's internals it relies on -------------------------------------------


def test_view_id_from_the_websocket_path() -> None:
    assert view_id_from_path("/view/0123456789abcdef") == "0123456789abcdef"
    assert view_id_from_path("/view/0123456789abcdef/") == "0123456789abcdef"
    for path in (None, "", "/", "/view/", "/view/short", "/view/bad id!x", "/x/0123456789"):
        assert view_id_from_path(path) is None, path


def test_viser_keeps_the_websocket_path_where_websocket_path_reads_it(viewer: Viewer) -> None:
    """Fails loudly if viser stops keeping its raw connections (the one private access)."""
    page = FakePage(viewer, OPERATOR)
    try:
        (client_id,) = viewer.server.get_clients()
        assert websocket_path(viewer.server, client_id) == f"/view/{OPERATOR}"
        assert websocket_path(viewer.server, client_id + 1000) is None
    finally:
        page.close()


# --- per-view drawing ---------------------------------------------------------------------


def test_each_page_sees_only_its_own_preview(
    viewer: Viewer, pages: tuple[FakePage, FakePage]
) -> None:
    operator, observer = pages
    viewer.show_preview(OPERATOR, *LAWNMOWER, body_start=1, label="preview: lawnmower")
    viewer.show_preview(OBSERVER, *SPIRAL, body_start=1, label="preview: spiral")
    # the viewer's own listing, per view
    assert "/preview/body" in viewer.view_node_names(OPERATOR, "/preview")
    end = viewer.view_node(OPERATOR, "/preview/end")
    assert isinstance(end, viser.LabelHandle) and "lawnmower" in end.text
    spiral = viewer.view_node(OBSERVER, "/preview/end")
    assert isinstance(spiral, viser.LabelHandle) and "spiral" in spiral.text
    assert viewer.node_names("/preview") == []  # nothing in the shared scene
    # what each page was sent
    wait_until(lambda: "/preview/end" in operator.names("/preview"), what="operator's preview")
    wait_until(lambda: "/preview/end" in observer.names("/preview"), what="observer's preview")
    assert "lawnmower" in operator.text("/preview/end")
    assert "spiral" in observer.text("/preview/end")
    body = viewer.view_node(OPERATOR, "/preview/body")
    assert isinstance(body, viser.LineSegmentsHandle)
    np.testing.assert_allclose(body.points[-1, 1], ned_to_view(10.0, 4.0, 3.0))
    # the observer's next preview leaves the operator's alone
    viewer.show_preview(OBSERVER, *SPIRAL, body_start=2, label="preview: spiral 2")
    wait_until(lambda: "spiral 2" in observer.text("/preview/end"), what="observer's 2nd preview")
    assert "lawnmower" in operator.text("/preview/end")
    end = viewer.view_node(OPERATOR, "/preview/end")
    assert isinstance(end, viser.LabelHandle) and "lawnmower" in end.text


def test_a_call_without_a_view_draws_nothing(
    viewer: Viewer, pages: tuple[FakePage, FakePage]
) -> None:
    viewer.show_preview(None, *LAWNMOWER, body_start=1)
    viewer.show_replay(None, [(0.0, 0.0, 0.0, 1.0, 0.0), (9.0, 5.0, 0.0, 1.0, 0.0)])
    viewer.show_script(None, *SPIRAL)
    for view in (OPERATOR, OBSERVER):
        assert viewer.view_node_names(view, "/") == []
    assert viewer.node_names("/preview") == viewer.node_names("/replay") == []
    with pytest.raises(ValueError, match="finite"):  # still checked
        viewer.show_preview(None, (0.0, float("nan")), (0.0, 0.0), (0.0, 0.0))


def test_replay_in_one_view_and_cleared(viewer: Viewer, pages: tuple[FakePage, FakePage]) -> None:
    operator, observer = pages
    track = [(float(t), float(t), 0.0, 1.0, 0.0) for t in range(30)]
    viewer.show_replay(OPERATOR, track, [(5.0, 5.0, 0.0, 1.0, "square")])
    wait_until(lambda: "/replay/track" in operator.names("/replay"), what="replay drawn")
    assert viewer.view_node_names(OBSERVER, "/replay") == []
    assert observer.names("/replay") == []
    assert viewer.clear_replay(OBSERVER) is False  # nothing there
    assert viewer.clear_replay(OPERATOR) is True
    assert viewer.view_node_names(OPERATOR, "/replay") == []
    wait_until(lambda: operator.names("/replay") == [], what="replay removed from the page")
    assert viewer.clear_replay(OPERATOR) is False


def test_a_script_preview_is_per_view(viewer: Viewer, pages: tuple[FakePage, FakePage]) -> None:
    operator, _ = pages
    viewer.show_script(OPERATOR, *LAWNMOWER, [(0, "1: straight"), (3, "2: hover")])
    assert "/script/path" in viewer.view_node_names(OPERATOR, "/script")
    assert viewer.view_node_names(OBSERVER, "/script") == []
    wait_until(lambda: "/script/path" in operator.names("/script"), what="script drawn")
    assert viewer.clear_script(OPERATOR) is True


def test_drawn_before_the_page_connects_and_dropped_when_it_leaves(viewer: Viewer) -> None:
    viewer.show_preview(OPERATOR, *LAWNMOWER, body_start=1, label="preview: lawnmower")
    assert OPERATOR not in viewer.view_ids()
    page = FakePage(viewer, OPERATOR)  # its 3D view loads after the first preview
    try:
        wait_until(lambda: "/preview/end" in page.names("/preview"), what="kept preview drawn")
        assert "lawnmower" in page.text("/preview/end")
    finally:
        page.close()
    wait_until(lambda: OPERATOR not in viewer.view_ids(), what="view dropped")
    assert viewer.view_node_names(OPERATOR) == []
    again = FakePage(viewer, OPERATOR)  # a reload (same id, for the test): a fresh view
    try:
        assert viewer.view_node_names(OPERATOR) == []
    finally:
        again.close()


def test_a_page_without_a_view_sees_the_shared_scene_only(viewer: Viewer) -> None:
    ws = connect(viewer.websocket_url, subprotocols=[f"viser-v{viser.__version__}"])  # type: ignore[list-item]
    try:
        ws.send(msgspec.msgpack.encode(CAMERA))
        wait_until(lambda: len(viewer.server.get_clients()) == 1, what="client connected")
        assert viewer.view_ids() == []
    finally:
        ws.close()


# --- labels ---------------------------------------------------------------------------------


def all_labels(viewer: Viewer, view_id: str) -> dict[str, tuple[float, float, float]]:
    """Every label a page's 3D view shows: the shared scene's and its own."""
    out = viewer.shared_label_positions()
    for spec in viewer.view_labels(view_id):
        assert spec.name not in out
        out[spec.name] = spec.position
    return out


def test_declutter_merges_near_labels_and_keeps_clear_of_reserved_ones() -> None:
    specs = [
        LabelSpec.at("/a", "a", (0.0, 0.0, 0.0)),
        LabelSpec.at("/b", "b", (1.0, 0.0, 0.0)),  # merged into a
        LabelSpec.at("/c", "c", (10.0, 0.0, 0.0)),  # near a reserved one: lifted
        LabelSpec.at("/d", "d", (20.0, 0.0, 0.0), lift=False),  # near a reserved one: dropped
    ]
    placed = declutter(specs, [(10.0, 0.0, -1.0), (20.0, 0.0, 0.0)])
    assert [s.name for s in placed] == ["/a", "/c"]
    assert placed[0].shown == "a · b"
    assert placed[1].position[2] >= 2.0 - 1e-9
    many = [LabelSpec.at(f"/m{k}", f"m{k}", (0.0, 0.1 * k, 0.0)) for k in range(6)]
    assert declutter(many)[0].shown == "m0 · m1 · m2 +3 more"
    far = [LabelSpec.at(f"/f{k}", "f", (10.0 * k, 0.0, 0.0)) for k in range(40)]
    assert len(declutter(far)) == MAX_VIEW_LABELS


def test_no_two_labels_of_a_drawn_scene_are_closer_than_the_threshold(
    viewer: Viewer, pages: tuple[FakePage, FakePage]
) -> None:
    # the vehicle where a preview starts; an active path ending where the preview ends
    viewer.update_pose(5.0, 0.5, 0.5, 1.0, 0.0, 0.0)
    viewer.show_active(*LAWNMOWER, label="active: lawnmower")
    viewer.show_preview(OPERATOR, *LAWNMOWER, body_start=1, label="preview: lawnmower")
    # a script whose steps crowd together, and a replay with a command every metre
    xs = np.linspace(0.0, 6.0, 13)
    viewer.show_script(
        OPERATOR, xs, np.zeros(13), np.full(13, 4.0), [(k, f"{k}") for k in range(13)]
    )
    track = [(float(t), float(t), 1.0, 2.0, 0.0) for t in range(40)]
    cmds = [(float(t), float(t), 1.0, 2.0, f"cmd{t}") for t in range(0, 40, 1)]
    viewer.show_replay(OPERATOR, track, cmds)
    labels = all_labels(viewer, OPERATOR)
    assert min_separation_m(list(labels.values())) >= MIN_LABEL_SEPARATION_M - 1e-9, labels
    own = viewer.view_labels(OPERATOR)
    assert 0 < len(own) <= MAX_VIEW_LABELS
    assert any("more" in s.shown for s in own)  # crowded labels were merged, not lost silently
    # the preview's start is where the vehicle is: its label is left to the vehicle's
    assert "/preview/start" not in {s.name for s in own}
    # the operator's page was sent exactly these labels (and none left over)
    operator, _ = pages
    drawn = {s.name for s in own}
    shared = set(viewer.shared_label_positions())
    wait_until(lambda: operator.label_names() == drawn | shared, what="labels sent to the page")
    # the active path moved: the page's labels are placed again, still clear of it
    viewer.show_active(*SPIRAL, label="active: spiral")
    assert min_separation_m(list(all_labels(viewer, OPERATOR).values())) >= (
        MIN_LABEL_SEPARATION_M - 1e-9
    )
