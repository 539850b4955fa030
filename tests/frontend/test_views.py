"""Per-page 3D views in real Chromium: an observer's preview never changes the operator's view,
and a replay is drawn in one page only and cleared by its "Clear replay" button.

Each page's 3D view is viser's client in an iframe; its scene (shared nodes and the page's own)
is read from viser's scene tree inside that iframe (``window.__viserSceneTree``), i.e. what
that page's viewer actually holds.
"""

from __future__ import annotations

import time

import pytest
from playwright.sync_api import Browser, Frame, Page, expect

from tests.frontend.conftest import Console, Watched
from tests.frontend.pagekit import SIZES
from tests.frontend.test_browser import (
    LAWNMOWER,
    POLL_MS,
    author,
    open_page,
    scene_names,
    viewer_frame,
    wait_scene_label,
)

#: How long a page's 3D view may take to load and connect (ms).
LOAD_MS = 60_000
SPIRAL = {"speed": 0.18, "depth": 2, "initial_radius": 2, "final_radius": 6, "loops": 2}


def labels_text(frame: Frame) -> str:
    """Every label's text in a page's 3D view, joined."""
    text: str = frame.evaluate(
        "() => Object.values(window.__viserSceneTree.getState())"
        ".map((n) => (n && n.message && n.message.props && n.message.props.text) || '')"
        ".join(' | ')"
    )
    return text


def wait_label_text(frame: Frame, part: str, timeout_ms: int = 20_000) -> None:
    """Wait until some label of a page's 3D view contains ``part``."""
    frame.wait_for_function(
        "(part) => Object.values(window.__viserSceneTree.getState())"
        ".some((n) => ((n && n.message && n.message.props && n.message.props.text) || '')"
        ".includes(part))",
        arg=part,
        polling=POLL_MS,
        timeout=timeout_ms,
    )


def wait_gone(frame: Frame, prefix: str, timeout_ms: int = 20_000) -> None:
    frame.wait_for_function(
        "(prefix) => !Object.keys(window.__viserSceneTree.getState())"
        ".some((k) => k.startsWith(prefix))",
        arg=prefix,
        polling=POLL_MS,
        timeout=timeout_ms,
    )


def second_page(browser: Browser, watched: Watched, size: tuple[int, int] = (1100, 800)) -> Watched:
    """Another browser (own context: no token, its own view id) at ``size``, watched like the
    first."""
    context = browser.new_context(viewport={"width": size[0], "height": size[1]})
    page = context.new_page()
    page.set_default_timeout(LOAD_MS)  # two real 3D views load on a busy 2-core machine
    w = Watched(page)
    page.on("pageerror", lambda err: w.errors.append(f"{err.name}: {err.message}"))
    return w


def view_id(page: Page) -> str:
    src = page.get_by_test_id("viewer").get_attribute("src") or ""
    assert "/view/" in src, src
    return src.rsplit("/view/", 1)[1].split("&", 1)[0]


@pytest.mark.parametrize("size", list(SIZES))
def test_an_observers_preview_does_not_change_the_operators_view(
    console: Console, watched: Watched, browser: Browser, size: str
) -> None:
    watched.page.set_default_timeout(LOAD_MS)
    width, height = SIZES[size]
    watched.page.set_viewport_size({"width": width, "height": height})
    operator = open_page(watched, console, viewer=True)
    author(operator, "lawnmower", LAWNMOWER)
    op_frame = viewer_frame(operator)
    # the first wait covers the 3D view's loading (seconds of SwiftShader on a busy machine)
    wait_scene_label(op_frame, "/preview/end", "lawnmower", "depth 3.0 m", timeout_ms=LOAD_MS)

    other = second_page(browser, watched, SIZES[size])
    try:
        observer = open_page(other, console, token=False, viewer=True)
        assert view_id(observer) != view_id(operator)  # each page its own view
        author(observer, "spiral", SPIRAL)
        ob_frame = viewer_frame(observer)
        wait_scene_label(ob_frame, "/preview/end", "spiral", "depth 2.0 m", timeout_ms=LOAD_MS)
        # the observer's view does not hold the operator's lawnmower ...
        assert "lawnmower" not in labels_text(ob_frame)
        # ... and the operator's view still holds the lawnmower, not the spiral: checked
        # again after a further observer preview had time to reach every viewer
        author(observer, "spiral", {**SPIRAL, "final_radius": 8})
        wait_scene_label(ob_frame, "/preview/end", "spiral")
        end = wait_scene_label(op_frame, "/preview/end", "lawnmower", "depth 3.0 m")
        assert end.startswith("preview: lawnmower end")
        assert "spiral" not in labels_text(op_frame)
        assert "/preview/body" in scene_names(op_frame, "/preview/")
        # the operator's form still says lawnmower
        expect(operator.get_by_test_id("pattern-select")).to_have_value("lawnmower")
        other.assert_clean()
    finally:
        other.page.context.close()
    watched.assert_clean()


def test_a_replay_is_drawn_in_one_page_and_cleared_by_the_button(
    console: Console, watched: Watched, browser: Browser
) -> None:
    # a dive with a track to replay (the simulator logs the track at 1 Hz of its time)
    deadline = time.monotonic() + 20.0
    while len(console.get("/api/dives/1")["track"]) < 3:
        assert time.monotonic() < deadline, "no track logged"
        time.sleep(0.1)
    watched.page.set_default_timeout(LOAD_MS)
    operator = open_page(watched, console, viewer=True)
    other = second_page(browser, watched)
    try:
        second = open_page(other, console, token=True, viewer=True)  # another operator page
        op_frame, second_frame = viewer_frame(operator), viewer_frame(second)
        wait_scene_label(second_frame, "/scale/north", "N", timeout_ms=LOAD_MS)  # connected
        operator.get_by_test_id("replay-1").click()
        wait_scene_label(op_frame, "/replay/track", timeout_ms=LOAD_MS)
        wait_label_text(op_frame, "replay")  # its start (and end, when far enough apart)
        # the other page's view never gets it
        operator.get_by_test_id("clear-replay").scroll_into_view_if_needed()
        assert scene_names(second_frame, "/replay") == []
        # cleared by the button, in this page's view only
        second.get_by_test_id("clear-replay").click()  # the other page's: nothing to clear
        expect(second.get_by_test_id("message").first).to_contain_text("no replay shown")
        assert "/replay/track" in scene_names(op_frame, "/replay")
        operator.get_by_test_id("clear-replay").click()
        wait_gone(op_frame, "/replay")
        expect(operator.get_by_test_id("message").first).to_contain_text("replay cleared")
        other.assert_clean()
    finally:
        other.page.context.close()
    watched.assert_clean()
