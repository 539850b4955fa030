"""The page fits a laptop and a desktop screen (issue 14, "a page that fits"): at 1280x800
and 1920x1080, for every pattern, Send, the estimates and the checks are in the window without
scrolling, not clipped by a scrolling box and not covered by anything; the 3D view and the
chart are both in sight beside them, and nothing overlaps. Also the lat/lon readouts: the
vehicle's position and the datum in degrees and decimal minutes, as backend/chart/geo.py gives
them."""

from __future__ import annotations

import time
from typing import Any

import pytest
from playwright.sync_api import Browser, Page, expect

from backend.chart.geo import Datum, dm, ned_to_geodetic
from tests.frontend.conftest import Console
from tests.frontend.pagekit import PATTERNS, POLL_MS, SIZES, open_sized, sized_page, wait_preview

#: In the browser: where an element is, whether a scrolling ancestor clips it, and whether
#: something else covers it (document.elementFromPoint at its centre and near its corners).
PLACE_JS = """
(id) => {
  const node = document.querySelector(`[data-testid="${id}"]`);
  const r = node.getBoundingClientRect();
  const clippedBy = [];
  for (let a = node.parentElement; a && a !== document.documentElement; a = a.parentElement) {
    const s = getComputedStyle(a);
    if ([s.overflow, s.overflowX, s.overflowY].some((o) => o !== "visible")) {
      const b = a.getBoundingClientRect();
      const out = r.left < b.left - 0.5 || r.right > b.right + 0.5
        || r.top < b.top - 0.5 || r.bottom > b.bottom + 0.5;
      if (out) clippedBy.push(a.className || a.tagName);
    }
  }
  const inset = 3;
  const points = [
    [(r.left + r.right) / 2, (r.top + r.bottom) / 2],
    [r.left + inset, r.top + inset], [r.right - inset, r.top + inset],
    [r.left + inset, r.bottom - inset], [r.right - inset, r.bottom - inset],
  ];
  const covered = points.filter(([x, y]) => {
    const hit = document.elementFromPoint(x, y);
    return !(hit && (hit === node || node.contains(hit)));
  }).map(([x, y]) => {
    const hit = document.elementFromPoint(x, y);
    const what = hit ? hit.tagName + "." + hit.className : "nothing";
    return `${Math.round(x)},${Math.round(y)}: ${what}`;
  });
  return {x: r.left, y: r.top, right: r.right, bottom: r.bottom, w: r.width, h: r.height,
          clippedBy, covered, vw: window.innerWidth, vh: window.innerHeight,
          scrollY: window.scrollY};
}
"""

#: Must be in sight for every pattern; the boxes that must not overlap one another.
MUST_SEE = ("send-button", "estimates", "violations")
NO_OVERLAP = ("author-foot", "author-scroll", "viewer-box", "chart-panel", "status-panel")


def place(page: Page, testid: str) -> dict[str, Any]:
    box: dict[str, Any] = page.evaluate(PLACE_JS, testid)
    return box


def assert_in_sight(page: Page, testid: str, what: str) -> dict[str, Any]:
    b = place(page, testid)
    assert b["scrollY"] == 0, f"{what}: the page was scrolled"
    assert b["w"] > 0 and b["h"] > 0, f"{testid} has no size ({what}): {b}"
    inside = b["x"] >= 0 and b["y"] >= 0 and b["right"] <= b["vw"] and b["bottom"] <= b["vh"]
    assert inside, f"{testid} is not inside the {b['vw']}x{b['vh']} window ({what}): {b}"
    assert not b["clippedBy"], f"{testid} is clipped by {b['clippedBy']} ({what})"
    assert not b["covered"], f"{testid} is covered at {b['covered']} ({what})"
    return b


def overlap(a: dict[str, Any], b: dict[str, Any]) -> bool:
    across = float(min(a["right"], b["right"]) - max(a["x"], b["x"]))
    down = float(min(a["bottom"], b["bottom"]) - max(a["y"], b["y"]))
    return across > 0.5 and down > 0.5


@pytest.mark.parametrize("size", list(SIZES))
def test_send_estimates_and_checks_are_in_sight_for_every_pattern(
    console: Console, browser: Browser, size: str
) -> None:
    width, height = SIZES[size]
    with sized_page(browser, width, height, shot=f"layout_{size}_helix") as w:
        page = open_sized(w, console)
        for pattern in PATTERNS:
            wait_preview(page, pattern)
            for testid in MUST_SEE:
                assert_in_sight(page, testid, f"{pattern} at {size}")
            expect(page.get_by_test_id("send-button")).to_be_enabled()
        # the 3D view and the chart, both in sight and of a useful size
        for testid, min_w, min_h in (("viewer", 300, 200), ("chart", 300, 220)):
            seen = assert_in_sight(page, testid, f"{size}")
            big = seen["w"] >= min_w and seen["h"] >= min_h
            assert big, f"{testid} too small at {size}: {seen}"
        boxes = {t: place(page, t) for t in NO_OVERLAP}
        for i, one in enumerate(NO_OVERLAP):
            for other in NO_OVERLAP[i + 1 :]:
                assert not overlap(boxes[one], boxes[other]), f"{one} overlaps {other}: {boxes}"
        # the page's own layout does not scroll sideways
        assert page.evaluate("() => document.documentElement.scrollWidth") <= width
        w.assert_clean()


def test_screenshot_of_a_lawnmower_preview_at_1280x800(console: Console, browser: Browser) -> None:
    """The artefact of the closing note: the whole window with a lawnmower preview."""
    with sized_page(browser, 1280, 800, shot="layout_1280x800_lawnmower") as w:
        page = open_sized(w, console)
        wait_preview(page, "lawnmower")
        for testid in MUST_SEE:
            assert_in_sight(page, testid, "lawnmower at 1280x800")
        w.assert_clean()


# ---- latitude and longitude -------------------------------------------------------------------


def expected_latlon(datum: Datum, x_m: float, y_m: float) -> str:
    lat, lon = ned_to_geodetic(datum, x_m, y_m)
    return f"{dm(float(lat), lat=True)} {dm(float(lon), lat=False)}"


@pytest.mark.parametrize("size", list(SIZES))
def test_position_and_datum_are_shown_in_degrees_and_decimal_minutes(
    console: Console, browser: Browser, size: str
) -> None:
    session = console.get("/api/session")
    assert session.get("datum"), f"training has a datum: {session.get('datum')}"
    datum = Datum(session["datum"]["lat_deg"], session["datum"]["lon_deg"])
    # move the vehicle off the origin: 60 s north-east at 0.18 m/s, then it holds there
    straight = {"speed": 0.18, "depth": 1, "duration": 60, "heading": 45}
    console.post("/api/commands", {"pattern": "straight", "params": straight}, token=True)
    with sized_page(browser, *SIZES[size], shot=f"latlon_{size}") as w:
        page = open_sized(w, console)
        expect(page.get_by_test_id("status-datum")).to_have_text(expected_latlon(datum, 0.0, 0.0))
        deadline = time.monotonic() + 40.0
        while True:
            pose = console.get("/api/vehicle")["pose"]
            x, y = pose["x_m"], pose["y_m"]
            want = expected_latlon(datum, x, y)
            assert (pose["lat_deg"], pose["lon_deg"]) != (None, None)
            api_text = f"{dm(pose['lat_deg'], lat=True)} {dm(pose['lon_deg'], lat=False)}"
            shown = page.get_by_test_id("status-latlon").text_content()
            moved = x > 5.0 and y > 5.0
            if moved and shown == want and api_text == want:
                break
            assert time.monotonic() < deadline, (
                f"lat/lon shown {shown!r}, expected {want!r} (API {api_text!r}) at x {x}, y {y}"
            )
            page.wait_for_timeout(POLL_MS)
        # one line: the north/east metres and the lat/lon never wrap mid-way
        for testid in ("status-position", "status-latlon", "status-datum"):
            assert page.evaluate(
                "(id) => { const n = document.querySelector(`[data-testid=${id}]`);"
                " const lh = parseFloat(getComputedStyle(n).lineHeight)"
                " || parseFloat(getComputedStyle(n).fontSize) * 1.4;"
                " return n.getBoundingClientRect().height < 1.8 * lh; }",
                testid,
            ), f"{testid} wraps"
        w.assert_clean()


def test_dm_in_the_page_matches_backend_geo(console: Console, browser: Browser) -> None:
    """frontend/ui.js dm() prints exactly what backend/chart/geo.py dm() prints, hemispheres,
    zero padding, the 59.9995' carry and exact ties included."""
    values = [
        0.0,
        29.5316,
        -82.3031,
        0.5,
        -0.5,
        89.99999999,
        -179.9999999,
        12.0625 / 60 + 3,
        45.0 + 0.0625 / 60,
        45.0 + 0.0635 / 60,
        1e-9,
        -1e-9,
        179.99,
        7.25,
        -33.8688,
        151.2093,
    ]
    with sized_page(browser, 1280, 800) as w:
        page = open_sized(w, console)
        shown = page.evaluate(
            "async (values) => { const ui = await import('/static/ui.js');"
            " return values.map((v) => [ui.dm(v, true), ui.dm(v, false)]); }",
            values,
        )
        want = [[dm(v, lat=True), dm(v, lat=False)] for v in values]
        assert shown == want
