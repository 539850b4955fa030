"""The confirm dialog lists every check a send runs (issue 19, item 4): a 740 m circle in
training (the transmitter at the datum, 730 m of ME range, the twin's 26,110 s endurance) is
named out of reach and beyond the battery, both soft (the override checkbox sends it), and
the repeating pattern says "repeats until retasked (one lap N s)", never a total duration; a
depth beyond the rating is hard (no override sends it). Chromium at 1280x800."""

from __future__ import annotations

import re

from playwright.sync_api import Browser, expect

from tests.frontend.conftest import Console
from tests.frontend.pagekit import open_sized, sized_page, wait_preview

DASH = "\u2013"  # the page's "no value" mark
LAP = re.compile(r"^repeats until retasked \(one lap [\d,]+ s\)$")


def test_the_confirm_dialog_lists_the_checks_of_a_wide_circle(
    console: Console, browser: Browser
) -> None:
    with sized_page(browser, 1280, 800, shot="confirm_checks_wide_circle") as w:
        page = open_sized(w, console)
        wait_preview(page, "circle")
        for k, v in {"speed": "0.18", "depth": "5", "radius": "740"}.items():
            page.get_by_test_id(f"param-{k}").fill(v)
        # the authoring column's estimates: no total duration for a repeating pattern
        duration = page.locator('#estimates [data-key="duration"] dd')
        expect(duration).to_have_text(LAP)

        page.get_by_test_id("send-button").click()
        dialog = page.get_by_test_id("confirm-dialog")
        expect(dialog).to_be_visible()
        estimates = page.get_by_test_id("confirm-estimates")
        expect(estimates.locator('[data-key="duration"] dd')).to_have_text(LAP)

        checks = page.get_by_test_id("confirm-checks")
        for check in ("depth_rating", "depth_limit", "speed_limit", "top_speed", "geofence"):
            expect(checks.locator(f'li[data-check="{check}"]')).to_have_count(1)
        expect(checks.locator('li[data-check="geofence"]')).to_have_attribute(
            "data-status", "skipped"
        )
        expect(checks.locator('li[data-check="top_speed"]')).to_have_attribute("data-status", "ok")
        reach = checks.locator('li[data-check="reach"]')
        expect(reach).to_have_attribute("data-status", "violated")
        expect(reach).to_have_attribute("data-kind", "soft")
        expect(reach).to_contain_text(
            re.compile(
                r"the path goes 7\d\d m from the transmitter, beyond the ME link's 730 m range: "
                r"the next retask could not reach the vehicle there"
            )
        )
        expect(reach).to_contain_text("soft: needs the override")
        endurance = checks.locator('li[data-check="endurance"]')
        expect(endurance).to_have_attribute("data-status", "violated")
        expect(endurance).to_have_attribute("data-kind", "soft")
        expect(endurance).to_contain_text(
            re.compile(r"the join and one lap take [\d,]+ s, beyond the [\d,]+ s the battery has")
        )
        expect(page.get_by_test_id("confirm-checks-summary")).to_contain_text(
            "2 soft (needs the override)"
        )
        body = page.get_by_test_id("confirm-body").text_content() or ""
        assert "within limits" not in body and DASH not in body, body

        # soft: the override checkbox, and only it, lets it go
        send = page.get_by_test_id("confirm-send")
        expect(page.get_by_test_id("confirm-override")).to_be_visible()
        expect(send).to_be_disabled()
        page.get_by_test_id("confirm-override").check()
        expect(send).to_be_enabled()
        page.get_by_test_id("confirm-cancel").click()
        expect(dialog).to_be_hidden()

        # hard: beyond the rating, no override sends it
        page.get_by_test_id("param-depth").fill("105")
        page.get_by_test_id("send-button").click()
        expect(dialog).to_be_visible()
        rating = checks.locator('li[data-check="depth_rating"]')
        expect(rating).to_have_attribute("data-kind", "hard")
        expect(rating).to_contain_text("hard: cannot be sent")
        page.get_by_test_id("confirm-override").check()
        expect(send).to_be_disabled()
        page.get_by_test_id("confirm-cancel").click()
        assert console.get("/api/commands") == []  # nothing was sent
        w.assert_clean()
