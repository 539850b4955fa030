"""A console without a transmitter shows the vehicle (issue 24, backend/relay/telemetry.py):
the ship in training hears the simulated vehicle and writes its track into the shared
PostgreSQL log; the shore (``target relay``) reads each batch's newest point when it is told
of it and shows it as its pose and status, labelled as relayed through the ship's log, with
its true age. Two real consoles in this process on one real PostgreSQL; the simulator at real
time (the track keeps a point a second of the vehicle's clock). Waits are on conditions."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.app import create_app
from backend.commands.health import STALE_TELEMETRY_S
from tests.backend.conftest import MakeClient, console_of, settings_for, wait_until
from tests.backend.control.consoles import Page

pytestmark = pytest.mark.slow

#: The issue's bound: the shore has the vehicle's pose this soon after the ship (s): the
#: track's interval of 1 s, its batch's 0.5 s and the notification's read.
LAG_S = 2.0


def vehicle(client: TestClient) -> dict[str, Any]:
    r = client.get("/api/vehicle")
    assert r.status_code == 200, r.text
    body: dict[str, Any] = r.json()
    return body


def posed(m: dict[str, Any]) -> bool:
    pose = m.get("pose")
    return bool(pose and pose.get("x_m") is not None)


def test_the_shore_shows_the_vehicle_the_ship_hears_relayed_and_aging_when_it_stops(
    shared_url: str, tmp_path: Path, make_client: MakeClient
) -> None:
    common: dict[str, Any] = {"database_url": shared_url, "control_timeout_s": 5.0}
    ship_settings = settings_for(
        tmp_path / "ship.sqlite3",
        console_name="ship",
        operator="alice",
        sim_time_scale=1.0,
        **common,
    )
    shore = make_client(
        db_path=tmp_path / "shore.sqlite3",
        console_name="shore",
        operator="bob",
        target="relay",
        **common,
    )
    shore_page = Page(shore)
    try:
        with TestClient(create_app(ship_settings, viewer=False)) as ship:
            ship_page = Page(ship)
            try:
                shown(ship, shore, ship_page, shore_page)
            finally:
                ship_page.close()
        stopped(shore, shore_page)
    finally:
        shore_page.close()


def shown(ship: TestClient, shore: TestClient, ship_page: Page, shore_page: Page) -> None:
    """The ship hears the vehicle: the shore shows it, relayed, within :data:`LAG_S`."""
    # the shore's page gets the vehicle's pose, named as read through the ship's log
    t_shore, first = shore_page.wait("telemetry", posed, timeout_s=15)
    assert first["relayed_via"] == "ship"
    assert 0.0 <= first["age_s"] <= LAG_S
    # ... within LAG_S of the ship's page having it (the same point or a later one)
    t_s = first["pose"]["t_s"]
    t_ship, _ = ship_page.wait("telemetry", lambda m: posed(m) and m["pose"]["t_s"] >= t_s)
    assert t_shore - t_ship < LAG_S, (t_shore, t_ship)
    assert all("relayed_via" not in m for _, m in ship_page.seen("telemetry"))

    # it is a point of the ship's track: the same position, in the ship's dive
    dive = console_of(ship).dive
    assert dive is not None and first["dive"] == dive
    track = ship.get(f"/api/dives/{dive}").json()["track"]
    (same,) = [p for p in track if p["t_s"] == t_s]
    for key in ("x_m", "y_m", "z_m", "heading_deg"):
        assert first["pose"][key] == pytest.approx(same[key])

    def full(m: dict[str, Any]) -> bool:
        """A point with the ship's datum (in its beat, read at most every 0.5 s: taken),
        and the status the ship had then (none before its first status)."""
        s = m["status"]
        return posed(m) and m["pose"]["lat_deg"] is not None and s["depth_m"] is not None

    _, later = shore_page.wait("telemetry", full)
    assert later["status"]["mode"] and later["status"]["battery_pct"] is not None

    # /api/vehicle: the pose, its age, and the link saying where it comes from
    now = wait_until(lambda: (v := vehicle(shore))["link"]["relay"]["telemetry_via"] and v)
    link = now["link"]
    assert link["target"] == "relay" and link["relay"]["via"] == "ship"
    assert now["pose"]["x_m"] is not None and now["age_s"] <= LAG_S + 1.0
    assert link["last_telemetry_age_s"] == pytest.approx(now["age_s"], abs=0.5)
    assert not [p for p in link["problems"] if "telemetry" in p], link["problems"]
    assert now["belief"] is not None
    assert vehicle(ship)["link"]["relay"] is None  # the ship hears it itself


def stopped(shore: TestClient, shore_page: Page) -> None:
    """The ship stopped (its last points written): the shore's telemetry ages, never
    renewed."""
    last = vehicle(shore)
    aged = wait_until(
        lambda: (v := vehicle(shore))["age_s"] > STALE_TELEMETRY_S + 1.0 and v,
        timeout_s=20,
    )
    assert aged["pose"] == last["pose"] or aged["pose"]["t_s"] >= last["pose"]["t_s"]
    assert aged["link"]["relay"]["telemetry_via"] == "ship"
    assert aged["link"]["level"] in ("amber", "red")
    # the page's link news (every second) says it too; its telemetry counts the age on
    _, told = shore_page.wait(
        "link", lambda m: (m["link"]["last_telemetry_age_s"] or 0) > STALE_TELEMETRY_S
    )
    assert told["link"]["relay"]["telemetry_via"] == "ship"
