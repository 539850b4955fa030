"""The replay of a fleet's dive in real Chromium (issue 23, Build item 7): the console with
``NEMESYS_VEHICLES=3`` on three in-memory vehicles behind the real onboard agent, one channel
(``tests/agent_link.py``'s ``agent_fleet``), each on its own lane, served by uvicorn in this
process.

The page replays the selected vehicle: the 3D replay, the timeline and every slider request
name it, the replay panel's title names it, and the slider shows that vehicle's positions
alone (never another's); selecting another vehicle replays the same dive for that one. The
console's REST API is the oracle. The single-vehicle replay is tests/frontend/test_replay.py's
(unchanged)."""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlsplit

import httpx
import pytest
from playwright.sync_api import Page, Request, expect

from backend.app import create_app
from backend.console import Console as Runtime
from backend.settings import Settings
from tests.agent_link import TARGET, agent_fleet
from tests.backend.conftest import clear_nemesys_env, wait_until
from tests.backend.live_server import serve
from tests.frontend.conftest import TOKEN, Watched
from tests.frontend.pagekit import POLL_MS
from tests.frontend.test_replay import POSITION, slide_to
from vehicle_contract.fleet import parse_vehicles

pytestmark = pytest.mark.browser

FLEET = parse_vehicles("3")
NAMES = [v.name for v in FLEET]
#: Each vehicle's lane (m east: agent_fleet's spacing) and the track points added to it.
LANE_M = 20.0
POINTS = 5


@dataclass
class FleetConsole:
    """The console of three in-memory vehicles (``base``: its URL) and its runtime."""

    base: str
    runtime: Runtime

    def get(self, path: str, **params: str) -> Any:
        r = httpx.get(self.base + path, params=params, timeout=10.0, trust_env=False)
        r.raise_for_status()
        return r.json()

    def at(self, dive: int, t_s: float, vehicle: str) -> dict[str, Any]:
        """The oracle: ``vehicle`` at ``t_s`` of ``dive`` (no view header: nothing drawn)."""
        doc = {"dive": dive, "t_s": t_s, "vehicle": vehicle}
        r = httpx.put(self.base + "/api/replay/at", json=doc, timeout=10.0, trust_env=False)
        r.raise_for_status()
        position: dict[str, Any] = r.json()["position"]
        return position


@pytest.fixture
def fleet_console(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[FleetConsole]:
    clear_nemesys_env(monkeypatch)
    settings = Settings(
        token=TOKEN, db_path=tmp_path / "log.sqlite3", viewer_port=0, target=TARGET, vehicles="3"
    )
    app = create_app(settings, viewer=True, link=agent_fleet(FLEET, spacing_m=LANE_M))
    with serve(app) as base:
        console = FleetConsole(base, app.state.console)
        wait_until(lambda: all(v["pose"] for v in console.get("/api/vehicles")), what="poses")
        yield console


def fly_lanes(runtime: Runtime) -> int:
    """Each vehicle heard :data:`POINTS` more seconds, going north on its own lane; the dive."""
    log, dive = runtime.log, runtime.dive
    assert log is not None and dive is not None
    start = max(r["t_s"] for r in log.track_rows(dive, positioned=False))
    for k in range(1, POINTS + 1):
        for i, name in enumerate(NAMES):
            log.add_track(dive, start + k, 3.0 * k, LANE_M * i, 2.0, 0.0, {}, vehicle=name)
    return dive


def open_fleet_page(w: Watched, console: FleetConsole) -> Page:
    """The page with the token (the 3D view stubbed), once the fleet's selector is built."""
    page = w.page
    w.stub_viewer()
    page.goto(f"{console.base}/?token={TOKEN}")
    expect(page.get_by_test_id("auth-state")).to_have_text(re.compile(r"^operator"))
    expect(page.get_by_test_id("vehicle-select").locator("option")).to_have_count(len(NAMES))
    return page


def vehicle_of(request: Request) -> str | None:
    """The vehicle a replay request names: its query's, or its JSON body's."""
    query = parse_qs(urlsplit(request.url).query).get("vehicle")
    if query:
        return query[0]
    if request.post_data:
        named: str | None = json.loads(request.post_data).get("vehicle")
        return named
    return None


def replay_request(method: str, path: str, vehicle: str) -> Any:
    """A matcher (for page.expect_request) of a ``method`` to a URL ending in ``path`` naming
    ``vehicle``."""

    def match(r: Request) -> bool:
        ends = urlsplit(r.url).path.endswith(path)
        return r.method == method and ends and vehicle_of(r) == vehicle

    return match


def assert_shows(page: Page, expected: dict[str, Any]) -> None:
    """The replay panel shows the oracle's position (north, east, depth)."""

    def shown() -> list[float] | None:
        found = POSITION.match(page.get_by_test_id("replay-position").text_content() or "")
        return [float(v) for v in found.groups()] if found else None

    want = [expected["x_m"], expected["y_m"], expected["z_m"]]
    wait_until(lambda: shown() == pytest.approx(want, abs=0.051), what=f"position {want}")


def test_the_page_replays_the_selected_vehicle_alone(
    fleet_console: FleetConsole, watched: Watched
) -> None:
    console = fleet_console
    dive = fly_lanes(console.runtime)
    page = open_fleet_page(watched, console)
    replay_button = page.get_by_test_id(f"replay-{dive}")
    expect(replay_button).to_be_enabled()
    bar = page.get_by_test_id("replay-bar")

    # auv2 selected: the replay, its timeline and the slider's first request name it
    page.get_by_test_id("vehicle-select").select_option("auv2")
    with (
        page.expect_request(replay_request("POST", f"/api/dives/{dive}/replay", "auv2")),
        page.expect_request(replay_request("GET", f"/api/dives/{dive}/timeline", "auv2")),
        page.expect_request(replay_request("PUT", "/api/replay/at", "auv2")),
    ):
        replay_button.click()
    expect(page.get_by_test_id("replay-title")).to_have_text(f"dive {dive}: auv2")
    expect(bar).to_have_attribute("data-vehicle", "auv2")
    timeline = console.get(f"/api/dives/{dive}/timeline", vehicle="auv2")
    assert {s["y_m"] for s in timeline["samples"]} == {LANE_M}  # its lane alone
    slider = page.get_by_test_id("replay-slider")
    assert float(slider.get_attribute("max") or 0) >= timeline["duration_s"]

    # along its lane: each second its own position (never another vehicle's lane)
    last = round(timeline["samples"][-1]["t_s"])
    for t_s in (last - 2, last):
        with page.expect_request(replay_request("PUT", "/api/replay/at", "auv2")):
            slide_to(page, t_s)
        expected = console.at(dive, t_s, "auv2")
        assert expected["y_m"] == LANE_M
        assert_shows(page, expected)

    # another vehicle selected: the same dive replayed for it, on its own lane
    with (
        page.expect_request(replay_request("POST", f"/api/dives/{dive}/replay", "auv3")),
        page.expect_request(replay_request("GET", f"/api/dives/{dive}/timeline", "auv3")),
    ):
        page.get_by_test_id("vehicle-select").select_option("auv3")
    expect(page.get_by_test_id("replay-title")).to_have_text(f"dive {dive}: auv3")
    expect(bar).to_have_attribute("data-vehicle", "auv3")
    page.wait_for_function(
        "() => document.querySelector('[data-testid=replay-bar]').dataset.t === '0'",
        polling=POLL_MS,
    )
    with page.expect_request(replay_request("PUT", "/api/replay/at", "auv3")):
        slide_to(page, last)
    expected = console.at(dive, last, "auv3")
    assert expected["y_m"] == 2 * LANE_M
    assert_shows(page, expected)

    # no request of the replay left without its vehicle (the slider's name it in the body)
    api = [urlsplit(url) for _, url in watched.requests if "/api/dives/" in url]
    unnamed = [u.geturl() for u in api if u.path.endswith(("/replay", "/timeline"))]
    unnamed = [u for u in unnamed if "vehicle=" not in u]
    assert not unnamed, unnamed
    watched.assert_clean()
