"""The chart fits each new preview (not only the first) until the operator moves or zooms it;
its Fit button fits again and brings the refit back. Real Chromium at 1280x800."""

from __future__ import annotations

import json

import pytest
from playwright.sync_api import Browser, Page, expect

from tests.frontend.conftest import Console
from tests.frontend.pagekit import POLL_MS, SIZES, open_sized, sized_page, wait_preview

pytestmark = pytest.mark.browser

CIRCLE = {"speed": 0.18, "depth": 3, "radius": 5, "direction": "cw"}

#: The preview's drawn lines all inside the chart's box (the fit shows the whole path).
PREVIEW_INSIDE = """
() => {
  const chart = document.getElementById('chart').getBoundingClientRect();
  const lines = [...document.querySelectorAll('#chart path.chart-preview')];
  if (!lines.length) return false;
  return lines.every((l) => {
    const r = l.getBoundingClientRect();
    return r.left >= chart.left - 1 && r.right <= chart.right + 1
      && r.top >= chart.top - 1 && r.bottom <= chart.bottom + 1;
  });
}
"""


def chart_data(page: Page, key: str) -> int:
    value = page.get_by_test_id("chart").get_attribute(f"data-{key}")
    return int(float(value or 0))


def set_radius(page: Page, radius: float) -> None:
    """Edit the radius; return once the page has drawn that command's preview (the chart
    draws it, and fits it or not, in the same task as the estimates)."""
    page.get_by_test_id("param-radius").fill(str(radius))
    command = json.dumps({"pattern": "circle", "params": {**CIRCLE, "radius": radius}})
    page.wait_for_function(
        "(c) => document.getElementById('estimates').dataset.command === c",
        arg=command.replace(" ", ""),
        polling=POLL_MS,
    )


def fitted_to(page: Page, zoom_before: int, *, wider: bool) -> int:
    """Wait until the chart has zoomed out (``wider``) or in from ``zoom_before`` and shows
    the whole preview; returns the new zoom."""
    cmp = "<" if wider else ">"
    page.wait_for_function(
        f"(z) => Number(document.getElementById('chart').dataset.zoom) {cmp} z",
        arg=zoom_before,
        polling=POLL_MS,
    )
    page.wait_for_function(PREVIEW_INSIDE, polling=POLL_MS)
    return chart_data(page, "zoom")


def test_the_chart_fits_each_new_preview_until_the_operator_moves_it(
    browser: Browser, console: Console
) -> None:
    with sized_page(browser, *SIZES["1280x800"], shot="chart_fit") as w:
        page = open_sized(w, console)
        expect(page.get_by_test_id("chart-panel")).to_have_class("chart-panel chart-ready")
        wait_preview(page, "circle")
        for name in ("speed", "depth"):
            page.get_by_test_id(f"param-{name}").fill(str(CIRCLE[name]))
        set_radius(page, 5)
        page.wait_for_function(PREVIEW_INSIDE, polling=POLL_MS)
        small = chart_data(page, "zoom")
        # a bigger circle: fitted again (zoomed out), the whole of it in view
        set_radius(page, 120)
        big = fitted_to(page, small, wider=True)
        # the operator zooms in: the next previews leave the view as the operator set it
        for level in (big + 1, big + 2):  # one click at a time: Leaflet skips one mid-zoom
            page.locator("#chart .leaflet-control-zoom-in").click()
            page.wait_for_function(
                "(z) => Number(document.getElementById('chart').dataset.zoom) === z",
                arg=level,
                polling=POLL_MS,
            )
        expect(page.get_by_test_id("chart")).to_have_attribute("data-fit", "operator")
        fits = chart_data(page, "fits")
        set_radius(page, 300)  # bigger than the view: not refitted all the same
        assert chart_data(page, "fits") == fits, "a preview refitted a chart the operator zoomed"
        assert chart_data(page, "zoom") == big + 2
        assert not page.evaluate(PREVIEW_INSIDE)
        # Fit: the view fits again, and so does each new preview from then on
        page.get_by_test_id("chart-fit").click()
        wide = fitted_to(page, big, wider=True)
        expect(page.get_by_test_id("chart")).to_have_attribute("data-fit", "auto")
        set_radius(page, 60)
        fitted_to(page, wide, wider=False)
        w.assert_clean()
