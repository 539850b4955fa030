"""Mission scripts through the send policy: the preview lists every step's violations, export
and run refuse a hard one (422 naming the step and the parameter) and a soft one without the
step's override (409); an overridden step is sent with its override recorded; nothing is
transmitted by a refused script (the bytes at a one-way TCP modem)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from bench._gateway import FrameGateway
from tests.backend.conftest import AUTH, MakeClient, wait_until
from tests.backend.scripts.test_scripts import HOVER, doc, step

DEEP: dict[str, float | str] = {"speed": 0.18, "depth": 105, "duration": 40, "heading": 90}
FAST: dict[str, float | str] = {"speed": 0.5, "depth": 2, "duration": 40, "heading": 90}


@pytest.fixture
def modem() -> Iterator[FrameGateway]:
    gateway = FrameGateway()
    try:
        yield gateway
    finally:
        gateway.close()


def violations(body: Any) -> list[dict[str, Any]]:
    detail = body["detail"]
    assert isinstance(detail, dict), body
    return list(detail["violations"])


def test_a_hard_step_is_listed_and_refused_everywhere(
    make_client: MakeClient, modem: FrameGateway
) -> None:
    client = make_client(target=modem.target)
    script = doc(step("hover", HOVER, "at", 0), step("straight", DEEP, "at", 60))
    r = client.post("/api/scripts/preview", json=script)
    assert r.status_code == 200, r.text
    preview = r.json()
    found = preview["steps"][1]["violations"]
    assert [(v["param"], v["kind"]) for v in found] == [("depth", "hard")]
    assert preview["steps"][0]["violations"] == []
    assert any(
        w.startswith("step 2: ") and "cannot be overridden" in w for w in preview["warnings"]
    )
    for path in ("/api/scripts/export", "/api/scripts/export?format=csv"):
        r = client.post(path, json=script)
        assert r.status_code == 422, r.text
        assert [(v["step"], v["param"]) for v in violations(r.json())] == [(1, "depth")]
    overridden = doc(
        step("hover", HOVER, "at", 0), {**step("straight", DEEP, "at", 60), "override": True}
    )
    r = client.post("/api/scripts/run", json={"script": overridden}, headers=AUTH)
    assert r.status_code == 422, r.text  # the depth rating: whatever the override says
    assert violations(r.json())[0]["step"] == 1
    assert client.get("/api/commands").json() == [] and modem.count() == 0


def test_a_soft_step_needs_its_override_which_is_recorded(
    make_client: MakeClient, modem: FrameGateway
) -> None:
    client = make_client(target=modem.target, top_speed_mps=0.19)  # the twin's top speed
    script = doc(step("straight", FAST, "at", 0))
    r = client.post("/api/scripts/export", json=script)
    assert r.status_code == 409, r.text
    assert [(v["step"], v["param"], v["kind"]) for v in violations(r.json())] == [
        (0, "speed", "soft")
    ]
    r = client.post("/api/scripts/run", json={"script": script}, headers=AUTH)
    assert r.status_code == 409, r.text
    assert client.get("/api/commands").json() == [] and modem.count() == 0

    overridden = doc({**step("straight", FAST, "at", 0), "override": True})
    assert client.post("/api/scripts/export", json=overridden).status_code == 200
    r = client.post("/api/scripts/run", json={"script": overridden}, headers=AUTH)
    assert r.status_code == 200, r.text
    rows = wait_until(lambda: client.get("/api/commands").json(), what="the step was sent")
    record = rows[0]
    assert record["kind"] == "script" and record["origin"] == "script"
    assert record["overrides"]["by"] and record["overrides"]["violations"][0]["param"] == "speed"
    wait_until(lambda: modem.count(record["hex"]) >= 1, what="the frame at the modem")


def test_a_step_refused_at_send_time_stops_the_run_and_sends_nothing(
    make_client: MakeClient, modem: FrameGateway
) -> None:
    """A step that passed when the run began is checked again when it is due: here the depth
    limit is tightened between the two (the vehicle profile or limits of the moment rule)."""
    client = make_client(target=modem.target)
    script = doc(step("hover", HOVER, "operator"))
    r = client.post("/api/scripts/run", json={"script": script, "mode": "step"}, headers=AUTH)
    assert r.status_code == 200, r.text
    console = client.app.state.console  # type: ignore[attr-defined]
    console.limits = type(console.limits)(
        max_depth_m=1.0, max_speed_mps=console.limits.max_speed_mps
    )
    r = client.post("/api/scripts/run/next", headers=AUTH)
    assert r.status_code == 200, r.text
    state = r.json()
    assert state["outcome"] == "failed" and "not sent" in state["reason"]
    assert "depth" in state["reason"]
    assert client.get("/api/commands").json() == [] and modem.count() == 0
