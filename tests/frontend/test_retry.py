"""Retry is a new command (issue 19, item 2), in Chromium at 1280x800 on a one-way ``tcp://``
modem: a loopback gateway (bench/_gateway.py) decodes every frame the console sends, with
its time. The command list's Retry opens the send's confirm dialog, filled from a fresh
preview of the old values from where the vehicle is now (every check, a soft violation
needing the override box); confirmed, it is a new record. A circle, a Surface, then a retry
of the superseded circle: the page says the circle was sent last, the CSV and the command
list follow the wire (circle, surface, circle), and the last frame on the wire is the
circle's."""

from __future__ import annotations

import csv
import io
import re
import time
from collections.abc import Callable
from typing import Any

import pytest
from playwright.sync_api import Browser, Page, expect

from bench._gateway import FrameGateway
from tests.frontend.conftest import Console
from tests.frontend.pagekit import POLL_MS, open_sized, sized_page, wait_preview

CIRCLE = {"speed": "0.18", "depth": "2", "radius": "4"}
#: Copies of the first circle: enough that it is still going out when Surface is pressed.
MANY = 20
TIMEOUT_S = 20.0


@pytest.fixture
def limits() -> dict[str, str]:
    """``NEMESYS_*`` limits added to the console's settings (a test parametrizes it)."""
    return {}


@pytest.fixture
def console_env(gateway: FrameGateway, limits: dict[str, str]) -> dict[str, str]:
    """Vehicle mode on the gateway (one-way: copies, no acknowledgement); copies and Surface
    repeats half a second apart, so that a test waits seconds, not tens of them."""
    return {
        "NEMESYS_TARGET": gateway.target,
        "NEMESYS_COPY_INTERVAL_S": "0.5",
        "NEMESYS_SURFACE_REPEAT_S": "0.5",
        **limits,
    }


def wait_until(what: str, check: Callable[[], Any]) -> Any:
    """Poll ``check`` until it returns something truthy (returned), or fail naming ``what``."""
    deadline = time.monotonic() + TIMEOUT_S
    while not (value := check()):
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.1)
    return value


def records(console: Console) -> list[dict[str, Any]]:
    """GET /api/commands: the log, newest on the wire first."""
    rows: list[dict[str, Any]] = console.get("/api/commands")
    return rows


def record(console: Console, command_id: int) -> dict[str, Any]:
    rec: dict[str, Any] = console.get(f"/api/commands/{command_id}")
    return rec


def newest(console: Console, pattern: str, after: set[int]) -> dict[str, Any]:
    """The one record of ``pattern`` logged since the ids ``after``, once there is one."""
    found: list[dict[str, Any]] = wait_until(
        f"a new {pattern} in the log",
        lambda: [r for r in records(console) if r["pattern"] == pattern and r["id"] not in after],
    )
    assert len(found) == 1, found
    return found[0]


def wait_state(page: Page, command_id: int, state: str) -> None:
    page.wait_for_function(
        '([id, state]) => document.querySelector(`[data-testid="state-${id}"]`)'
        "?.textContent === state",
        arg=[command_id, state],
        polling=POLL_MS,
        timeout=TIMEOUT_S * 1000,
    )


def send_circle(page: Page, console: Console, *, copies: int, override: bool) -> dict[str, Any]:
    """Author a circle and send it through the confirm dialog (ticking the override box when
    ``override``); its record, once its first copy is on the wire."""
    before = {r["id"] for r in records(console)}
    wait_preview(page, "circle")
    for name, value in CIRCLE.items():
        page.get_by_test_id(f"param-{name}").fill(value)
    page.get_by_test_id("copies-input").fill(str(copies))
    page.get_by_test_id("send-button").click()
    expect(page.get_by_test_id("confirm-dialog")).to_be_visible()
    expect(page.locator("#confirm-title")).to_have_text("Send circle?")
    if override:
        page.get_by_test_id("confirm-override").check()
    page.get_by_test_id("confirm-send").click()
    expect(page.get_by_test_id("confirm-dialog")).to_be_hidden()
    circle = newest(console, "circle", before)
    wait_state(page, circle["id"], "transmitted")
    return circle


def surface_over(page: Page, console: Console, circle: dict[str, Any]) -> dict[str, Any]:
    """Press Surface while the circle's copies go out: the circle is superseded."""
    before = {r["id"] for r in records(console)}
    page.get_by_test_id("surface-button").click()
    surface = newest(console, "surface", before)
    wait_state(page, circle["id"], "superseded")
    assert record(console, circle["id"])["superseded_by"] == surface["id"]
    expect(page.get_by_test_id("echo-sent")).to_have_text("surface")
    return surface


def open_retry(page: Page, circle: dict[str, Any]) -> None:
    """Press the circle's Retry: the confirm dialog, titled as a retry of it, with the fresh
    preview's estimates and every check."""
    page.get_by_test_id("copies-input").fill("")  # the retry's copies: the console's choice
    page.get_by_test_id(f"retry-{circle['id']}").click()
    expect(page.get_by_test_id("confirm-dialog")).to_be_visible()
    expect(page.locator("#confirm-title")).to_have_text(
        f"Retry command {circle['id']} (circle) as a new command?"
    )
    duration = page.get_by_test_id("confirm-estimates").locator('[data-key="duration"] dd')
    expect(duration).to_have_text(re.compile(r"^repeats until retasked"))
    checks = page.get_by_test_id("confirm-checks")
    for check in ("depth_rating", "depth_limit", "speed_limit", "top_speed", "reach"):
        expect(checks.locator(f'li[data-check="{check}"]')).to_have_count(1)


def retried_of(console: Console, circle: dict[str, Any], before: set[int]) -> dict[str, Any]:
    """The retry's record: new, created now, naming the circle; the circle keeps its state."""
    new = newest(console, "circle", before)
    assert new["id"] > circle["id"] and new["retry_of"] == circle["id"], new
    assert new["origin"] == "retry" and new["created_at"] > circle["created_at"], new
    assert record(console, circle["id"])["state"] == "superseded"
    return new


def test_retry_of_a_superseded_circle_is_the_last_sent_in_wire_order(
    console: Console, browser: Browser, gateway: FrameGateway
) -> None:
    with sized_page(browser, 1280, 800, shot="retry_wire_order") as w:
        page = open_sized(w, console)
        circle = send_circle(page, console, copies=MANY, override=False)
        surface = surface_over(page, console, circle)

        open_retry(page, circle)
        expect(page.get_by_test_id("confirm-checks-summary")).to_contain_text("within limits")
        expect(page.get_by_test_id("confirm-override-box")).to_be_hidden()
        before = {r["id"] for r in records(console)}
        page.get_by_test_id("confirm-send").click()
        expect(page.get_by_test_id("confirm-dialog")).to_be_hidden()
        retried = retried_of(console, circle, before)
        assert retried["hex"] == circle["hex"] and retried["overrides"] is None, retried
        wait_state(page, retried["id"], "sent")

        # "last sent" is the server's: the retried circle, whose first copy left last
        expect(page.get_by_test_id("echo-sent")).to_contain_text(re.compile(r"^circle: "))
        assert console.get("/api/vehicle")["last_sent"]["id"] == retried["id"]
        ids = [circle["id"], surface["id"], retried["id"]]
        # the command list, newest on the wire on top
        rows = page.get_by_test_id("command-list").locator(":scope > li")
        expect(rows).to_have_count(3)
        assert [int(i or 0) for i in rows.evaluate_all("ls => ls.map((l) => l.dataset.id)")] == [
            *reversed(ids)
        ]
        # the CSV, oldest on the wire first
        csv_text = console.http.get("/api/log.csv").text
        log = [(int(r["id"]), r["pattern"]) for r in csv.DictReader(io.StringIO(csv_text))]
        assert log == list(zip(ids, ["circle", "surface", "circle"], strict=True)), log

        # the wire: the circle's copies, then the Surface's, then the retried circle's last
        final = {r["id"]: record(console, r["id"]) for r in records(console)}
        wait_until(
            "every copy on the wire",
            lambda: len(gateway.trace()) == sum(r["copies_sent"] for r in final.values()),
        )
        wire = [f.hex for f in gateway.trace()]
        s_hex = surface["hex"]
        assert wire[-1] == circle["hex"], wire
        assert (
            wire.index(s_hex) > 0
            and wire[: wire.index(s_hex)] == [circle["hex"]] * (final[circle["id"]]["copies_sent"])
        ), wire
        last_surface = len(wire) - 1 - wire[::-1].index(s_hex)
        assert wire[last_surface + 1 :] == [circle["hex"]] * final[retried["id"]]["copies_sent"]
        w.assert_clean()


@pytest.mark.parametrize("limits", [{"NEMESYS_MAX_DEPTH_M": "1"}], ids=["max-depth-1m"])
def test_a_retry_beyond_a_soft_limit_needs_the_override_box(
    console: Console, browser: Browser
) -> None:
    with sized_page(browser, 1280, 800, shot="retry_needs_override") as w:
        page = open_sized(w, console)
        # the 2 m circle breaks the 1 m limit: sent with the override, then superseded
        circle = send_circle(page, console, copies=MANY, override=True)
        surface_over(page, console, circle)

        open_retry(page, circle)
        depth = page.get_by_test_id("confirm-checks").locator('li[data-check="depth_limit"]')
        expect(depth).to_have_attribute("data-status", "violated")
        expect(depth).to_have_attribute("data-kind", "soft")
        expect(depth).to_contain_text("soft: needs the override")
        expect(page.get_by_test_id("confirm-checks-summary")).to_contain_text(
            "1 soft (needs the override)"
        )
        send = page.get_by_test_id("confirm-send")
        override = page.get_by_test_id("confirm-override")
        expect(override).to_be_visible()
        expect(override).not_to_be_checked()  # the first send's override is not carried over
        expect(send).to_be_disabled()
        override.check()
        expect(send).to_be_enabled()
        before = {r["id"] for r in records(console)}
        send.click()
        expect(page.get_by_test_id("confirm-dialog")).to_be_hidden()
        retried = retried_of(console, circle, before)
        overrides = retried["overrides"]
        assert overrides and [v["check"] for v in overrides["violations"]] == ["depth_limit"], (
            retried
        )
        wait_state(page, retried["id"], "sent")
        expect(page.get_by_test_id("echo-sent")).to_contain_text(re.compile(r"^circle: "))
        w.assert_clean()
