"""Messages (toasts) in real Chromium at the laptop and desktop sizes: they never cover a
control (element bounding boxes), and an error message goes when its cause is fixed."""

from __future__ import annotations

import pytest
from playwright.sync_api import Browser, Page, expect

from tests.frontend.conftest import Console
from tests.frontend.pagekit import POLL_MS, SIZES, open_sized, sized_page, wait_preview

pytestmark = pytest.mark.browser

#: Everything an operator can press, type into or drag, outside the messages themselves.
CONTROLS = (
    "button, input, select, textarea, a[href], summary, iframe, [role=button], "
    "#chart.leaflet-container, .uplot .u-over"
)

#: Each message's box against each visible control's box in the viewport: the overlaps, and
#: whether the Clear replay button is the element at its own centre (nothing drawn over it).
OVERLAPS = """
(selector) => {
  window.scrollTo(0, 0);
  const messages = [...document.querySelectorAll('#messages [data-testid=message]')];
  const boxes = messages.map((m) => m.getBoundingClientRect());
  const inViewport = (r) => r.width > 0 && r.height > 0 && r.bottom > 0 && r.right > 0
    && r.top < window.innerHeight && r.left < window.innerWidth;
  const hits = [];
  let controls = 0;
  for (const c of document.querySelectorAll(selector)) {
    if (c.closest('#messages, dialog:not([open]), [hidden]')) continue;
    const r = c.getBoundingClientRect();
    if (!inViewport(r) || getComputedStyle(c).visibility === 'hidden') continue;
    controls += 1;
    for (const [i, m] of boxes.entries()) {
      const x = Math.min(r.right, m.right) - Math.max(r.left, m.left);
      const y = Math.min(r.bottom, m.bottom) - Math.max(r.top, m.top);
      if (x > 0.5 && y > 0.5) hits.push(`${messages[i].textContent} covers ${c.outerHTML}`);
    }
  }
  const clear = document.getElementById('clear-replay').getBoundingClientRect();
  const top = document.elementFromPoint(clear.x + clear.width / 2, clear.y + clear.height / 2);
  const clearOnTop = top !== null && top.id === 'clear-replay';
  return { messages: messages.length, controls, hits, clearOnTop };
}
"""


def show_three_messages(page: Page, console: Console) -> None:
    """Two information messages (the issue's: a replay drawn, covering Clear replay) and an
    error (a Send with a depth beyond the dictionary's range)."""
    while not console.get("/api/dives"):  # the dive the simulator's first pose starts
        pass
    page.get_by_test_id("log-refresh").evaluate("b => b.click()")  # no scroll
    replay = page.get_by_test_id("replay-1")
    expect(replay).to_be_enabled()
    for _ in range(2):
        replay.evaluate("b => b.click()")
        page.wait_for_function(
            "() => document.querySelectorAll('#messages .message-info').length >= 1",
            polling=POLL_MS,
        )
    page.get_by_test_id("param-depth").fill("500")
    page.get_by_test_id("send-button").click()
    expect(page.locator("#messages .message-error")).to_have_count(1)
    expect(page.get_by_test_id("messages").get_by_test_id("message")).to_have_count(3)


@pytest.mark.parametrize("size", sorted(SIZES))
def test_messages_cover_no_control(browser: Browser, console: Console, size: str) -> None:
    width, height = SIZES[size]
    with sized_page(browser, width, height, shot=f"toasts_{size}") as w:
        page = open_sized(w, console)
        wait_preview(page, "circle")
        show_three_messages(page, console)
        found = page.evaluate(OVERLAPS, CONTROLS)
        assert found["messages"] == 3
        assert found["controls"] > 20, found  # the check looked at the page's controls
        assert found["hits"] == [], found["hits"]
        assert found["clearOnTop"], "the Clear replay button is covered"


def test_an_error_message_goes_when_its_cause_is_fixed(browser: Browser, console: Console) -> None:
    with sized_page(browser, *SIZES["1280x800"]) as w:
        page = open_sized(w, console)
        wait_preview(page, "circle")
        errors = page.locator("#messages .message-error")
        page.get_by_test_id("param-depth").fill("500")
        for _ in range(2):  # pressed twice: one message, its cause named once
            page.get_by_test_id("send-button").click()
            expect(errors).to_have_count(1)
        expect(errors.first).to_contain_text("Fix the parameters first: depth")
        expect(page.get_by_test_id("confirm-dialog")).to_be_hidden()
        page.get_by_test_id("param-depth").fill("4")  # fixed: the preview of 4 m succeeds
        expect(errors).to_have_count(0)
        expect(page.get_by_test_id("error-depth")).to_be_hidden()
        page.get_by_test_id("send-button").click()  # and Send opens its dialog now
        expect(page.get_by_test_id("confirm-dialog")).to_be_visible()
