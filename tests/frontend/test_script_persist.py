"""The mission script panel in real Chromium: steps authored in the page survive a reload
(kept in localStorage), corrupt stored data gives a notice and not a crash, "Clear script"
empties it, and the page refuses "on completion" after a circle, saying why."""

from __future__ import annotations

from typing import Any

from playwright.sync_api import Page, expect

from tests.frontend.conftest import Console, Watched
from tests.frontend.test_browser import author, open_page

HOVER: dict[str, Any] = {"duration": 200, "depth": 3, "heading": 90}
LAWNMOWER: dict[str, Any] = {
    "speed": 0.18,
    "depth": 3,
    "sweep_length": 12,
    "lane_spacing": 2,
    "laps": 2,
}
CIRCLE: dict[str, Any] = {"speed": 0.18, "depth": 3, "radius": 4, "direction": "ccw"}
STRAIGHT: dict[str, Any] = {"speed": 0.18, "depth": 2, "duration": 60, "heading": 45}
REFUSAL = (
    "step 4 waits for step 3 (circle) to complete, but a circle repeats until retasked, so it "
    "never completes: use a time ('at') or the operator's go"
)


def add(page: Page, pattern: str, params: dict[str, Any]) -> None:
    count = page.locator("#script-steps > li").count()
    author(page, pattern, params)
    page.get_by_test_id("script-add").click()
    expect(page.locator("#script-steps > li")).to_have_count(count + 1)


def reload(watched: Watched, console: Console) -> Page:
    """Load the page again (same browser context, so the same localStorage) and wait until
    it is built."""
    return open_page(watched, console)


def test_steps_survive_a_reload_and_clear_empties_them(console: Console, watched: Watched) -> None:
    page = open_page(watched, console)
    page.get_by_test_id("script-name").fill("survey then hold")
    add(page, "hover", HOVER)
    add(page, "lawnmower", LAWNMOWER)
    page.get_by_test_id("script-step-1-trigger").select_option("at")
    page.get_by_test_id("script-step-1-t").fill("300")

    page = reload(watched, console)
    expect(page.locator("#script-steps > li")).to_have_count(2)
    expect(page.get_by_test_id("script-name")).to_have_value("survey then hold")
    expect(page.get_by_test_id("script-step-0-pattern")).to_have_value("hover")
    expect(page.get_by_test_id("script-step-0-trigger")).to_have_value("at")
    expect(page.get_by_test_id("script-step-1-pattern")).to_have_value("lawnmower")
    expect(page.get_by_test_id("script-step-1-trigger")).to_have_value("at")
    expect(page.get_by_test_id("script-step-1-t")).to_have_value("300")
    expect(page.get_by_test_id("script-step-0-param-duration")).to_have_value("200")
    expect(page.get_by_test_id("script-step-1-param-sweep_length")).to_have_value("12")
    expect(page.get_by_test_id("message").filter(has_text="restored the script")).to_have_count(1)
    # what was restored is what the API previews: the hover's 200 s, the lawnmower at 300 s
    page.get_by_test_id("script-preview").click()
    timeline = page.locator("#script-timeline > li")
    expect(
        timeline.filter(
            has_text="at 300 s from the run's start: lawnmower retasks the vehicle "
            "(at its set time)"
        )
    ).to_have_count(1)
    expect(
        timeline.filter(has_text="at 200 s from the run's start: hover completes")
    ).to_have_count(1)

    page.get_by_test_id("script-clear").click()
    expect(page.locator("#script-steps > li")).to_have_count(0)
    page = reload(watched, console)
    expect(page.locator("#script-steps > li")).to_have_count(0)
    watched.assert_clean()


def test_corrupt_stored_script_gives_a_notice_not_a_crash(
    console: Console, watched: Watched
) -> None:
    page = open_page(watched, console)
    for stored, why in (
        ("{not json", "not JSON"),
        ('{"format": "nemesys-mission-script", "version": 0, "steps": []}', "version 0"),
        (
            '{"format": "nemesys-mission-script", "version": 1, "name": "x",'
            ' "steps": [{"pattern": "teleport", "trigger": {"kind": "at"}}]}',
            "unknown pattern teleport",
        ),
    ):
        page.evaluate("(text) => localStorage.setItem('nemesys.script', text)", stored)
        page = reload(watched, console)
        notice = page.get_by_test_id("message").filter(has_text="could not be restored")
        expect(notice.first).to_contain_text(why)
        expect(page.locator("#script-steps > li")).to_have_count(0)
        # the page still works: a step can be added, and is kept
        add(page, "hover", HOVER)
        assert "hover" in (page.evaluate("() => localStorage.getItem('nemesys.script')") or "")
        page.get_by_test_id("script-clear").click()
    watched.assert_clean()


def test_the_page_refuses_on_completion_after_a_circle(console: Console, watched: Watched) -> None:
    page = open_page(watched, console)
    add(page, "hover", HOVER)
    add(page, "lawnmower", LAWNMOWER)
    add(page, "circle", CIRCLE)
    expect(page.get_by_test_id("script-step-2-trigger")).to_have_value("after_previous")
    # a step added after the circle starts on the operator's go, and the page says why
    add(page, "straight", STRAIGHT)
    expect(page.get_by_test_id("script-step-3-trigger")).to_have_value("operator")
    expect(
        page.get_by_test_id("message").filter(has_text="repeats until retasked")
    ).not_to_have_count(0)
    # choosing "after the previous step completes" is refused with the reason
    page.get_by_test_id("script-step-3-trigger").select_option("after_previous")
    expect(page.get_by_test_id("script-step-3-trigger")).to_have_value("operator")
    check = page.get_by_test_id("script-step-3-check")
    expect(check).to_be_visible()
    expect(check).to_have_text(REFUSAL)
    # a time is accepted, and the message goes
    page.get_by_test_id("script-step-3-trigger").select_option("at")
    expect(page.get_by_test_id("script-step-3-trigger")).to_have_value("at")
    expect(check).to_be_hidden()
    # a stored script with the refused trigger (moved into place) is flagged, and the API
    # refuses it with the same words
    page.get_by_test_id("script-step-3-trigger").select_option("operator")
    page.get_by_test_id("script-step-3-up").click()  # straight now follows the lawnmower
    page.get_by_test_id("script-step-2-trigger").select_option("after_previous")
    page.get_by_test_id("script-step-3-up").click()  # circle, then straight on completion
    expect(page.get_by_test_id("script-step-2-pattern")).to_have_value("circle")
    expect(page.get_by_test_id("script-step-3-trigger")).to_have_value("after_previous")
    expect(check).to_have_text(REFUSAL)
    page.get_by_test_id("script-preview").click()
    expect(check).to_have_text(f"trigger.kind: {REFUSAL}")
    stored = page.evaluate("() => JSON.parse(localStorage.getItem('nemesys.script'))")
    assert [s["pattern"] for s in stored["steps"]] == ["hover", "lawnmower", "circle", "straight"]
