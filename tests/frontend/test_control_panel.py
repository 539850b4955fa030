"""The Control panel (issue 24, item 3; frontend/control.js): in Chromium, a ship's console
(training, holding the transmitter, in control from its start) and a shore's (a relay)
sharing one real PostgreSQL database, each with its page at 1280x800.

The shore clicks Request control; the ship's page shows the waiting request with Grant and
Refuse and clicks Grant; both pages then show the shore in control; the ship's Send is refused
with the console's 409 naming the shore, shown in the confirm dialog; the shore clicks
Release, and both show nobody. Then the refuse path (the ship takes control at once, the shore
asks, the ship refuses: the shore's page shows the logged refusal and offers Request again) and
a takeover the owner allowed. On a SQLite log (one console) the panel is one line saying
plainly that this console is the only one, without buttons. Every wait is on a condition."""

from __future__ import annotations

import re
import warnings
from collections.abc import Iterator
from pathlib import Path

import pytest
from playwright.sync_api import Browser, Page, expect
from playwright.sync_api import Error as PlaywrightError

from bench._server import start_console
from tests.backend.conftest import pg_server, shared_url
from tests.frontend.conftest import ARTIFACTS, START_TIMEOUT_S, TOKEN, Console, Watched
from tests.frontend.pagekit import POLL_MS, open_sized, sized_page, wait_preview

__all__ = ["pg_server", "shared_url"]

#: The one vehicle's name without a fleet (the control rows' key).
V = "nemesys"


@pytest.fixture
def ship(tmp_path: Path, shared_url: str) -> Iterator[Console]:
    """The ship's console: started first, it takes control of the vehicle nobody controls."""
    env = {
        "NEMESYS_DATABASE_URL": shared_url,
        "NEMESYS_CONSOLE_NAME": "ship",
        "NEMESYS_OPERATOR": "alice",
    }
    db = str(tmp_path / "ship.sqlite3")
    with (
        start_console(
            tmp_path / "ship.log",
            TOKEN,
            *("--db", db, "--time-scale", "10"),
            env=env,
            timeout_s=START_TIMEOUT_S,
        ) as server,
        server.client() as http,
    ):
        yield Console(server, http)


@pytest.fixture
def shore(tmp_path: Path, shared_url: str, ship: Console) -> Iterator[Console]:
    """The shore's console: a relay (no transmitter of its own), after the ship."""
    env = {
        "NEMESYS_DATABASE_URL": shared_url,
        "NEMESYS_CONSOLE_NAME": "shore",
        "NEMESYS_OPERATOR": "bob",
        "NEMESYS_TARGET": "relay",
    }
    db = str(tmp_path / "shore.sqlite3")
    with (
        start_console(
            tmp_path / "shore.log", TOKEN, "--db", db, env=env, timeout_s=START_TIMEOUT_S
        ) as server,
        server.client() as http,
    ):
        yield Console(server, http)


def expect_owner(ship_page: Page, shore_page: Page, owner: str | None) -> None:
    """Both pages name ``owner`` ("ship", "shore" or None: nobody) in control, each from its
    own side."""
    names = {"ship": "alice", "shore": "bob"}
    for page, here in ((ship_page, "ship"), (shore_page, "shore")):
        row = page.get_by_test_id(f"control-who-{V}")
        if owner is None:
            expect(row).to_have_text("nobody")
        elif owner == here:
            expect(row).to_have_text(f"this console, {owner} (operator {names[owner]})")
        else:
            expect(row).to_have_text(f"console {owner} (operator {names[owner]})")


def expect_buttons(page: Page, *wanted: str) -> None:
    """Wait until the page offers exactly ``wanted`` (the rows are redrawn on every change)."""
    page.wait_for_function(
        "([v, wanted]) => { const row = document.querySelector(`[data-testid=control-row-${v}]`);"
        " if (!row) return false;"
        " const got = [...row.querySelectorAll('button, input[type=checkbox]')]"
        ".map((n) => n.dataset.testid.replace(/^control-/, '').replace(`-${v}`, '')).sort();"
        " return JSON.stringify(got) === JSON.stringify(wanted); }",
        arg=[V, sorted(wanted)],
        polling=POLL_MS,
    )


def test_request_grant_send_refused_release_refuse_and_takeover_across_two_pages(
    ship: Console, shore: Console, browser: Browser
) -> None:
    with (
        sized_page(browser, 1280, 800) as ship_w,
        sized_page(browser, 1280, 800) as shore_w,
    ):
        ship_page, shore_page = open_sized(ship_w, ship), open_sized(shore_w, shore)
        # the ship took control at its start; each page offers what makes sense there
        expect_owner(ship_page, shore_page, "ship")
        expect(ship_page.get_by_test_id("control-panel")).to_be_visible()
        expect_buttons(ship_page, "release", "takeover-allowed")
        expect_buttons(shore_page, "request")
        expect(shore_page.get_by_test_id(f"control-note-{V}")).to_contain_text(
            "sends are refused (409); SURFACE is accepted from any console"
        )
        facts = ship_page.get_by_test_id(f"control-facts-{V}")
        expect(facts).to_contain_text("epoch 1")
        expect(facts).to_contain_text("no takeover without asking")
        expect(facts).to_contain_text(re.compile(r"since \d\d:\d\d:\d\d"))

        # the shore asks; the ship's page shows the request with Grant and Refuse
        shore_page.get_by_test_id(f"control-request-{V}").click()
        expect(shore_page.get_by_test_id("control-result")).to_have_text(
            f"{V}: request sent; it waits for the answer of console ship (operator alice)"
        )
        expect(shore_page.get_by_test_id(f"control-asked-{V}")).to_contain_text(
            "this console's request"
        )
        expect_buttons(shore_page)  # asked: nothing to do but wait
        asked = ship_page.get_by_test_id(f"control-asked-{V}")
        expect(asked).to_contain_text("console shore (operator bob) asks for control")
        expect_buttons(ship_page, "grant", "refuse", "release", "takeover-allowed")
        snapshot(ship_page, "control_request_waiting_1280x800")

        ship_page.get_by_test_id(f"control-grant-{V}").click()
        expect(ship_page.get_by_test_id("control-result")).to_have_text(
            f"{V}: control granted to console shore (operator bob)"
        )
        expect_owner(ship_page, shore_page, "shore")
        expect(ship_page.get_by_test_id(f"control-facts-{V}")).to_contain_text("epoch 2")
        expect(shore_page.get_by_test_id(f"control-last-{V}")).to_contain_text(
            "console 'ship' (operator 'alice') granted console 'shore' (operator 'bob') control"
        )
        expect_buttons(shore_page, "release", "takeover-allowed")
        expect_buttons(ship_page, "request")

        # the ship is no longer in control: its Send is refused, the 409 naming the shore
        wait_preview(ship_page, "circle")
        ship_page.get_by_test_id("send-button").click()
        ship_page.get_by_test_id("confirm-send").click()
        refused = ship_page.get_by_test_id("confirm-error")
        expect(refused).to_contain_text(
            f"409: console 'shore' (operator 'bob') is in control of vehicle {V}"
        )
        expect(refused).to_contain_text("this console ('ship') is not")
        ship_page.get_by_test_id("confirm-cancel").click()
        assert ship.get("/api/commands") == [], "nothing was written or sent"

        # the shore releases: nobody is in control, either may request it
        shore_page.get_by_test_id(f"control-release-{V}").click()
        expect(shore_page.get_by_test_id("control-result")).to_have_text(
            f"{V}: control released; nobody is in control"
        )
        expect_owner(ship_page, shore_page, None)
        expect_buttons(ship_page, "request")
        expect_buttons(shore_page, "request")

        # the refuse path: the ship takes it at once, the shore asks, the ship refuses
        ship_page.get_by_test_id(f"control-request-{V}").click()
        expect(ship_page.get_by_test_id("control-result")).to_have_text(
            f"{V}: control is this console's"
        )
        expect_owner(ship_page, shore_page, "ship")
        shore_page.get_by_test_id(f"control-request-{V}").click()
        expect_buttons(ship_page, "grant", "refuse", "release", "takeover-allowed")
        ship_page.get_by_test_id(f"control-refuse-{V}").click()
        expect(ship_page.get_by_test_id("control-result")).to_have_text(
            f"{V}: request refused; control stays with this console, ship (operator alice)"
        )
        expect(shore_page.get_by_test_id(f"control-last-{V}")).to_contain_text(
            "console 'ship' (operator 'alice') refused console 'shore' (operator 'bob') control"
        )
        expect(shore_page.get_by_test_id(f"control-asked-{V}")).to_have_count(0)
        expect_owner(ship_page, shore_page, "ship")
        expect_buttons(shore_page, "request")

        # a takeover only where the owner allows it: then the shore's page offers it
        ship_page.get_by_test_id(f"control-takeover-allowed-{V}").check()
        expect(ship_page.get_by_test_id("control-result")).to_have_text(
            f"{V}: this console keeps control; takeover allowed"
        )
        expect(shore_page.get_by_test_id(f"control-facts-{V}")).to_contain_text("takeover allowed")
        expect_buttons(shore_page, "request", "takeover")
        shore_page.get_by_test_id(f"control-takeover-{V}").click()
        expect(shore_page.get_by_test_id("control-result")).to_have_text(
            f"{V}: taken over; control is this console's"
        )
        expect_owner(ship_page, shore_page, "shore")
        expect(ship_page.get_by_test_id(f"control-last-{V}")).to_contain_text(
            "console 'shore' (operator 'bob') took control of nemesys from console 'ship'"
        )
        expect_buttons(ship_page, "request")

        # an action the console refuses shows its reason: the ship's next press is turned into
        # a release on its way (the page never offers one it cannot do), and the console's
        # 409 names what was wrong
        ship_page.route(
            "**/api/control",
            lambda route: route.continue_(post_data='{"action": "release", "vehicle": "nemesys"}'),
        )
        ship_page.get_by_test_id(f"control-request-{V}").click()
        expect(ship_page.get_by_test_id("control-result")).to_have_text(
            f"{V}: request not done: 409: only the console in control can release: "
            "console 'shore' (operator 'bob') is in control of nemesys"
        )
        expect(ship_page.get_by_test_id("control-result")).to_have_class("error")
        expect_owner(ship_page, shore_page, "shore")
        for w in (ship_w, shore_w):
            w.assert_clean()


def test_a_single_console_on_sqlite_says_plainly_it_is_in_control(
    console: Console, watched: Watched
) -> None:
    page = open_sized(watched, console)
    solo = page.get_by_test_id("control-solo")
    expect(solo).to_have_text("Control: this console, the only one on its mission log (SQLite)")
    name = console.get("/api/session")["console"]["name"]
    title = solo.get_attribute("title") or ""
    assert f"this console ({name})" in title and "always in control" in title, title
    assert "no send is refused for control" in title, title
    panel = page.get_by_test_id("control-panel")
    expect(panel).to_be_visible()
    expect(panel.locator("button, input")).to_have_count(0)  # nothing to do: no clutter
    box = panel.bounding_box()
    assert box is not None and box["height"] < 60, f"one line, not a panel of rows: {box}"
    watched.assert_clean()


def snapshot(page: Page, name: str) -> None:
    """A best-effort screenshot in test-artifacts/ (the panel as the operator sees it)."""
    ARTIFACTS.mkdir(exist_ok=True)
    try:
        page.screenshot(path=str(ARTIFACTS / f"{name}.png"), timeout=10_000)
    except PlaywrightError as err:
        warnings.warn(f"no screenshot {name}: {err}", stacklevel=1)
