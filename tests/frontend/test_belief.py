"""The page renders the console's belief and decides nothing itself (Chromium, 1280x800):

* on a one-way ``tcp://`` modem (a loopback gateway decoding every frame): a circle of 2
  copies, a Surface pressed between them, a retry of the circle: the page's "last sent" is the
  circle, "vehicle runs" the circle with the p the API gives and the Surface the runner-up;
  before anything is sent it says "unknown (no telemetry)", not idle, and the preview says its
  start is assumed;
* the SURFACE banner after a double press 0.8 s apart (training): gone once acknowledged;
* a dead-reckoned belief: the chart draws the position with its uncertainty ring;
* the console killed: the page no longer says the vehicle link is connected.
"""

from __future__ import annotations

import json
import re
import time
from collections.abc import Callable
from typing import Any

import pytest
from playwright.sync_api import Browser, Route, expect

from bench._gateway import FrameGateway
from tests.frontend.conftest import Console
from tests.frontend.pagekit import POLL_MS, open_sized, sized_page, wait_preview

TIMEOUT_S = 30.0


def wait_until(what: str, check: Callable[[], Any]) -> Any:
    deadline = time.monotonic() + TIMEOUT_S
    while not (value := check()):
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.1)
    return value


def pct(p: float) -> str:
    """frontend/delivery.js pct(): enough decimals that a value below 1 never reads 100 %."""
    if p >= 1:
        return "100 %"
    for digits in range(2, 7):
        text = f"{p * 100:.{digits}f}"
        if float(text) < 100:
            return f"{float(text):g} %"
    return f"> {100 - 10**-6:.6f} %"


def records(console: Console) -> list[dict[str, Any]]:
    rows: list[dict[str, Any]] = console.get("/api/commands")
    return rows


def record(console: Console, command_id: int) -> dict[str, Any]:
    rec: dict[str, Any] = console.get(f"/api/commands/{command_id}")
    return rec


# --- one-way ------------------------------------------------------------------------------------


@pytest.fixture
def console_env(request: pytest.FixtureRequest) -> dict[str, str]:
    """A one-way modem for the tests that take the gateway: copies 3 s apart (a Surface
    pressed after a circle's first copy supersedes it), Surface repeats 0.5 s apart."""
    if "gateway" not in request.fixturenames:
        return {}
    gateway: FrameGateway = request.getfixturevalue("gateway")
    return {
        "NEMESYS_TARGET": gateway.target,
        "NEMESYS_COPY_INTERVAL_S": "3",
        "NEMESYS_SURFACE_REPEAT_S": "0.5",
    }


def test_one_way_circle_surface_retry(
    console: Console, browser: Browser, gateway: FrameGateway
) -> None:
    with sized_page(browser, 1280, 800, shot="belief_one_way") as w:
        page = open_sized(w, console)
        # nothing sent, nothing heard: not "idle"
        expect(page.get_by_test_id("belief-command")).to_have_text("unknown (no telemetry)")
        expect(page.get_by_test_id("belief-position")).to_contain_text("assumed: no fix ever")
        wait_preview(page, "circle")
        start = page.get_by_test_id("preview-start")
        expect(start).to_be_visible()
        expect(start).to_contain_text("starts from an assumed position: the datum's origin")

        circle = console.post(
            "/api/commands",
            {
                "pattern": "circle",
                "params": {"speed": 0.18, "depth": 2, "radius": 4, "direction": "cw"},
                "copies": 2,
            },
            token=True,
        )
        wait_until("the circle's first copy", lambda: record(console, circle["id"])["copies_sent"])
        page.get_by_test_id("surface-button").click()
        surface = wait_until(
            "the Surface",
            lambda: next((r for r in records(console) if r["kind"] == "surface"), None),
        )
        wait_until("the Surface sent", lambda: record(console, surface["id"])["state"] == "sent")
        assert record(console, circle["id"])["state"] == "superseded"
        expect(page.get_by_test_id("surface-state")).to_have_text(re.compile(r"^surface sent: "))

        retried = console.post(f"/api/commands/{circle['id']}/retry", {}, token=True)
        wait_until("the retry sent", lambda: record(console, retried["id"])["state"] == "sent")

        belief = console.get("/api/vehicle")["belief"]
        assert belief["last_sent"]["id"] == retried["id"], belief
        command, runner_up = belief["command"], belief["runner_up"]
        assert command["id"] == retried["id"] and runner_up["id"] == surface["id"], belief
        p_r = record(console, retried["id"])["p_delivered"]
        assert command["p"] == pytest.approx(p_r)

        # the page shows the same: last sent, the circle and its p, the Surface runner-up
        expect(page.get_by_test_id("echo-sent")).to_contain_text(re.compile(r"^circle: "))
        expect(page.get_by_test_id("belief-command")).to_contain_text(re.compile(r"^circle: "))
        expect(page.get_by_test_id("belief-p")).to_have_text(f"p {pct(command['p'])}")
        expect(page.get_by_test_id("belief-runner-up")).to_have_text(
            f"surface (p {pct(runner_up['p'])})"
        )
        assert (page.get_by_test_id("echo-active").get_attribute("title") or "").startswith(
            "one-way link: "
        )
        w.assert_clean()


# --- training -----------------------------------------------------------------------------------


def test_the_banner_is_gone_after_a_double_surface(console: Console, browser: Browser) -> None:
    """The operator presses SURFACE twice, 0.8 s apart (the second press joins the first
    Surface or makes a new one): once every Surface is acknowledged, the banner no longer
    says "surfacing"."""
    with sized_page(browser, 1280, 800, shot="belief_double_surface") as w:
        page = open_sized(w, console)
        banner = page.get_by_test_id("surface-state")
        button = page.get_by_test_id("surface-button")
        for attempt in range(3):
            before = {r["id"] for r in records(console)}
            button.click()
            page.wait_for_timeout(800)  # the scenario: a second press 0.8 s after the first
            button.click()

            def settled(before: set[int] = before) -> bool:
                new = [r for r in records(console) if r["id"] not in before]
                return bool(new) and all(r["state"] == "acknowledged" for r in new)

            wait_until(f"the Surfaces of press pair {attempt} acknowledged", settled)
            page.wait_for_function(
                "() => { const b = document.querySelector('[data-testid=\"surface-state\"]');"
                " return b.hidden || !b.textContent.includes('surfacing'); }",
                polling=POLL_MS,
                timeout=10_000,
            )
            assert banner.is_hidden() or banner.text_content() == "surface acknowledged"
        w.assert_clean()


def _dead_reckoned(route: Route) -> None:
    """GET /api/vehicle as the console answers it, its belief's position dead-reckoned (the
    chart draws what it is given; when telemetry stops is tests/backend/belief's)."""
    doc = route.fetch().json()
    p = doc["belief"]["position"]
    p.update(source="dead_reckoning", sigma_m=4.0, age_s=12.0, basis="the last fix 12 s ago")
    doc["belief"]["seq"] = 10**9  # newer than any the console will push in this test
    route.fulfill(status=200, content_type="application/json", body=json.dumps(doc))


def test_a_dead_reckoned_position_is_drawn_with_its_ring(
    console: Console, browser: Browser
) -> None:
    with sized_page(browser, 1280, 800, shot="belief_ring") as w:
        w.page.route(re.compile(r"/api/vehicle$"), _dead_reckoned)
        page = open_sized(w, console)
        marker = page.locator('[data-testid="chart-belief"]')
        expect(marker).to_have_attribute("data-source", "dead_reckoning")
        expect(marker).to_contain_text("believed ±4 m")
        expect(page.locator(".chart-belief-ring")).to_have_count(1)
        expect(page.get_by_test_id("belief-position")).to_contain_text(
            re.compile(r"± 4 m: dead-reckoned, 12 s since the last fix$")
        )
        w.assert_clean()


def test_a_killed_console_leaves_no_connected_vehicle_link(
    console: Console, browser: Browser
) -> None:
    with sized_page(browser, 1280, 800, shot="belief_console_killed") as w:
        page = open_sized(w, console)
        link = page.get_by_test_id("status-link")
        expect(link).to_contain_text("connected")
        expect(link).to_contain_text(re.compile(r"telemetry \d"))
        console.server.kill()
        expect(page.get_by_test_id("conn-state")).not_to_have_text("connected")
        expect(link).not_to_contain_text(re.compile(r"\bconnected\b"))
        expect(link).to_contain_text(
            re.compile(r"^console unreachable: the vehicle link as of \d+ s ago")
        )
        expect(page.get_by_test_id("link-text")).to_have_text("unknown (console unreachable)")
        expect(page.get_by_test_id("echo-active")).to_contain_text("(console unreachable)")
