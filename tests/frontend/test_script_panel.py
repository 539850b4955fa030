"""The mission script panel at 1280x800 in real Chromium (issue 20): the script's preview is
in sight when it is drawn (the panel is below the fold, the 3D view above it), and the panel
speaks the operator's words: triggers "after the previous step completes", times "at 20 s from
the run's start", durations "takes 20 s (estimated)", steps "not sent yet" / "sent"; a run is
completed when its last step's pattern completes, as the vehicle reports it; a Surface during
a run stops it, and the panel says why."""

from __future__ import annotations

import re
import time
from typing import Any

from playwright.sync_api import Browser, Page, expect

from tests.frontend.conftest import Console
from tests.frontend.pagekit import POLL_MS, open_sized, sized_page
from tests.frontend.test_browser import author

#: At the simulated vehicle's start depth (2 m), so nothing but the hold itself takes time.
HOVER: dict[str, Any] = {"duration": 20, "depth": 2, "heading": 90}
STRAIGHT: dict[str, Any] = {"speed": 0.18, "depth": 2, "duration": 10, "heading": 45}
TRIGGER_WORDS = [
    "after the previous step completes",
    "at a time from the run's start",
    "on the operator's go",
]
#: The JSON's identifiers, never shown to the operator.
IDENTIFIERS = re.compile(r"after_previous|transmitted|into the dive|completion_s|\byes\b")


def add(page: Page, pattern: str, params: dict[str, Any]) -> None:
    count = page.locator("#script-steps > li").count()
    author(page, pattern, params)
    page.get_by_test_id("script-add").click()
    expect(page.locator("#script-steps > li")).to_have_count(count + 1)


def in_viewport(page: Page, testid: str) -> dict[str, float]:
    box: dict[str, float] = page.evaluate(
        "(id) => { const r = document.querySelector(`[data-testid='${id}']`)"
        ".getBoundingClientRect(); return {top: r.top, bottom: r.bottom, left: r.left,"
        " right: r.right, h: r.height, vw: innerWidth, vh: innerHeight}; }",
        testid,
    )
    return box


def test_the_preview_is_in_sight_and_the_panel_speaks_words_at_1280x800(
    console: Console, browser: Browser
) -> None:
    with sized_page(browser, 1280, 800, shot="script_panel_1280x800") as w:
        page = open_sized(w, console)
        add(page, "straight", STRAIGHT)
        add(page, "hover", HOVER)
        trigger = page.get_by_test_id("script-step-1-trigger")
        expect(trigger).to_have_value("after_previous")
        assert trigger.locator("option").all_text_contents() == TRIGGER_WORDS
        expect(page.get_by_test_id("script-step-0-t")).to_have_attribute(
            "aria-label", "step 1 time from the run's start (s)"
        )

        # the operator goes down to the script panel and previews: the plan is drawn there,
        # in sight, while the 3D view (top of the page) is not
        page.get_by_test_id("script-preview").scroll_into_view_if_needed()
        page.get_by_test_id("script-preview").click()
        plan = page.get_by_test_id("script-plan")
        expect(plan).to_be_visible()
        page.wait_for_function(
            "() => document.querySelectorAll('#script-plan .plan-step').length === 2",
            polling=POLL_MS,
        )
        box = in_viewport(page, "script-plan")
        assert box["h"] > 100, box
        assert box["top"] >= 0 and box["bottom"] <= box["vh"], f"the preview is out of sight: {box}"
        assert box["left"] >= 0 and box["right"] <= box["vw"], box
        viewer = in_viewport(page, "viewer-box")
        # the premise: down here the 3D view is (all but a sliver) out of sight, so the plan
        # view is what shows the script (the header's message row moves the sliver's size)
        assert viewer["bottom"] < viewer["h"] / 4, f"the 3D view should be out of sight: {viewer}"
        points = page.locator("#script-plan polyline").get_attribute("points") or ""
        assert len(points.split()) >= 2
        expect(page.get_by_test_id("script-plan-caption")).to_contain_text("Plan view, north up")

        # times and durations, labelled as such
        timeline = page.locator("#script-timeline > li")
        expect(timeline.first).to_have_text(
            "at 0 s from the run's start: straight starts (at its set time)"
        )
        expect(
            timeline.filter(has_text="from the run's start: hover retasks the vehicle")
        ).to_contain_text("(after step 1 completes, estimated)")
        expect(page.get_by_test_id("script-step-1-timing")).to_have_text(
            re.compile(
                r"^starts at [0-9.]+ s from the run's start \(estimated\), "
                r"takes 20 s \(estimated\)$"
            )
        )

        # run it: the straight, then the hover when the straight completes; the run is
        # completed when the vehicle reports the hover complete
        page.get_by_test_id("script-run").click()
        run_steps = page.locator("#script-run-steps > li")
        expect(run_steps).to_have_count(2)
        expect(run_steps.nth(1)).to_contain_text(
            "2. hover · after the previous step completes · takes 20 s (estimated) ·"
        )
        state = page.get_by_test_id("script-run-state")
        expect(state).to_have_attribute("data-outcome", "completed", timeout=30_000)
        expect(state).to_have_text(
            re.compile(
                r"^completed at [0-9.]+ s from the run's start: the vehicle reported step 2 "
                r"\(hover\) complete$"
            )
        )
        expect(run_steps.nth(0)).to_contain_text(
            "1. straight · at 0 s from the run's start · takes"
        )
        expect(run_steps.nth(1)).to_contain_text("acknowledged by the vehicle; completed at")
        run = console.get("/api/scripts/run")
        assert run["outcome"] == "completed" and run["completion_by"] == "vehicle", run
        hover = run["steps"][1]
        # not before the hover's 20 s after it went out
        assert run["completed_s"] >= hover["sent_s"] + HOVER["duration"] - 1e-6, run
        panel = page.get_by_test_id("script-panel").inner_text()
        assert not IDENTIFIERS.search(panel), IDENTIFIERS.search(panel)
        w.assert_clean()


def test_surface_during_a_run_stops_it_and_the_panel_says_why_at_once(
    console: Console, browser: Browser
) -> None:
    """The page is open, idle (not polling a run), when a run starts from the API; the
    operator presses Surface: the run is stopped (backend/scripts/guard.py) and the panel shows
    why, told by the mission log's event on /ws, and the later step as never sent."""
    script = {
        "format": "nemesys-mission-script",
        "version": 1,
        "name": "pod patrol",
        "steps": [
            {"pattern": "hover", "params": HOVER, "trigger": {"kind": "at", "t_s": 0}},
            {"pattern": "straight", "params": STRAIGHT, "trigger": {"kind": "at", "t_s": 900}},
        ],
    }
    with sized_page(browser, 1280, 800) as w:
        page = open_sized(w, console)
        state = page.get_by_test_id("script-run-state")
        expect(state).to_have_text("not running")
        expect(page.locator("#conn-state")).to_have_text("connected")
        console.post("/api/scripts/run", {"script": script, "mode": "auto"}, token=True)
        deadline = time.monotonic() + 20.0
        while console.get("/api/scripts/run")["waiting_for"] != "time":
            assert time.monotonic() < deadline, console.get("/api/scripts/run")
            time.sleep(0.05)
        page.get_by_test_id("surface-button").click()
        expect(state).to_have_attribute("data-outcome", "stopped")
        expect(state).to_have_text(
            re.compile(r"^stopped: the operator sent Surface \(command \d+\)$")
        )
        run_steps = page.locator("#script-run-steps > li")
        expect(run_steps.nth(1)).to_have_text(
            re.compile(
                r"^2\. straight · at 900 s from the run's start · takes [0-9.]+ s "
                r"\(estimated(; [0-9.]+ s by the plan's own clock)?\) · not sent yet$"
            )
        )
        expect(page.get_by_test_id("script-run")).to_be_enabled()
        run = console.get("/api/scripts/run")
        surface = max(console.get("/api/commands"), key=lambda c: c["id"])
        assert surface["pattern"] == "surface", surface
        assert run["reason"] == f"the operator sent Surface (command {surface['id']})", run
        w.assert_clean()
