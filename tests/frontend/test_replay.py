"""The replay's time slider in real Chromium: as it moves, the page shows where the vehicle was,
the command it was running and the link events then, and the vehicle marker moves in the
page's own 3D view (viser's scene tree inside the iframe). The console's REST API is the
oracle (the dive's timeline, the vehicle at a time)."""

from __future__ import annotations

import math
import re
import time
from typing import Any

import pytest
from playwright.sync_api import Frame, Page, expect

from tests.frontend.conftest import Console, Watched
from tests.frontend.test_browser import POLL_MS, open_page, viewer_frame

pytestmark = pytest.mark.browser

CIRCLE = {"speed": 0.18, "depth": 3, "radius": 4, "direction": "cw"}
SQUARE = {"speed": 0.18, "depth": 2, "side_span": 6, "direction": "cw"}
#: Samples of the dive with each command running before the page replays it.
SAMPLES = 6
LOAD_MS = 60_000
POSITION = re.compile(r"^x (-?[\d.]+) m north, y (-?[\d.]+) m east, depth (-?[\d.]+) m")


def send(console: Console, pattern: str, params: dict[str, Any]) -> int:
    record = console.post("/api/commands", {"pattern": pattern, "params": params}, token=True)
    return int(record["id"])


def running(console: Console, command_id: int, at_least: int) -> list[float]:
    """Wait until the dive's timeline has ``at_least`` samples of ``command_id`` running;
    their times (s since the dive's start)."""
    deadline = time.monotonic() + 60.0
    while True:
        samples = console.get("/api/dives/1/timeline")["samples"]
        times = [s["t_s"] for s in samples if s["command_id"] == command_id]
        if len(times) >= at_least:
            return times
        assert time.monotonic() < deadline, f"command {command_id} never ran {at_least} s"
        time.sleep(0.2)


def vehicle_at(console: Console, t_s: float) -> dict[str, Any]:
    """The oracle: the vehicle at ``t_s`` (no view header: nothing drawn)."""
    r = console.http.put("/api/replay/at", json={"dive": 1, "t_s": t_s})
    r.raise_for_status()
    position: dict[str, Any] = r.json()["position"]
    return position


def marker(frame: Frame) -> list[float] | None:
    """The 3D view's replay marker (view frame: east, north, up), or None."""
    got: list[float] | None = frame.evaluate(
        "() => { const n = window.__viserSceneTree.getState()['/replay_at/vehicle'];"
        " if (!n) return null; const p = n.message.props.points;"
        " return Array.from(new Float32Array(p.buffer, p.byteOffset, 3)); }"
    )
    return got


def slide_to(page: Page, t_s: int) -> None:
    page.get_by_test_id("replay-slider").fill(str(t_s))
    expect(page.get_by_test_id("replay-bar")).to_have_attribute("data-t", str(t_s))


def assert_shows(page: Page, frame: Frame, expected: dict[str, Any], pattern: str) -> None:
    """The page's readouts and the 3D marker show the oracle's vehicle and command."""
    found = POSITION.match(page.get_by_test_id("replay-position").text_content() or "")
    assert found, page.get_by_test_id("replay-position").text_content()
    shown = [float(v) for v in found.groups()]
    want = [expected["x_m"], expected["y_m"], expected["z_m"]]
    assert shown == pytest.approx(want, abs=0.051), (shown, want)
    cid = str(expected["command_id"])
    expect(page.get_by_test_id("replay-bar")).to_have_attribute("data-command-id", cid)
    expect(page.get_by_test_id("replay-command")).to_contain_text(f"command {cid} {pattern}")
    view = [expected["y_m"], expected["x_m"], -expected["z_m"]]
    frame.wait_for_function(
        "(want) => { const n = window.__viserSceneTree.getState()['/replay_at/vehicle'];"
        " if (!n) return false; const p = n.message.props.points;"
        " const f = new Float32Array(p.buffer, p.byteOffset, 3);"
        " return want.every((v, i) => Math.abs(f[i] - v) < 0.01); }",
        arg=view,
        polling=POLL_MS,
        timeout=LOAD_MS,
    )


def test_the_replay_slider_shows_the_vehicle_its_command_and_the_link_over_time(
    console: Console, watched: Watched
) -> None:
    circle = send(console, "circle", CIRCLE)
    circle_times = running(console, circle, SAMPLES)
    square = send(console, "square", SQUARE)
    square_times = running(console, square, SAMPLES)
    timeline = console.get("/api/dives/1/timeline")

    watched.page.set_default_timeout(LOAD_MS)
    page = open_page(watched, console, viewer=True)
    frame = viewer_frame(page)
    page.get_by_test_id("replay-1").click()
    bar = page.get_by_test_id("replay-bar")
    expect(bar).to_be_visible()
    expect(page.get_by_test_id("replay-title")).to_have_text("dive 1")
    slider = page.get_by_test_id("replay-slider")
    assert float(slider.get_attribute("max") or 0) >= timeline["duration_s"]

    # into the circle, then into the square: the position and the command follow
    t_circle = math.ceil(circle_times[len(circle_times) // 2])
    slide_to(page, t_circle)
    assert_shows(page, frame, vehicle_at(console, t_circle), "circle")
    t_square = math.ceil(square_times[len(square_times) // 2])
    slide_to(page, t_square)
    assert_shows(page, frame, vehicle_at(console, t_square), "square")
    assert marker(frame) is not None

    # just after the square's first copy left: that event is listed, seconds before
    sent = next(e for e in timeline["events"] if e["kind"] == "sent" and e["command_id"] == square)
    t_sent = math.ceil(sent["t_s"]) + 1
    slide_to(page, t_sent)
    events = page.get_by_test_id("replay-events")
    expect(events.locator("li[data-kind=sent]").first).to_contain_text(f"command {square} square")

    # Clear replay: the slider goes with the replayed dive
    page.get_by_test_id("clear-replay").click()
    expect(bar).to_be_hidden()
    frame.wait_for_function(
        "() => !window.__viserSceneTree.getState()['/replay_at/vehicle']", polling=POLL_MS
    )
    watched.assert_clean()
