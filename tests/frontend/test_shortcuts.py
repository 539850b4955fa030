"""Keyboard shortcuts and the confirm dialog (issue 14): the send key opens the confirm dialog
and never sends; the Surface key (Ctrl+Shift+S, issue 19) is one SURFACE per key press (held
down or not) with the focus anywhere (the pattern select, a number or text field, a button,
the confirm dialog, the 3D view) and never changes the form, and nothing without the operator
token; the list is in the page. The confirm dialog shows the estimates on the first send and
lists only the parameters that really change."""

from __future__ import annotations

import re
import time
from collections.abc import Callable

import pytest
from playwright.sync_api import Browser, Page, expect

from tests.frontend.conftest import Console
from tests.frontend.pagekit import SIZES, open_sized, sized_page, wait_preview

#: Counts the surface button's clicks (the shortcut must be exactly that click).
COUNT_CLICKS_JS = """() => { window.__surfaceClicks = 0;
  const button = document.querySelector('#surface-button');
  button.addEventListener('click', () => window.__surfaceClicks++);
}"""
DASH = "\u2013"  # the page's "no value" mark
SURFACE_KEY = "Control+Shift+S"
#: What the operator has entered, by control id: none of it may change with the Surface key.
FORM_JS = """() => { const out = {};
  const controls = '#pattern-select, #param-form input, #param-form select, #script-name,'
    + ' #log-filter-text, #log-filter-pattern, #log-filter-state';
  for (const node of document.querySelectorAll(controls)) out[node.id] = node.value;
  return out; }"""


def surface_clicks(page: Page) -> int:
    n: int = page.evaluate("() => window.__surfaceClicks")
    return n


def surfaces(console: Console) -> list[dict[str, object]]:
    return [r for r in console.get("/api/commands") if r.get("pattern") == "surface"]


@pytest.mark.parametrize("size", list(SIZES))
def test_the_shortcuts_are_listed_in_the_page(
    console: Console, browser: Browser, size: str
) -> None:
    with sized_page(browser, *SIZES[size]) as w:
        page = open_sized(w, console)
        # visible hints on the buttons themselves
        expect(page.get_by_test_id("send-button")).to_contain_text("Ctrl+Enter")
        expect(page.get_by_test_id("surface-button")).to_contain_text("Ctrl+Shift+S")
        expect(page.get_by_test_id("shortcuts-button")).to_be_visible()
        page.locator("body").press("?")
        dialog = page.get_by_test_id("shortcuts-dialog")
        expect(dialog).to_be_visible()
        listing = page.get_by_test_id("shortcuts-list")
        for text in ("Ctrl+Enter", "confirm dialog", "Ctrl+Shift+S", "SURFACE", "?"):
            expect(listing).to_contain_text(text)
        expect(page.get_by_test_id("shortcut-surface")).to_contain_text("from anywhere")
        page.keyboard.press("Escape")
        expect(dialog).to_be_hidden()
        page.get_by_test_id("shortcuts-button").click()
        expect(dialog).to_be_visible()
        page.get_by_test_id("shortcuts-close").click()
        expect(dialog).to_be_hidden()
        w.assert_clean()


def test_send_key_opens_the_confirm_dialog_and_never_sends(
    console: Console, browser: Browser
) -> None:
    with sized_page(browser, 1280, 800) as w:
        page = open_sized(w, console)
        wait_preview(page, "circle")
        # while typing a parameter: the send key still works (it is the one that does)
        page.get_by_test_id("param-radius").fill("7")
        page.get_by_test_id("param-radius").press("Control+Enter")
        dialog = page.get_by_test_id("confirm-dialog")
        expect(dialog).to_be_visible()
        expect(page.locator("#confirm-title")).to_have_text("Send circle?")
        # pressed again inside the dialog: nothing more (the dialog's own button sends)
        page.keyboard.press("Control+Enter")
        expect(dialog).to_be_visible()
        assert console.get("/api/commands") == [], "the send key must not send"
        page.get_by_test_id("confirm-cancel").click()
        expect(dialog).to_be_hidden()
        assert console.get("/api/commands") == []
        w.assert_clean()


def wait_surfaces(console: Console, page: Page, n: int, what: str) -> None:
    deadline = time.monotonic() + 15.0
    while len(surfaces(console)) < n:
        assert time.monotonic() < deadline, f"{what}: no SURFACE was logged"
        page.wait_for_timeout(100)


def test_surface_key_works_from_every_control_and_never_changes_the_form(
    console: Console, browser: Browser
) -> None:
    with sized_page(browser, 1280, 800) as w:
        page = open_sized(w, console)
        page.evaluate(COUNT_CLICKS_JS)
        wait_preview(page, "circle")  # the pattern just picked: the select has the focus
        page.get_by_test_id("param-radius").fill("7")
        dialog = page.get_by_test_id("confirm-dialog")
        viewer = page.frame_locator("#viewer").locator("body")
        places: list[tuple[str, Callable[[], None]]] = [
            ("the pattern select", lambda: page.get_by_test_id("pattern-select").focus()),
            ("a number field", lambda: page.get_by_test_id("param-radius").focus()),
            ("a text field", lambda: page.get_by_test_id("script-name").focus()),
            ("a search field", lambda: page.get_by_test_id("log-filter-text").focus()),
            ("a button (not pressed)", lambda: page.get_by_test_id("send-button").focus()),
            ("the 3D view", viewer.click),
            ("the confirm dialog", lambda: page.get_by_test_id("send-button").click()),
        ]
        for n, (what, focus) in enumerate(places, start=1):
            focus()
            if what == "the confirm dialog":
                expect(dialog).to_be_visible()
                assert page.evaluate("() => document.activeElement.closest('dialog') !== null")
            form = page.evaluate(FORM_JS)
            page.keyboard.press(SURFACE_KEY)
            assert surface_clicks(page) == n, what
            wait_surfaces(console, page, n, what)
            assert page.evaluate(FORM_JS) == form, f"{what}: the form changed"
            expect(dialog).to_be_hidden()  # never opened by the button; a pending one cancelled
        assert page.get_by_test_id("param-radius").input_value() == "7"
        assert page.get_by_test_id("script-name").input_value() == "mission"

        # held down (key repeat): exactly one click, one SURFACE
        page.locator("body").click(position={"x": 640, "y": 795})
        page.keyboard.down("Control")
        page.keyboard.down("Shift")
        for _ in range(3):
            page.keyboard.down("S")  # the 2nd and 3rd: auto-repeat (event.repeat)
        page.keyboard.up("S")
        page.keyboard.up("Shift")
        page.keyboard.up("Control")
        n = len(places) + 1
        assert surface_clicks(page) == n
        wait_surfaces(console, page, n, "held down")
        # the next request the page makes comes after any extra POST would have: none
        page.get_by_test_id("log-refresh").click()
        page.wait_for_function("() => document.querySelectorAll('#log-rows tr').length > 0")
        assert len(surfaces(console)) == n, surfaces(console)
        sent = [r for r in w.requests if r[1].endswith("/api/surface")]
        assert sent == [("POST", f"{console.base}/api/surface")] * n
        # the circle awaiting confirmation was never sent
        assert [r["pattern"] for r in console.get("/api/commands")] == ["surface"] * n
        # Shift+S alone is not the key: a capital S in a text field, as typed
        name = page.get_by_test_id("script-name")
        name.fill("")
        name.press("Shift+S")
        expect(name).to_have_value("S")
        assert surface_clicks(page) == n
        w.assert_clean()


def test_without_the_token_the_keys_do_nothing(console: Console, browser: Browser) -> None:
    with sized_page(browser, 1280, 800) as w:
        page = open_sized(w, console, token=False)
        page.evaluate(COUNT_CLICKS_JS)
        expect(page.get_by_test_id("surface-button")).to_be_disabled()
        expect(page.get_by_test_id("send-button")).to_be_disabled()
        page.locator("body").press(SURFACE_KEY)
        page.get_by_test_id("pattern-select").press(SURFACE_KEY)
        page.locator("body").press("Control+Enter")
        assert surface_clicks(page) == 0
        assert page.evaluate("() => document.querySelector('#confirm-dialog').open") is False
        assert console.get("/api/commands") == []
        w.assert_clean()


def test_confirm_shows_estimates_on_the_first_send_and_only_real_changes(
    console: Console, browser: Browser
) -> None:
    with sized_page(browser, 1280, 800, shot="confirm_circle_radius") as w:
        page = open_sized(w, console)
        wait_preview(page, "circle")
        params = {"speed": "0.18", "depth": "3", "radius": "5"}
        for k, v in params.items():
            page.get_by_test_id(f"param-{k}").fill(v)
        page.get_by_test_id("send-button").click()
        dialog = page.get_by_test_id("confirm-dialog")
        expect(dialog).to_be_visible()
        expect(page.get_by_test_id("confirm-summary")).to_have_text("Active: none  ->  new: circle")
        estimates = page.get_by_test_id("confirm-estimates")
        for key, pattern in (
            ("duration", r"^[\d.]+ s$|repeats"),
            ("length", r"^[\d.]+ m$"),
            ("depth range", r"^[\d.]+ to 3 m$"),
            ("battery use", r"^[\d.]+ %$"),
        ):
            expect(estimates.locator(f'[data-key="{key}"] dd')).to_have_text(re.compile(pattern))
        expect(page.get_by_test_id("confirm-copies")).to_have_text(
            re.compile(r"^copies: \d+ \(auto, chosen by the console, p\(delivered\) [\d.]+ %\)$")
        )
        body = page.get_by_test_id("confirm-body").text_content() or ""
        assert DASH not in body, f"a dash in the first send's confirm dialog: {body!r}"
        page.get_by_test_id("confirm-send").click()
        expect(dialog).to_be_hidden()
        # the circle is the active pattern once the vehicle runs it
        expect(page.get_by_test_id("status-pattern")).to_have_text("circle", timeout=15_000)

        page.get_by_test_id("param-radius").fill("6")
        page.get_by_test_id("send-button").click()
        expect(dialog).to_be_visible()
        summary = page.get_by_test_id("confirm-summary")
        expect(summary).to_have_text("Active: circle  ->  new: circle")
        changes = page.get_by_test_id("confirm-changes").locator("li")
        expect(changes).to_have_count(1)
        expect(changes).to_have_text("radius: 5 m -> 6 m")
        page.get_by_test_id("confirm-cancel").click()

        # a new pattern with the same speed and depth: only what differs is listed
        wait_preview(page, "box_orbit")
        for k, v in params.items():
            page.get_by_test_id(f"param-{k}").fill(v)
        page.get_by_test_id("send-button").click()
        expect(dialog).to_be_visible()
        listed = page.get_by_test_id("confirm-changes").locator("li").all_text_contents()
        same = ("speed", "depth", "radius")
        assert listed and all(not t.startswith(same) for t in listed), listed
        page.get_by_test_id("confirm-cancel").click()
        assert len(console.get("/api/commands")) == 1
        w.assert_clean()
