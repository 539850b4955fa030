"""The page's 2D chart (Leaflet), predicted track and telemetry plots (uPlot) in real
Chromium at 1280x800 (the chart's drawing at 1920x1080 too), against a real console in
training mode (datum: training's site).

Leaflet and uPlot come from npm (``frontend/vendor``, ``make test`` installs them) and are
served by the console itself: every request the page makes must stay on loopback, and none of
the /vendor ones may fail. The REST API is the oracle (datum, range, preview, vehicle).
"""

from __future__ import annotations

import json
import math
import re
import struct
import zlib
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import pytest
from playwright.sync_api import Page, Response, expect

from backend.chart.geo import TRAINING_DATUM
from tests.frontend.conftest import TOKEN, Console, Watched
from tests.frontend.pagekit import SIZES

POLL_MS = 100
WIDTH, HEIGHT = 1280, 800
#: The sim at time scale 10: an acknowledgement and a few metres of motion take seconds.
MOVE_MS = 30_000
#: Speed within the training vehicle's top speed (no overridable violation to confirm).
STRAIGHT_EAST = {"speed": 0.18, "depth": 2, "duration": 120, "heading": 90}  # heading last
LAT_LABEL = re.compile(r"^(\d{2})°(\d{2}\.\d{3})'([NS])$")
LON_LABEL = re.compile(r"^(\d{3})°(\d{2}\.\d{3})'([EW])$")
TILES = "tiles"  # console_env parameter: a directory of local tiles around the datum
TILE_ZOOMS = range(14, 18)


# ---- fixtures ----------------------------------------------------------------------------


def png_tile(rgb: tuple[int, int, int], size: int = 256) -> bytes:
    """A solid ``size`` x ``size`` RGB PNG."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    row = b"\x00" + bytes(rgb) * size
    header = struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0)
    body = zlib.compress(row * size)
    return (
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", body) + chunk(b"IEND", b"")
    )


def tile_xy(lat_deg: float, lon_deg: float, z: int) -> tuple[int, int]:
    """The XYZ (slippy map) tile holding a point at zoom ``z``."""
    n = 1 << z
    x = int((lon_deg + 180.0) / 360.0 * n)
    lat = math.radians(lat_deg)
    y = int((1.0 - math.asinh(math.tan(lat)) / math.pi) / 2.0 * n)
    return x, y


def make_tiles(root: Path) -> Path:
    """z/x/y.png tiles around the training datum: 5 x 5 at every zoom of TILE_ZOOMS."""
    data = png_tile((40, 90, 140))
    for z in TILE_ZOOMS:
        cx, cy = tile_xy(TRAINING_DATUM.lat_deg, TRAINING_DATUM.lon_deg, z)
        for x in range(cx - 2, cx + 3):
            for y in range(cy - 2, cy + 3):
                path = root / str(z) / str(x) / f"{y}.png"
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_bytes(data)
    return root


@pytest.fixture
def console_env(request: pytest.FixtureRequest, tmp_path: Path) -> dict[str, str]:
    """This module's settings: ``{}``, a dict of ``NEMESYS_*`` (parametrize indirectly), or
    ``TILES`` for a tiles directory made in the test's tmp_path."""
    param: Any = getattr(request, "param", {})
    if param == TILES:
        return {"NEMESYS_TILES": str(make_tiles(tmp_path / "tiles"))}
    return dict(param)


# ---- helpers -----------------------------------------------------------------------------


class Network:
    """Every response and failed request of a page."""

    def __init__(self, page: Page) -> None:
        self.responses: list[tuple[str, int]] = []
        self.failed: list[str] = []
        page.on("response", self._response)
        page.on("requestfailed", lambda r: self.failed.append(f"{r.url} ({r.failure})"))

    def _response(self, r: Response) -> None:
        self.responses.append((r.url, r.status))

    def statuses(self, prefix: str) -> list[tuple[str, int]]:
        return [(u, s) for u, s in self.responses if urlsplit(u).path.startswith(prefix)]


def open_chart(
    w: Watched, console: Console, size: tuple[int, int] = (WIDTH, HEIGHT)
) -> tuple[Page, Network]:
    """The page at ``size`` (default 1280x800) with the operator token, once the chart is
    drawn."""
    page = w.page
    page.set_viewport_size({"width": size[0], "height": size[1]})
    w.stub_viewer()
    net = Network(page)
    page.goto(f"{console.base}/?token={TOKEN}")
    expect(page.get_by_test_id("chart-panel")).to_have_class(re.compile(r"\bchart-ready\b"))
    expect(page.locator("#chart.leaflet-container")).to_have_count(1)
    return page, net


def author(page: Page, pattern: str, params: dict[str, float]) -> dict[str, Any]:
    """Type a command into the form; returns the page's own preview of it (the oracle of
    what the chart must draw). The last parameter must differ from the form's default."""
    page.get_by_test_id("pattern-select").select_option(pattern)
    *first, (last, last_value) = params.items()
    for name, value in first:
        page.get_by_test_id(f"param-{name}").fill(str(value))

    def final(r: Response) -> bool:
        if urlsplit(r.url).path != "/api/preview" or r.request.method != "POST" or not r.ok:
            return False
        sent = json.loads(r.request.post_data or "{}")
        got = sent.get("params", {})
        return sent.get("pattern") == pattern and all(
            name in got and float(got[name]) == float(value) for name, value in params.items()
        )

    with page.expect_response(final) as info:
        page.get_by_test_id(f"param-{last}").fill(str(last_value))
    doc: dict[str, Any] = info.value.json()
    return doc


def minutes_value(match: re.Match[str]) -> float:
    deg, minutes, hemi = match.groups()
    value = int(deg) + float(minutes) / 60.0
    return -value if hemi in "SW" else value


def assert_loopback_only(w: Watched, net: Network, console: Console) -> None:
    outside = [
        url
        for _, url in w.requests
        if urlsplit(url).scheme not in ("data", "blob")
        and urlsplit(url).hostname not in ("127.0.0.1", "localhost")
    ]
    assert w.requests, "no request was recorded"
    assert not outside, f"requests that leave the machine: {outside}"
    vendor = net.statuses("/vendor/")
    assert {urlsplit(u).path for u, _ in vendor} >= {
        "/vendor/leaflet/leaflet-src.esm.js",
        "/vendor/leaflet/leaflet.css",
        "/vendor/uplot/uPlot.esm.js",
        "/vendor/uplot/uPlot.min.css",
    }, vendor
    bad = [(u, s) for u, s in vendor if s >= 400]
    assert not bad, f"/vendor requests that failed: {bad}"
    assert not [f for f in net.failed if "/vendor/" in f], net.failed


def assert_segments(page: Page, reach: dict[str, Any]) -> None:
    """One polyline per reach segment of the preview, in order, each with its class."""
    expected = [{"chart-preview", f"reach-{s['state']}"} for s in reach["segments"]]
    page.wait_for_function(
        "(n) => document.querySelectorAll('path.chart-preview').length === n",
        arg=len(expected),
        polling=POLL_MS,
    )
    classes = page.eval_on_selector_all(
        "path.chart-preview", "ns => ns.map(n => n.getAttribute('class'))"
    )
    assert [set(c.split()) - {"leaflet-interactive"} for c in classes] == expected, classes


def wait_attr_change(page: Page, selector: str, attr: str, before: str | None) -> str:
    handle = page.wait_for_function(
        "([sel, attr, before]) => { const n = document.querySelector(sel);"
        " const v = n && n.getAttribute(attr); return v && v !== before ? v : null; }",
        arg=[selector, attr, before],
        polling=POLL_MS,
        timeout=MOVE_MS,
    )
    value: str = handle.json_value()
    return value


# ---- tests -------------------------------------------------------------------------------


@pytest.mark.parametrize("size", list(SIZES))
def test_chart_draws_graticule_range_rings_and_preview_without_leaving_the_machine(
    console: Console, watched: Watched, size: str
) -> None:
    page, net = open_chart(watched, console, SIZES[size])
    chart = console.get("/api/chart")
    assert chart["datum"] == {
        "lat_deg": TRAINING_DATUM.lat_deg,
        "lon_deg": TRAINING_DATUM.lon_deg,
    }
    expect(page.get_by_test_id("chart-missing")).to_be_hidden()
    # the graticule: lines both ways, labelled in degrees and decimal minutes near the datum
    # (the chart opens on a wider view and fits the datum and the first preview: its labels
    # are waited for in whole degrees of the datum, not only for being there)
    page.wait_for_function(
        """([lat, lon]) => {
          const degrees = (cls) => [...document.querySelectorAll(cls)]
            .map((e) => Number((e.textContent.match(/^(\\d+)°/) || [])[1]));
          const la = degrees('.graticule-lat'), lo = degrees('.graticule-lon');
          return la.length >= 2 && lo.length >= 2
            && la.every((d) => d === lat) && lo.every((d) => d === lon);
        }""",
        arg=[int(abs(TRAINING_DATUM.lat_deg)), int(abs(TRAINING_DATUM.lon_deg))],
        polling=POLL_MS,
    )
    assert page.locator("path.graticule-line").count() >= 4
    lats = page.locator(".graticule-lat").all_text_contents()
    lons = page.locator(".graticule-lon").all_text_contents()
    for text in lats:
        m = LAT_LABEL.match(text)
        assert m, f"latitude label {text!r} is not dd°mm.mmm'N"
        assert abs(minutes_value(m) - TRAINING_DATUM.lat_deg) < 0.05, text
    for text in lons:
        m = LON_LABEL.match(text)
        assert m, f"longitude label {text!r} is not ddd°mm.mmm'W"
        assert abs(minutes_value(m) - TRAINING_DATUM.lon_deg) < 0.05, text
    # the transmitter's ME range ring and its 75 % ring; no attribution (it would link out)
    expect(page.locator("path.chart-range-ring")).to_have_count(1)
    expect(page.locator("path.chart-marginal-ring")).to_have_count(1)
    expect(page.locator(".chart-station")).to_have_count(1)
    expect(page.locator(".leaflet-control-attribution")).to_have_count(0)
    expect(page.get_by_test_id("chart-legend")).to_contain_text("marginal")
    # the page's first preview (the default pattern, well inside 730 m) is drawn, in range
    expect(page.locator("path.chart-preview.reach-in_range").first).to_be_attached()
    expect(page.locator("path.chart-preview.reach-out_of_range")).to_have_count(0)
    expect(page.get_by_test_id("reach-warning")).to_be_hidden()
    assert chart["me_range_m"] == 730.0
    # the graticule follows the view: zooming out changes the spacing and the labels
    before = lats
    page.locator(".leaflet-control-zoom-out").click()
    page.locator(".leaflet-control-zoom-out").click()
    page.wait_for_function(
        "(before) => JSON.stringify([...document.querySelectorAll('.graticule-lat')]"
        ".map(n => n.textContent)) !== JSON.stringify(before)",
        arg=before,
        polling=POLL_MS,
    )
    assert_loopback_only(watched, net, console)
    watched.assert_clean()


def test_preview_segments_carry_reach_classes_and_the_prediction_is_drawn(
    console: Console, watched: Watched
) -> None:
    page, net = open_chart(watched, console)
    preview = author(page, "straight", {"speed": 0.18, "depth": 3, "heading": 45, "duration": 90})
    reach = preview["link_reach"]
    assert reach["state"] == "in_range", reach
    assert preview["path"]["lat_deg"] and len(preview["path"]["lat_deg"]) == len(
        preview["path"]["x_m"]
    )
    assert_segments(page, reach)
    # the predicted track (dashed) and planned against predicted durations
    expect(page.locator("path.chart-predicted")).to_have_count(1, timeout=60_000)
    dash = page.eval_on_selector("path.chart-predicted", "n => n.getAttribute('stroke-dasharray')")
    assert dash, "the predicted track is not dashed"
    expect(page.get_by_test_id("prediction-planned")).to_have_text(re.compile(r"^\d+(\.\d)? s$"))
    expect(page.get_by_test_id("prediction-predicted")).to_have_text(re.compile(r"\d+ (s|min)"))
    expect(page.get_by_test_id("prediction-deviation")).to_have_text(re.compile(r"^\d+(\.\d)? m$"))
    planned = page.get_by_test_id("prediction-planned").text_content() or ""
    oracle = preview["estimate"]["planned_duration_s"]
    assert abs(float(planned.split()[0]) - oracle) <= 1.0, (planned, oracle)
    assert any(urlsplit(u).path == "/api/predict" and s == 200 for u, s in net.responses)
    assert_loopback_only(watched, net, console)
    watched.assert_clean()


def test_vehicle_marker_and_track_follow_telemetry_and_the_plots_fill(
    console: Console, watched: Watched
) -> None:
    page, net = open_chart(watched, console)
    marker = ".chart-vehicle"
    expect(page.locator(marker)).to_have_count(1)
    pose = console.get("/api/vehicle")["pose"]
    assert pose["lat_deg"] is not None, pose
    lon0 = wait_attr_change(page, marker, "data-lon", None)
    assert abs(float(lon0) - pose["lon_deg"]) < 1e-4, (lon0, pose)
    # the plots: three uPlot charts that get samples
    expect(page.locator("#plots .uplot canvas")).to_have_count(3)
    page.wait_for_function(
        "() => Number(document.getElementById('plots').dataset.points || 0) >= 2",
        polling=POLL_MS,
    )
    expect(page.get_by_test_id("plot-depth")).to_contain_text("commanded")
    # a command east, previewed in the page and sent: the active path is drawn (as
    # previewed), the marker moves east, turns to ~90 deg, and the track grows
    author(page, "straight", STRAIGHT_EAST)
    expect(page.locator("path.chart-active")).to_have_count(0)
    console.post("/api/commands", {"pattern": "straight", "params": STRAIGHT_EAST}, token=True)
    expect(page.locator("path.chart-active")).to_have_count(1, timeout=MOVE_MS)
    page.wait_for_function(
        "([sel, lon0]) => { const n = document.querySelector(sel);"
        " return n && Number(n.dataset.lon) > Number(lon0) + 2e-5; }",  # ~2 m east
        arg=[marker, lon0],
        polling=POLL_MS,
        timeout=MOVE_MS,
    )
    page.wait_for_function(
        "(sel) => Math.abs(Number(document.querySelector(sel).dataset.heading) - 90) < 10",
        arg=marker,
        polling=POLL_MS,
        timeout=MOVE_MS,
    )
    transform = page.eval_on_selector(f"{marker} svg", "n => n.style.transform")
    assert transform.startswith("rotate("), transform
    page.wait_for_function(
        "() => { const d = document.querySelector('path.chart-track')?.getAttribute('d') || '';"
        " return (d.match(/L/g) || []).length >= 2; }",
        polling=POLL_MS,
        timeout=MOVE_MS,
    )
    # centre on the vehicle
    page.get_by_test_id("chart-centre-vehicle").click()
    box = page.locator("#chart").bounding_box()
    icon = page.locator(marker).bounding_box()
    assert box and icon
    cx, cy = icon["x"] + icon["width"] / 2, icon["y"] + icon["height"] / 2
    assert abs(cx - (box["x"] + box["width"] / 2)) < box["width"] / 4
    assert abs(cy - (box["y"] + box["height"] / 2)) < box["height"] / 4
    # the commanded depth and the speed reach the plots: more samples keep coming
    points = int(page.get_by_test_id("plots").get_attribute("data-samples") or 0)
    page.wait_for_function(
        "(n) => Number(document.getElementById('plots').dataset.samples) > n + 2",
        arg=points,
        polling=POLL_MS,
        timeout=MOVE_MS,
    )
    assert_loopback_only(watched, net, console)
    watched.assert_clean()


@pytest.mark.parametrize("console_env", [TILES], indirect=True)
def test_local_tiles_are_requested_and_drawn(console: Console, watched: Watched) -> None:
    tiles = console.get("/api/chart")["tiles"]
    assert tiles is not None and tiles["url"] == "/api/tiles/{z}/{x}/{y}", tiles
    assert (tiles["min_zoom"], tiles["max_zoom"]) == (min(TILE_ZOOMS), max(TILE_ZOOMS))
    page, net = open_chart(watched, console)
    page.wait_for_function(
        "() => [...document.querySelectorAll('#chart img.leaflet-tile-loaded')]"
        ".some(i => i.naturalWidth === 256 && i.src.includes('/api/tiles/'))",
        polling=POLL_MS,
    )
    served = [(u, s) for u, s in net.statuses("/api/tiles/") if s == 200]
    assert served, net.statuses("/api/tiles/")
    # the tiles are below the graticule, which is still drawn
    assert page.locator("path.graticule-line").count() >= 4
    assert_loopback_only(watched, net, console)
    watched.assert_clean()


@pytest.mark.parametrize("console_env", [{"NEMESYS_ME_RANGE_M": "6"}], indirect=True)
def test_a_preview_leaving_range_is_shaded_and_warned(console: Console, watched: Watched) -> None:
    page, net = open_chart(watched, console)
    assert console.get("/api/chart")["me_range_m"] == 6.0
    params = {"speed": 0.18, "depth": 2, "heading": 0, "duration": 120}
    reach = author(page, "straight", params)["link_reach"]
    assert reach["state"] == "out_of_range" and reach["warning"], reach
    warning = page.get_by_test_id("reach-warning")
    expect(warning).to_be_visible()
    expect(warning).to_have_text(reach["warning"])
    assert {s["state"] for s in reach["segments"]} >= {"in_range", "out_of_range"}, reach
    assert_segments(page, reach)
    # the ring is 6 m across the transmitter: drawn, and smaller than the 75 % one's double
    expect(page.locator("path.chart-range-ring")).to_have_count(1)
    assert_loopback_only(watched, net, console)
    watched.assert_clean()


def test_without_the_npm_libraries_the_page_says_why_and_still_works(
    console: Console, watched: Watched
) -> None:
    """As after `make run` on a machine without npm: /vendor/ is not there."""
    page = watched.page
    page.set_viewport_size({"width": WIDTH, "height": HEIGHT})
    watched.stub_viewer()
    page.route(re.compile(r"^http://127\.0\.0\.1:\d+/vendor/"), lambda r: r.fulfill(status=404))
    page.goto(f"{console.base}/?token={TOKEN}")
    missing = page.get_by_test_id("chart-missing")
    expect(missing).to_be_visible()
    expect(missing).to_contain_text("chart unavailable")
    expect(missing).to_contain_text("npm ci --prefix frontend/vendor")
    expect(page.get_by_test_id("plots-missing")).to_contain_text("plots unavailable")
    # the rest of the page works: a preview is shown, and so is its prediction
    expect(page.get_by_test_id("frame-hex")).to_have_text(re.compile(r"^[0-9a-f]{25}$"))
    expect(page.get_by_test_id("prediction-planned")).to_be_visible(timeout=60_000)
    watched.assert_clean()
