"""The telemetry plots after a reload, in real Chromium: the dive so far comes from the mission
log (GET /api/series), on the dive's own clock (the axis starts at its start), with readable
value axes (several labelled ticks)."""

from __future__ import annotations

import json
from typing import Any

import pytest
from playwright.sync_api import Page

from tests.frontend.conftest import Console, Watched
from tests.frontend.pagekit import POLL_MS, open_sized

pytestmark = pytest.mark.browser

#: Samples of the dive in the log before the page opens (the simulator at time scale 10
#: writes about ten a second).
LOGGED = 30


def shown(page: Page) -> dict[str, Any]:
    """What the plots hold: ``t0`` (the vehicle's clock at the dive's start) and the samples
    (``t``: s since the dive's start, ``depth``, ``battery``, ``navLost``)."""
    got: dict[str, Any] = page.evaluate("() => document.getElementById('plots').samplesShown()")
    return got


def wait_logged(page: Page, at_least: int) -> None:
    page.wait_for_function(
        "(n) => Number(document.getElementById('plots').dataset.logged || 0) >= n"
        " && document.querySelector('#plots.plots-ready') !== null",
        arg=at_least,
        polling=POLL_MS,
    )


def ticks(page: Page, plot: str, axis: str) -> list[float]:
    text = page.get_by_test_id(plot).get_attribute(f"data-{axis}-ticks")
    assert text, f"{plot} has drawn no {axis} ticks"
    values: list[float] = json.loads(text)
    return values


def assert_from_the_dive_start(page: Page, series: dict[str, Any]) -> None:
    """The plots count from the dive's start and hold the logged samples, as logged."""
    got = shown(page)
    assert got["t0"] == series["start_t_s"]
    assert got["t"][0] == 0.0
    by_t = dict(
        zip(got["t"], zip(got["depth"], got["battery"], got["navLost"], strict=True), strict=True)
    )
    for t, depth, battery, nav_valid in zip(
        series["t_s"], series["depth_m"], series["battery_pct"], series["nav_valid"], strict=True
    ):
        # the nav-lost bar: at the surface line (0) where the navigation was not valid
        lost = 0 if nav_valid is False else None
        assert by_t.get(t) == (depth, battery, lost), f"the log's sample at {t} s"
    # the time axis starts at the dive's start; every value axis labels more than one tick
    assert ticks(page, "plot-depth", "x")[0] == 0
    for plot in ("plot-depth", "plot-battery", "plot-speed"):
        values = ticks(page, plot, "y")
        assert len(values) >= 3 and len(set(values)) == len(values), (plot, values)


def test_plots_after_a_reload_come_from_the_log_from_the_dive_start(
    console: Console, watched: Watched
) -> None:
    series = console.get("/api/series")
    while len(series["t_s"]) < LOGGED:  # the simulator logs its track: conditions, no sleeps
        series = console.get("/api/series")
    assert series["dive"] == 1 and series["t_s"][0] == 0.0
    page = open_sized(watched, console)
    wait_logged(page, LOGGED)
    # the log as it was when asked: what the page loaded holds it (the page asked later)
    assert_from_the_dive_start(page, series)
    before = shown(page)["t"][-1]

    page.reload()
    wait_logged(page, LOGGED)
    again = console.get("/api/series")
    # nothing before the reload is lost: every sample the log holds up to then is shown
    assert again["start_t_s"] == series["start_t_s"]
    upto = sum(1 for t in again["t_s"] if t <= before)
    assert upto >= len(series["t_s"]) and again["t_s"][upto - 1] >= before - 2.0
    assert_from_the_dive_start(
        page, {k: v[:upto] if isinstance(v, list) else v for k, v in again.items()}
    )
    watched.assert_clean()
