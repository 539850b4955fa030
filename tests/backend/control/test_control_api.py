"""``GET/POST /api/control`` on a SQLite log (one console, in control implicitly: today's
behaviour unchanged, the actions still logged), the input's errors, and the console's name
(``backend/control/identity.py``)."""

from __future__ import annotations

from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from backend.control.identity import ConsoleNameError, console_name, name_path
from backend.settings import Settings
from tests.backend.conftest import AUTH, CIRCLE, loc_of, send, wait_state
from tests.backend.control.consoles import act


def test_on_sqlite_the_one_console_is_in_control_and_its_actions_are_logged(
    client: TestClient,
) -> None:
    (view,) = client.get("/api/control").json()
    assert view["vehicle"] == "nemesys" and view["implicit"] is True
    assert view["operator"] == "operator" and view["epoch"] == 0
    took = act(client, "request", takeover_allowed=True)
    assert took.status_code == 200, took.text
    assert took.json()["outcome"] == "granted"
    control = took.json()["control"]
    assert control["implicit"] is False and control["takeover_allowed"] is True
    assert control["console"] == view["console"] and control["epoch"] == 1 and control["since"]
    assert act(client, "release").json()["outcome"] == "released"
    (after,) = client.get("/api/control").json()
    assert after["implicit"] is True and after["epoch"] == 2
    # released or not, the one console sends
    wait_state(client, send(client)["id"], ("acknowledged",))
    events = [e for e in client.get("/api/dives/1/timeline").json()["events"]]
    assert sum("control" in e["text"] for e in events) == 2, events


def test_the_session_names_this_console_and_its_log(client: TestClient) -> None:
    """What a page needs to offer only the actions that make sense here: its console's name
    (the control views name consoles) and whether the log is shared at all."""
    s = client.get("/api/session").json()["console"]
    (view,) = client.get("/api/control").json()
    assert s["name"] == view["console"] and s["shared_log"] is False
    assert s["control_timeout_s"] > 0


def test_the_owner_changes_whether_a_takeover_is_allowed_and_it_is_logged(
    client: TestClient,
) -> None:
    assert act(client, "request").json()["control"]["takeover_allowed"] is False
    allowed = act(client, "request", takeover_allowed=True)
    assert allowed.json()["outcome"] == "unchanged", allowed.text
    assert allowed.json()["control"]["takeover_allowed"] is True
    assert act(client, "request").json()["control"]["takeover_allowed"] is True  # kept
    assert (
        act(client, "request", takeover_allowed=False).json()["control"]["takeover_allowed"]
        is False
    )
    details = [e["text"] for e in client.get("/api/dives/1/timeline").json()["events"]]
    said = [d for d in details if "allows a takeover" in d]
    assert len(said) == 2 and "now allows" in said[0] and "no longer allows" in said[1], details
    assert sum("already has control" in d for d in details) == 1, details


def test_control_actions_are_checked(client: TestClient) -> None:
    r = client.post("/api/control", json={"action": "request"})
    assert r.status_code == 401
    r = client.post("/api/control", json={"action": "seize"}, headers=AUTH)
    assert r.status_code == 422 and loc_of(r.json()) == ["body", "action"]
    r = act(client, "request", vehicle="auv9")
    assert r.status_code == 422 and loc_of(r.json()) == ["body", "vehicle"]
    assert "this console's vehicles: nemesys" in r.json()["detail"][0]["msg"]
    r = act(client, "request", takeover_allowed="yes")
    assert r.status_code == 422 and loc_of(r.json()) == ["body", "takeover_allowed"]
    r = act(client, "grant")
    assert r.status_code == 409 and "only the console in control can grant" in r.json()["detail"]
    act(client, "request")
    r = act(client, "grant")
    assert r.status_code == 409 and "no request for control" in r.json()["detail"]
    r = client.post("/api/commands", json={"pattern": "circle", "params": CIRCLE}, headers=AUTH)
    assert r.status_code == 202 and r.json()["console"]


def test_a_consoles_name_is_kept_beside_its_log(tmp_path: Path) -> None:
    db = tmp_path / "log" / "missions.sqlite3"
    first = console_name(Settings(db_path=db))
    assert console_name(Settings(db_path=db)) == first  # the same console after a restart
    assert name_path(db).read_text().strip() == first
    assert console_name(Settings(db_path=tmp_path / "other.sqlite3")) != first
    assert console_name(Settings(db_path=db, console_name="ship")) == "ship"
    name_path(db).write_text("not a name!\n")
    with pytest.raises(ConsoleNameError, match="not a name"):
        console_name(Settings(db_path=db))
    with pytest.raises(ValueError, match="console_name"):
        Settings(console_name="bad name")
