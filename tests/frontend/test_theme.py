"""The day theme (issue 14): a light, high-contrast theme for sunlight beside the dark one. A
toggle in the header, remembered across reloads, the system's preference on a first visit; the
text of the key elements meets WCAG AA contrast (4.5:1) against what is behind it, in both."""

from __future__ import annotations

import pytest
from playwright.sync_api import Browser, Page, expect

from tests.frontend.conftest import Console
from tests.frontend.pagekit import SIZES, open_sized, sized_page, wait_preview

#: In the browser: the WCAG contrast ratio of an element's text colour against the first
#: opaque background behind it (its own or an ancestor's; the page's when none).
CONTRAST_JS = """
(selector) => {
  const node = document.querySelector(selector);
  if (!node) return null;
  const parse = (c) => (c.match(/[\\d.]+/g) || []).map(Number);
  const lum = ([r, g, b]) => {
    const f = (v) => { v /= 255; return v <= 0.03928 ? v / 12.92 : ((v + 0.055) / 1.055) ** 2.4; };
    return 0.2126 * f(r) + 0.7152 * f(g) + 0.0722 * f(b);
  };
  const fg = parse(getComputedStyle(node).color);
  let bg = null;
  for (let a = node; a && !bg; a = a.parentElement) {
    const c = parse(getComputedStyle(a).backgroundColor);
    if (c.length === 3 || (c.length === 4 && c[3] === 1)) bg = c.slice(0, 3);
  }
  bg = bg || [255, 255, 255];
  const [l1, l2] = [lum(fg), lum(bg)].sort((x, y) => y - x);
  return (l1 + 0.05) / (l2 + 0.05);
}
"""

#: The text an operator reads in the sun: labels, values, estimates, the verdict, the buttons.
KEY_TEXT = (
    "body",
    "#authoring-title",
    ".author-foot h3",
    "#estimates dt",
    "#estimates dd",
    "#violations li",
    "#send-button",
    "#surface-button",
    ".header-facts dt",
    "#auth-state",
    "#status-depth",
    ".status-grid dt",
    "#status-latlon",
    "#param-form label",
    "#param-form .hint",
    "#param-form input",
    "#copies-hint",
)
AA_NORMAL = 4.5


def theme(page: Page) -> str:
    value: str = page.evaluate("() => document.documentElement.dataset.theme")
    return value


def contrasts(page: Page) -> dict[str, float]:
    out = {}
    for selector in KEY_TEXT:
        ratio = page.evaluate(CONTRAST_JS, selector)
        assert ratio is not None, f"no element {selector}"
        out[selector] = ratio
    return out


def assert_aa(page: Page) -> None:
    ratios = contrasts(page)
    assert len({round(r, 1) for r in ratios.values()}) > 3, f"not measured: {ratios}"
    assert all(1.0 <= r <= 21.0 for r in ratios.values()), ratios
    low = {s: round(r, 2) for s, r in ratios.items() if r < AA_NORMAL}
    assert not low, f"below WCAG AA ({AA_NORMAL}:1) in the {theme(page)} theme: {low}"


@pytest.mark.parametrize("size", list(SIZES))
def test_day_theme_toggles_persists_and_keeps_aa_contrast(
    console: Console, browser: Browser, size: str
) -> None:
    with sized_page(browser, *SIZES[size], shot=f"theme_day_{size}", scheme="dark") as w:
        page = open_sized(w, console)
        wait_preview(page, "circle")
        assert theme(page) == "night", "a first visit follows the system's dark preference"
        night_bg = page.evaluate("() => getComputedStyle(document.body).backgroundColor")
        assert_aa(page)

        toggle = page.get_by_test_id("theme-toggle")
        expect(toggle).to_have_attribute("aria-pressed", "false")
        toggle.click()
        assert theme(page) == "day"
        expect(toggle).to_have_attribute("aria-pressed", "true")
        day_bg = page.evaluate("() => getComputedStyle(document.body).backgroundColor")
        assert day_bg == "rgb(255, 255, 255)" and day_bg != night_bg
        assert_aa(page)

        # remembered: the reload comes back in the day theme, whatever the system prefers
        page.reload()
        page.wait_for_function("() => document.querySelector('#estimates')")
        assert theme(page) == "day"
        expect(toggle).to_have_attribute("aria-pressed", "true")
        wait_preview(page, "circle")
        assert_aa(page)

        toggle.click()
        assert theme(page) == "night"
        page.reload()
        page.wait_for_function("() => document.querySelector('#estimates')")
        assert theme(page) == "night"
        w.assert_clean()


def test_first_visit_follows_a_light_system_preference(console: Console, browser: Browser) -> None:
    with sized_page(browser, 1280, 800, scheme="light") as w:
        page = open_sized(w, console)
        assert theme(page) == "day"
        expect(page.get_by_test_id("theme-toggle")).to_have_text("Night")
        w.assert_clean()
