"""The link panel's BER estimate (frontend/link.js) and the "copies follow" choice
(frontend/assumptions.js): in training beside the emulated BER, and on a one-way modem link
where no acknowledgement comes (the choice falls back to the assumed BER and says so)."""

from __future__ import annotations

import re
import time
from typing import Any

import pytest
from playwright.sync_api import expect

from tests.frontend.conftest import Console, Watched
from tests.frontend.pagekit import open_sized

CIRCLE = {"speed": 0.18, "depth": 3, "radius": 5, "direction": "cw"}
FINAL = {"acknowledged", "rejected", "timed_out", "superseded", "interrupted", "sent"}


def rate(x: float) -> str:
    """As the page writes a rate: two significant digits, as typed."""
    return "0" if x == 0 else repr(float(f"{x:.2g}"))


def acknowledged_frames(console: Console, frames: int) -> dict[str, Any]:
    """Send circles one at a time until the link's estimate rests on ``frames`` frames."""
    deadline = time.monotonic() + 60.0
    while True:
        channel: dict[str, Any] = console.get("/api/vehicle")["link"]["channel"]
        if channel["frames"] >= frames:
            return channel
        assert time.monotonic() < deadline, channel
        record = console.post("/api/commands", {"pattern": "circle", "params": CIRCLE}, token=True)
        while console.get(f"/api/commands/{record['id']}")["state"] not in FINAL:
            assert time.monotonic() < deadline, record
            time.sleep(0.05)


def test_in_training_the_estimate_shows_beside_the_emulated_ber(
    console: Console, watched: Watched
) -> None:
    console.put("/api/training/channel", {"ber": 0.02})
    page = open_sized(watched, console)
    estimate = page.get_by_test_id("link-ber-estimate")
    expect(estimate).to_have_text(re.compile(r"^estimated: no estimate yet \(\d frames?\)$"))
    link = page.get_by_test_id("status-link")
    expect(link).to_contain_text("BER 2e-2 (emulated channel)")

    channel = acknowledged_frames(console, 12)
    assert channel["ber"] is not None, channel
    # the page follows the link messages (every second): the same figures, as it writes them
    shown = console.get("/api/vehicle")["link"]["channel"]
    expect(estimate).to_have_text(
        f"estimated: BER \u2248 {rate(shown['ber'])} (95 % {rate(shown['low'])}"
        f"\u2013{rate(shown['high'])}, {shown['frames']} frames)"
    )
    expect(link).to_contain_text("BER 2e-2 (emulated channel)")  # the copies still follow it
    # the choice is the emulated channel's in training
    page.get_by_test_id("link-details").locator("summary").click()
    expect(page.get_by_test_id("copies-from-input")).to_be_disabled()
    expect(page.get_by_test_id("copies-from-note")).to_have_text(
        "training: the emulated channel's BER"
    )
    watched.assert_clean()


@pytest.mark.parametrize("console_env", [{"NEMESYS_TARGET": "loop://"}], ids=["loop-modem"])
def test_choosing_the_estimates_upper_end_without_an_estimate_says_the_assumed_ber_is_used(
    console: Console, watched: Watched
) -> None:
    page = open_sized(watched, console)
    estimate = page.get_by_test_id("link-ber-estimate")
    expect(estimate).to_have_text("estimated: none (no acknowledgements on this link)")
    link = page.get_by_test_id("status-link")
    expect(link).to_contain_text("BER 1e-3 (assumed)")
    choice = page.get_by_test_id("copies-from-input")
    expect(choice).to_be_enabled()
    expect(choice).to_have_value("assumed")

    choice.select_option("estimate_upper")
    page.get_by_test_id("link-apply").click()
    expect(page.get_by_test_id("link-apply-result")).to_contain_text("copies per command now")
    expect(link).to_contain_text("BER 1e-3 (assumed: no estimate yet for the chosen upper end)")
    health = console.get("/api/vehicle")["link"]
    assert health["copies_from"] == "estimate_upper" and health["ber_source"] == "assumed"
    # a reload shows the console's choice, not the form's default
    page.reload()
    expect(page.get_by_test_id("copies-from-input")).to_have_value("estimate_upper")
    watched.assert_clean()
