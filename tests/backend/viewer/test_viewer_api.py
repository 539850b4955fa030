"""The API's side of per-page views: ``X-Nemesys-View`` routes previews, script previews and
replays to the calling page's 3D view only, and ``DELETE /api/replay`` clears it."""

from __future__ import annotations

from typing import Any

from fastapi.testclient import TestClient

from backend.viewer.viewer import Viewer
from tests.backend.conftest import AUTH, CIRCLE, SQUARE, MakeClient, console_of, wait_until
from tests.backend.viewer.test_views import FakePage

OPERATOR, OBSERVER = "operator-page-0001", "observer-page-0002"
SCRIPT: dict[str, Any] = {
    "format": "nemesys-mission-script",
    "version": 1,
    "name": "two steps",
    "steps": [
        {"pattern": "square", "params": SQUARE, "trigger": {"kind": "at", "t_s": 0}},
        {"pattern": "circle", "params": CIRCLE, "trigger": {"kind": "operator"}},
    ],
}


def view(view_id: str) -> dict[str, str]:
    return {"X-Nemesys-View": view_id}


def viewer_of(client: TestClient) -> Viewer:
    v = console_of(client).viewer
    assert isinstance(v, Viewer)
    return v


def end_label(v: Viewer, view_id: str) -> str:
    node = v.view_node(view_id, "/preview/end")
    return str(getattr(node, "text", ""))


def test_previews_go_to_the_calling_page_only(make_client: MakeClient) -> None:
    client = make_client(viewer=True)
    v = viewer_of(client)
    operator, observer = FakePage(v, OPERATOR), FakePage(v, OBSERVER)
    try:
        body = {"pattern": "circle", "params": CIRCLE}
        assert client.post("/api/preview", json=body, headers=view(OPERATOR)).status_code == 200
        wait_until(lambda: "circle" in end_label(v, OPERATOR), what="operator's preview")
        square = {"pattern": "square", "params": SQUARE}
        assert client.post("/api/preview", json=square, headers=view(OBSERVER)).status_code == 200
        wait_until(lambda: "square" in end_label(v, OBSERVER), what="observer's preview")
        assert "circle" in end_label(v, OPERATOR)  # untouched by the observer's
        wait_until(lambda: "circle" in operator.text("/preview/end"), what="sent to the page")
        # an API user's preview (no header) is drawn in no view
        assert client.post("/api/preview", json=square).status_code == 200
        assert client.post("/api/preview", json=body, headers=view(OBSERVER)).status_code == 200
        wait_until(lambda: "circle" in end_label(v, OBSERVER), what="observer's 2nd preview")
        assert "circle" in end_label(v, OPERATOR)
        assert v.node_names("/preview") == []
    finally:
        operator.close()
        observer.close()


def test_script_preview_and_replay_per_page_and_clear(make_client: MakeClient) -> None:
    client = make_client(viewer=True)
    v = viewer_of(client)
    operator, observer = FakePage(v, OPERATOR), FakePage(v, OBSERVER)
    try:
        r = client.post("/api/scripts/preview", json=SCRIPT, headers=view(OPERATOR))
        assert r.status_code == 200, r.text
        assert "/script/path" in v.view_node_names(OPERATOR, "/script")
        assert v.view_node_names(OBSERVER, "/script") == []
        wait_until(lambda: console_of(client).hub.known_pose, what="a pose in the dive")
        r = client.post("/api/dives/1/replay", headers={**AUTH, **view(OPERATOR)})
        assert r.status_code == 200, r.text
        assert v.view_node_names(OPERATOR, "/replay")
        assert v.view_node_names(OBSERVER, "/replay") == []
        r = client.delete("/api/replay", headers=view(OBSERVER))
        assert r.status_code == 200 and r.json() == {"view": OBSERVER, "cleared": False}
        r = client.delete("/api/replay", headers=view(OPERATOR))
        assert r.json() == {"view": OPERATOR, "cleared": True}
        assert v.view_node_names(OPERATOR, "/replay") == []
        wait_until(lambda: operator.names("/replay") == [], what="replay removed from the page")
        assert client.delete("/api/replay").json() == {"view": None, "cleared": False}
    finally:
        operator.close()
        observer.close()


def test_a_malformed_view_id_is_a_422_naming_the_header(client: TestClient) -> None:
    body = {"pattern": "circle", "params": CIRCLE}
    for bad in ("short", "x" * 65, "bad id with spaces", "../../etc"):
        r = client.post("/api/preview", json=body, headers=view(bad))
        assert r.status_code == 422, bad
        assert r.json()["detail"][0]["loc"] == ["header", "x-nemesys-view"]
        assert client.delete("/api/replay", headers=view(bad)).status_code == 422
    # no viewer at all (viewer=False): a view id is accepted, nothing is drawn
    assert client.post("/api/preview", json=body, headers=view(OPERATOR)).status_code == 200
    assert client.delete("/api/replay", headers=view(OPERATOR)).json()["cleared"] is False
