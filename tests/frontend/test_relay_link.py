"""The page of a console without a transmitter (issue 24, item 4; frontend/link.js): its
header's vehicle-link indicator says "relay via <the console holding it>", the status panel's
link row names that console's link; the vehicle, as the ship writes its track into the log,
is on the chart and in the vehicle panel, its telemetry said to come "via ship's log"
(backend/relay/telemetry.py); when that console stops, the row says it is not seen and the
indicator turns red. In Chromium, on a relay console and a training console (the ship)
sharing one PostgreSQL database."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from playwright.sync_api import expect

from bench._server import ConsoleProcess, start_console
from tests.backend.conftest import pg_server, shared_url, wait_until
from tests.frontend.conftest import TOKEN, Console, Watched
from tests.frontend.pagekit import POLL_MS, open_sized

__all__ = ["pg_server", "shared_url"]


@pytest.fixture
def ship(tmp_path: Path, shared_url: str) -> Iterator[ConsoleProcess]:
    env = {"NEMESYS_DATABASE_URL": shared_url, "NEMESYS_CONSOLE_NAME": "ship"}
    db = str(tmp_path / "ship.sqlite3")
    with start_console(tmp_path / "ship.log", TOKEN, "--db", db, env=env) as server:
        yield server


@pytest.fixture
def console_env(ship: ConsoleProcess, shared_url: str) -> dict[str, str]:
    """The console under test: the shore, a relay (after the ship: it is there to be seen)."""
    return {
        "NEMESYS_DATABASE_URL": shared_url,
        "NEMESYS_CONSOLE_NAME": "shore",
        "NEMESYS_TARGET": "relay",
    }


def test_the_header_says_relay_via_the_console_holding_the_transmitter(
    ship: ConsoleProcess, console: Console, watched: Watched
) -> None:
    # the shore has the vehicle (and the ship's datum) from the ship's track in the log
    pose = wait_until(lambda: (p := console.get("/api/vehicle")["pose"]) and p["lat_deg"] and p)
    with ship.client() as http:
        heard = http.get("/api/vehicle").json()["pose"]
    assert abs(pose["lat_deg"] - heard["lat_deg"]) < 1e-4, (pose, heard)  # ~10 m
    assert abs(pose["lon_deg"] - heard["lon_deg"]) < 1e-4, (pose, heard)
    page = open_sized(watched, console)
    indicator = page.get_by_test_id("link-text")
    expect(indicator).to_contain_text("relay via ship")
    row = page.get_by_test_id("status-link")
    expect(row).to_contain_text("relay via ship (its link: sim, connected")
    expect(row).to_contain_text("telemetry via ship's log")
    expect(page.get_by_test_id("status-position")).to_contain_text(" m north")
    expect(page.get_by_test_id("status-age")).to_contain_text("(telemetry via ship's log)")
    marker = page.locator(".chart-vehicle")
    expect(marker).to_have_count(1)
    page.wait_for_function(
        "([lat, lon]) => { const n = document.querySelector('.chart-vehicle');"
        " return n && Math.abs(Number(n.dataset.lat) - lat) < 1e-4"
        " && Math.abs(Number(n.dataset.lon) - lon) < 1e-4; }",
        arg=[heard["lat_deg"], heard["lon_deg"]],
        polling=POLL_MS,
    )
    ship.stop()
    expect(row).to_contain_text("ship NOT SEEN", timeout=20_000)
    # no more points: the vehicle's last known values, stale, their age growing
    stale = page.get_by_test_id("status-stale")
    expect(stale).to_contain_text("Stale: no vehicle message (telemetry via ship's log) for")
    expect(page.get_by_test_id("link-indicator")).to_have_class("link-indicator level-red")
    problem = page.get_by_test_id("link-problem").first
    expect(problem).to_contain_text("console 'ship', holding the transmitter, last seen")
