"""The chart with a fleet of 5 at 1280x800 (issue 23): its fit, the automatic one of each new
preview and the Fit button's, holds every vehicle (not only the selected one and the preview),
and a label near the chart's edge goes to the side with room, so no label is cut.

The vehicles hold 0, 20, ... 80 m east of the origin (test_fleet_page.py's console); the
preview is a small circle at the selected vehicle, so a fit of it alone leaves the others out.
"""

from __future__ import annotations

from playwright.sync_api import Browser, Page, expect

from tests.frontend.pagekit import POLL_MS, sized_page, wait_preview
from tests.frontend.test_fleet_page import (
    NAMES,
    FleetConsole,
    assert_fleet_inside_chart,
    fleet_console,  # noqa: F401 (the fixture)
    fleet_outside_chart,
    open_fleet_page,
)

#: Pairs of labels, or a label and one of the chart's buttons or legend, that overlap.
LABEL_CLASHES = """
() => {
  const box = (n) => n.getBoundingClientRect();
  const hit = (a, b) => a.left < b.right - 0.5 && b.left < a.right - 0.5
    && a.top < b.bottom - 0.5 && b.top < a.bottom - 0.5;
  const labels = [...document.querySelectorAll('#chart .chart-fleet')].map(
    (m) => [m.dataset.vehicle, box(m.querySelector('.chart-fleet-label'))]);
  const controls = [...document.querySelectorAll('#chart .leaflet-control')].map(
    (c) => [c.className, box(c)]);
  const out = [];
  labels.forEach(([name, r], i) => {
    for (const [other, o] of [...labels.slice(i + 1), ...controls]) {
      if (hit(r, o)) out.push(`${name} / ${other}`);
    }
  });
  return out;
}
"""


def label_clashes(page: Page) -> list[str]:
    out: list[str] = page.evaluate(LABEL_CLASHES)
    return out


def test_the_fit_holds_every_vehicle_and_no_label_is_cut(
    fleet_console: FleetConsole,  # noqa: F811 (the fixture)
    browser: Browser,
) -> None:
    with sized_page(browser, 1280, 800, shot="fleet_chart_fit_1280x800") as w:
        page = open_fleet_page(w, fleet_console)
        chart = page.get_by_test_id("chart")
        expect(page.get_by_test_id("chart-panel")).to_have_class("chart-panel chart-ready")
        for name in NAMES:
            expect(page.get_by_test_id(f"chart-fleet-{name}")).to_be_visible()
        # the automatic fit of auv1's preview: every vehicle in, every label whole
        wait_preview(page, "circle")
        assert_fleet_inside_chart(page, "the preview's automatic fit")
        # the operator zooms in: vehicles leave the view (the check above can fail)
        zoom = float(chart.get_attribute("data-zoom") or 0)
        for level in (zoom + 1, zoom + 2):  # one click at a time
            page.locator("#chart .leaflet-control-zoom-in").click()
            page.wait_for_function(
                "(z) => Number(document.getElementById('chart').dataset.zoom) === z",
                arg=level,
                polling=POLL_MS,
            )
        expect(chart).to_have_attribute("data-fit", "operator")
        assert fleet_outside_chart(page), "zoomed in 2 levels, every vehicle still in view"
        # Fit: every vehicle in again, every label whole (the easternmost's to its left)
        page.get_by_test_id("chart-fit").click()
        expect(chart).to_have_attribute("data-fit", "auto")
        assert_fleet_inside_chart(page, "the Fit button")
        assert label_clashes(page) == [], "labels over each other or the chart's buttons"
        # another vehicle selected: its preview's fit still holds them all
        page.get_by_test_id("vehicle-select").select_option("auv5")
        page.wait_for_function(
            "() => (document.getElementById('estimates').dataset.command || '')"
            '.includes(\'"vehicle":"auv5"\')',
            polling=POLL_MS,
        )
        assert_fleet_inside_chart(page, "auv5's preview's fit")
        assert label_clashes(page) == [], "labels over each other or the chart's buttons"
        w.assert_clean()
