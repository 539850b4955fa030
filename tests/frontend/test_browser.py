"""The operator page in real headless Chromium against a real console (training mode).

Each test opens the page of a fresh ``nemesys console`` and drives it only through the page's
``data-testid`` controls; the REST API is used as the oracle (what the backend encodes, which
commands it logged). The 3D view is checked through viser's scene tree inside its iframe.
Rendering is slow here (SwiftShader), so waits poll every 100 ms instead of per frame.
"""

from __future__ import annotations

import re
import time
from typing import Any
from urllib.parse import parse_qs, urlsplit

import pytest
from playwright.sync_api import Frame, Page, Route, expect

from tests.frontend.conftest import TOKEN, Console, Watched

POLL_MS = 100
LAWNMOWER = {"speed": 0.18, "depth": 3, "sweep_length": 20.3, "lane_spacing": 2, "laps": 2}
#: How long the vehicle may take to acknowledge (sim at time scale 10; ack timeout 5 s).
ACK_MS = 10_000


# ---- helpers -----------------------------------------------------------------------------


def open_page(w: Watched, console: Console, *, token: bool = True, viewer: bool = False) -> Page:
    """Load the page (with or without the operator token) and wait until it is built: the
    pattern picker is filled from the dictionary and the access state is known. The real 3D
    view is loaded only with ``viewer=True`` (see ``Watched.stub_viewer``)."""
    page = w.page
    if not viewer:
        w.stub_viewer()
    page.goto(f"{console.base}/?token={TOKEN}" if token else f"{console.base}/")
    page.wait_for_function(
        "() => document.querySelectorAll('#pattern-select option').length > 0"
        " && document.querySelector('#param-form [data-testid^=\"param-\"]') !== null",
        polling=POLL_MS,
    )
    operator = console.get("/api/session")["operator"]
    role = "operator" if operator == "operator" else f"operator ({operator})"
    expect(page.get_by_test_id("auth-state")).to_have_text(
        role if token else "read-only (observer)"
    )
    if token:  # the token left the address bar (it is kept in sessionStorage)
        assert "token" not in page.url
    return page


def author(page: Page, pattern: str, params: dict[str, Any]) -> None:
    """Pick a pattern and type its parameters into the authoring form."""
    page.get_by_test_id("pattern-select").select_option(pattern)
    for name, value in params.items():
        control = page.get_by_test_id(f"param-{name}")
        if isinstance(value, str):
            control.select_option(value)
        else:
            control.fill(f"{value:g}")


def wait_text(page: Page, testid: str, text: str, timeout_ms: int = 10_000) -> None:
    """Wait until the element's textContent is exactly ``text`` (polling, not per frame)."""
    page.wait_for_function(
        '([id, text]) => { const n = document.querySelector(`[data-testid="${id}"]`);'
        " return n !== null && n.textContent === text; }",
        arg=[testid, text],
        polling=POLL_MS,
        timeout=timeout_ms,
    )


def text_of(page: Page, testid: str) -> str:
    return page.get_by_test_id(testid).text_content() or ""


def viewer_frame(page: Page) -> Frame:
    handle = page.get_by_test_id("viewer").element_handle()
    frame = handle.content_frame()
    assert frame is not None, "the 3D view iframe has no document"
    return frame


def wait_scene_label(frame: Frame, name: str, *parts: str, timeout_ms: int = 20_000) -> str:
    """Wait until viser's scene tree (inside the viewer iframe) holds node ``name`` and, for a
    label, its text contains every one of ``parts``; return the text ('' for other nodes)."""
    frame.wait_for_function(
        "([name, parts]) => { const t = window.__viserSceneTree;"
        " const node = t && t.getState()[name];"
        " if (!node) return false;"
        " const text = (node.message.props && node.message.props.text) || '';"
        " return parts.every((p) => text.includes(p)); }",
        arg=[name, list(parts)],
        polling=POLL_MS,
        timeout=timeout_ms,
    )
    text: str = frame.evaluate(
        "(name) => window.__viserSceneTree.getState()[name].message.props.text || ''", name
    )
    return text


def render_viewer(page: Page, frame: Frame) -> None:
    """Scroll the 3D view into sight and wait for two of its frames to be drawn. The tests
    keep it below the fold (see the ``watched`` fixture), where Chromium does not render it."""
    page.get_by_test_id("viewer").scroll_into_view_if_needed()
    frame.evaluate(
        "() => new Promise((done) => requestAnimationFrame(() => requestAnimationFrame(done)))"
    )


def scene_names(frame: Frame, prefix: str) -> list[str]:
    names: list[str] = frame.evaluate(
        "(prefix) => Object.keys(window.__viserSceneTree.getState())"
        ".filter((k) => k.startsWith(prefix)).sort()",
        prefix,
    )
    return names


def commands(console: Console, **query: str) -> list[dict[str, Any]]:
    """GET /api/commands (newest first)."""
    rows: list[dict[str, Any]] = console.get("/api/commands", **query)
    return rows


def wait_command(console: Console, pattern: str, timeout_s: float = 15.0) -> dict[str, Any]:
    """The newest logged command of ``pattern``, once there is one."""
    deadline = time.monotonic() + timeout_s
    while True:
        rows = commands(console, pattern=pattern)
        if rows:
            return rows[0]
        assert time.monotonic() < deadline, f"no {pattern} command was logged"
        time.sleep(0.1)


def assert_acknowledged_row(page: Page, command_id: int) -> None:
    """The command's row in the command list reaches ``acknowledged`` and shows the vehicle's
    acknowledgement: bits corrected and the decode and replan latencies."""
    row = page.get_by_test_id("command-list").get_by_test_id(f"command-{command_id}")
    expect(row).to_be_visible()
    wait_text(page, f"state-{command_id}", "acknowledged", ACK_MS)
    detail = row.get_by_test_id(f"command-detail-{command_id}")
    expect(detail).to_have_text(
        re.compile(r"corrected 0 bits, .*decode [\d.]+ ms, replan [\d.]+ ms")
    )


# ---- the flows -------------------------------------------------------------------------------


def test_author_lawnmower_shows_bits_snaps_airtime_and_3d_preview(
    console: Console, watched: Watched
) -> None:
    page = open_page(watched, console, viewer=True)
    author(page, "lawnmower", LAWNMOWER)
    oracle = console.post("/api/encode", {"pattern": "lawnmower", "params": LAWNMOWER})
    bits: str = oracle["bits"]
    assert len(bits) == 100 and set(bits) <= {"0", "1"}

    # the frame: the same 100 bits and hex as the backend's encoder
    wait_text(page, "bits-strip", bits)
    strip = text_of(page, "bits-strip")
    assert len(strip) == 100 and set(strip) <= {"0", "1"}
    expect(page.get_by_test_id("frame-hex")).to_have_text(oracle["hex"])
    expect(page.get_by_test_id("airtime")).to_contain_text("2.778 ms")
    # the field sections are coloured separately: one span per field of the pattern
    expect(page.get_by_test_id("bits-sweep_length")).to_have_text(
        next(s["bits"] for s in oracle["sections"] if s["name"] == "sweep_length")
    )

    # 20.3 m does not fit the 8-bit scale: the form shows requested -> sent
    snap = next(s for s in oracle["snaps"] if s["field"] == "sweep_length")
    assert snap["changed"] and snap["sent"] != 20.3
    expect(page.get_by_test_id("snap-sweep_length")).to_be_visible()
    expect(page.get_by_test_id("snap-sweep_length")).to_have_text(f"20.3 m -> {snap['sent']:g} m")
    for exact in ("speed", "depth", "lane_spacing", "laps"):  # these are sent as typed
        expect(page.get_by_test_id(f"snap-{exact}")).to_be_hidden()

    # the preview drawn in the 3D view (viser, inside the iframe): the lawnmower at 3 m
    frame = viewer_frame(page)
    end = wait_scene_label(frame, "/preview/end", "lawnmower", "depth 3.0 m")
    assert end.startswith("preview: lawnmower end")
    assert "/preview/body" in scene_names(frame, "/preview/")
    render_viewer(page, frame)  # for the screenshot
    assert commands(console) == [], "authoring must not transmit anything"
    watched.assert_clean()


def test_send_lawnmower_is_acknowledged_and_the_vehicle_moves(
    console: Console, watched: Watched
) -> None:
    page = open_page(watched, console)
    author(page, "lawnmower", LAWNMOWER)
    oracle = console.post("/api/encode", {"pattern": "lawnmower", "params": LAWNMOWER})
    wait_text(page, "bits-strip", oracle["bits"])
    expect(page.get_by_test_id("status-pattern")).to_have_text("none")

    page.get_by_test_id("send-button").click()
    dialog = page.get_by_test_id("confirm-dialog")
    expect(dialog).to_be_visible()
    expect(page.locator("#confirm-title")).to_have_text("Send lawnmower?")
    expect(page.get_by_test_id("confirm-summary")).to_have_text("Active: none  ->  new: lawnmower")
    expect(page.get_by_test_id("confirm-changes")).to_contain_text("every parameter is new")
    expect(page.get_by_test_id("confirm-body")).to_contain_text(oracle["hex"])
    assert commands(console) == [], "nothing is sent before the operator confirms"

    page.get_by_test_id("confirm-send").click()
    expect(dialog).to_be_hidden()
    record = wait_command(console, "lawnmower")
    assert record["params"]["sweep_length"] == oracle["params"]["sweep_length"]
    assert record["bits"] == oracle["bits"]
    row = page.get_by_test_id(f"command-{record['id']}")
    expect(row).to_be_visible()
    expect(row).to_contain_text("lawnmower")
    assert_acknowledged_row(page, record["id"])

    # the vehicle flies it: the pattern is reported and the position keeps changing
    wait_text(page, "status-pattern", "lawnmower", ACK_MS)
    expect(page.get_by_test_id("status-mode")).to_have_text("running")
    before = text_of(page, "status-position")
    page.wait_for_function(
        "(before) => document.querySelector('[data-testid=\"status-position\"]').textContent"
        " !== before",
        arg=before,
        polling=POLL_MS,
        timeout=20_000,
    )
    expect(page.get_by_test_id("echo-active")).to_contain_text("lawnmower")
    expect(page.get_by_test_id("echo-mismatch")).to_be_hidden()
    watched.assert_clean()


def test_mission_script_with_two_commands_runs_to_completion(
    console: Console, watched: Watched
) -> None:
    page = open_page(watched, console)
    # step 1: a square at t = 0; step 2: a circle at t = 15 s (1.5 s of wall time at scale 10)
    author(page, "square", {"speed": 0.18, "depth": 2, "side_span": 4, "direction": "cw"})
    page.get_by_test_id("script-add").click()
    author(page, "circle", {"speed": 0.18, "depth": 3, "radius": 3, "direction": "ccw"})
    page.get_by_test_id("script-add").click()
    expect(page.locator("#script-steps > li")).to_have_count(2)
    expect(page.get_by_test_id("script-step-0-pattern")).to_have_value("square")
    expect(page.get_by_test_id("script-step-0-trigger")).to_have_value("at")
    expect(page.get_by_test_id("script-step-1-pattern")).to_have_value("circle")
    page.get_by_test_id("script-step-1-trigger").select_option("at")
    page.get_by_test_id("script-step-1-t").fill("15")

    # preview: the timeline of the two commands
    page.get_by_test_id("script-preview").click()
    timeline = page.locator("#script-timeline > li")
    # one entry per command sent (a circle repeats, so a note that one lap is shown follows)
    sends = timeline.filter(has_text=re.compile(r"starts \(|retasks the vehicle \("))
    expect(sends).to_have_count(2)
    expect(sends.nth(0)).to_have_text(
        "at 0 s from the run's start: square starts (at its set time)"
    )
    expect(sends.nth(1)).to_have_text(
        "at 15 s from the run's start: circle retasks the vehicle (at its set time)"
    )
    assert commands(console) == [], "a preview must not transmit anything"

    # run it in auto mode
    expect(page.get_by_test_id("script-step-mode")).not_to_be_checked()
    page.get_by_test_id("script-run").click()
    # the last step is a circle: it repeats, so the run leaves it running until retasked
    wait_text(
        page,
        "script-run-state",
        "every step sent: step 2 (circle) is running until retasked",
        20_000,
    )
    run = console.get("/api/scripts/run")
    assert run["outcome"] == "until_retasked" and not run["running"], run
    ids = [run["commands"][k] for k in sorted(run["commands"], key=int)]
    assert len(ids) == 2
    for command_id, pattern in zip(ids, ("square", "circle"), strict=True):
        row = page.get_by_test_id(f"command-{command_id}")
        expect(row).to_contain_text(pattern)
        expect(row).to_contain_text("[script]")
        assert_acknowledged_row(page, command_id)
    expect(page.locator("#script-run-steps > li.st-acknowledged")).to_have_count(2)
    expect(page.get_by_test_id("script-run")).to_be_enabled()
    expect(page.get_by_test_id("script-stop")).to_be_disabled()
    wait_text(page, "status-pattern", "circle", ACK_MS)
    watched.assert_clean()


def test_surface_button_is_acknowledged_and_the_banner_clears(
    console: Console, watched: Watched
) -> None:
    page = open_page(watched, console)
    banner = page.get_by_test_id("surface-state")
    expect(banner).to_be_hidden()
    page.get_by_test_id("surface-button").click()
    record = wait_command(console, "surface")
    assert record["kind"] == "surface"
    row = page.get_by_test_id("command-list").get_by_test_id(f"command-{record['id']}")
    expect(row).to_contain_text("SURFACE")
    wait_text(page, f"state-{record['id']}", "acknowledged", ACK_MS)
    expect(row.get_by_test_id(f"command-detail-{record['id']}")).to_contain_text("corrected 0")
    wait_text(page, "status-pattern", "surface", ACK_MS)
    expect(page.get_by_test_id("status-mode")).to_have_text(re.compile(r"^surfac(ing|ed)$"))
    # the "surfacing... repeating" banner is gone once the vehicle acknowledged
    page.wait_for_function(
        "() => { const b = document.querySelector('[data-testid=\"surface-state\"]');"
        " return b.hidden || !b.textContent.includes('surfacing'); }",
        polling=POLL_MS,
        timeout=20_000,
    )
    assert banner.is_hidden() or text_of(page, "surface-state") == "surface acknowledged"
    watched.assert_clean()


def test_without_token_the_page_is_read_only(console: Console, watched: Watched) -> None:
    page = open_page(watched, console, token=False)
    author(page, "circle", {"radius": 4})
    for testid in ("send-button", "surface-button", "script-run", "training-reset", "link-apply"):
        button = page.get_by_test_id(testid)
        expect(button).to_be_disabled()
        expect(button).to_have_attribute("title", "read-only: open the URL with the operator token")
    expect(page.get_by_test_id("token-form")).to_be_visible()
    # clicking anyway (a forced click, a script's click()) transmits nothing
    page.get_by_test_id("send-button").click(force=True)
    page.get_by_test_id("surface-button").click(force=True)
    page.evaluate(
        "() => { for (const id of ['send-button', 'surface-button'])"
        ' document.querySelector(`[data-testid="${id}"]`).click(); }'
    )
    expect(page.get_by_test_id("confirm-dialog")).to_be_hidden()
    page.wait_for_timeout(300)
    posts = [url for method, url in watched.requests if method != "GET"]
    # only the read-only calls (preview, and the prediction that follows it): nothing transmits
    read_only = {"/api/preview", "/api/predict"}
    assert all(urlsplit(u).path in read_only for u in posts), posts
    assert commands(console) == []
    assert console.get("/api/session")["authenticated"] is False
    watched.assert_clean()


def test_the_page_makes_no_external_requests(console: Console, watched: Watched) -> None:
    sockets: list[str] = []
    watched.page.on("websocket", lambda ws: sockets.append(ws.url))
    page = open_page(watched, console, viewer=True)
    # use it: author, preview, send, watch the acknowledgement
    author(page, "circle", {"speed": 0.18, "depth": 2, "radius": 4})
    page.get_by_test_id("send-button").click()
    page.get_by_test_id("confirm-send").click()
    record = wait_command(console, "circle")
    wait_text(page, f"state-{record['id']}", "acknowledged", ACK_MS)
    # the 3D view, scrolled into sight so that it renders (labels, fonts, textures) too
    frame = viewer_frame(page)
    wait_scene_label(frame, "/preview/end", "circle", "depth 2.0 m")
    render_viewer(page, frame)
    wait_scene_label(frame, "/vehicle/info", "depth")

    session = console.get("/api/session")
    viewer_ws = parse_qs(urlsplit(session["viewer_url"]).query)["websocket"][0]
    viewer_port = urlsplit(viewer_ws).port
    allowed = {("127.0.0.1", console.port), ("127.0.0.1", viewer_port)}
    assert watched.requests, "no request was recorded"
    assert sockets, "no websocket was recorded"
    outside = []
    urls = [url for _, url in watched.requests]
    for url in urls + sockets:
        parts = urlsplit(url)
        if parts.scheme in ("data", "blob"):
            continue
        if (parts.hostname, parts.port) not in allowed:
            outside.append(url)
    assert not outside, f"requests that leave the console: {outside}"
    # both servers were really used: the page's own API and viser's websocket
    assert any(urlsplit(u).path == "/viewer/" for u in urls)
    assert any(urlsplit(u).path == "/api/commands" for u in urls)
    # viser's websocket, on this page's own view (ws://host:port/view/<id>)
    own_view = rf"ws://127\.0\.0\.1:{viewer_port}/view/[0-9a-f]{{32}}"
    assert any(re.fullmatch(own_view, u) for u in sockets), sockets
    watched.assert_clean()


# ---- the vehicle link and the delivery states ----------------------------------------------

CIRCLE = {"speed": 0.18, "depth": 2, "radius": 4}
#: A shorter acknowledgement timeout, so that a frame lost on the emulated channel times out
#: in about a second of wall time.
SHORT_ACK = {"NEMESYS_ACK_TIMEOUT_S": "1"}
#: Vehicle mode on an ME modem link (pyserial's loop://): one-way, no telemetry.
ONE_WAY = {"NEMESYS_TARGET": "loop://"}
LEVEL = re.compile(r"\blevel-(green|amber|red)\b")


def send_from_page(
    page: Page, console: Console, pattern: str, params: dict[str, Any], copies: int | None = None
) -> int:
    """Author a command, send it through the confirm dialog, and return its new record's id."""
    before = {r["id"] for r in commands(console)}
    author(page, pattern, params)
    page.get_by_test_id("copies-input").fill("" if copies is None else str(copies))
    page.get_by_test_id("send-button").click()
    page.get_by_test_id("confirm-send").click()
    expect(page.get_by_test_id("confirm-dialog")).to_be_hidden()
    deadline = time.monotonic() + 5.0
    while True:
        new = [r["id"] for r in commands(console) if r["id"] not in before]
        if new:
            return int(max(new))
        assert time.monotonic() < deadline, f"no new {pattern} command was logged"
        time.sleep(0.1)


def header_labels(page: Page) -> list[str]:
    return [t.strip() for t in page.locator(".header-facts dt").all_text_contents()]


@pytest.mark.parametrize("console_env", [SHORT_ACK], ids=["ack-timeout-1s"])
def test_link_indicator_is_green_with_acks_and_turns_red_on_timeouts(
    console: Console, watched: Watched
) -> None:
    page = open_page(watched, console)
    # the page's websocket to the console is "console", not "link"
    assert "link" not in header_labels(page), header_labels(page)
    expect(page.get_by_test_id("conn-label")).to_have_text("console")
    expect(page.get_by_test_id("conn-state")).to_have_text("connected")

    indicator = page.get_by_test_id("link-indicator")
    expect(indicator).to_have_class(re.compile(r"\blevel-green\b"))
    expect(indicator).to_contain_text("acks")
    expect(indicator).to_have_attribute("title", re.compile(r"no problems"))
    link = console.get("/api/vehicle")["link"]
    assert link["capability"] == "acks_and_telemetry" and link["acknowledges"], link
    expect(page.get_by_test_id("status-link")).to_contain_text("acks + telemetry")
    surface = page.get_by_test_id("surface-button")
    expect(surface).to_have_attribute("title", re.compile("repeated until acknowledged"))

    # every frame is lost from now on: two commands time out
    console.put("/api/training/channel", {"loss": 1.0})
    for _ in range(2):
        command_id = send_from_page(page, console, "circle", CIRCLE)
        wait_text(page, f"state-{command_id}", "timed_out", 20_000)
        row = page.get_by_test_id(f"command-{command_id}")
        expect(row.get_by_test_id(f"command-detail-{command_id}")).to_contain_text(
            "no acknowledgement"
        )
        expect(row.get_by_test_id(f"retry-{command_id}")).to_be_enabled()

    expect(indicator).to_have_class(re.compile(r"\blevel-red\b"), timeout=30_000)
    expect(indicator).to_have_attribute("title", re.compile(r"timed out"))
    expect(indicator).to_contain_text("failing")  # in words too, not only in red
    expect(page.get_by_test_id("status-link")).to_contain_text("timed out")
    watched.assert_clean()


def test_reset_while_a_command_is_transmitted_shows_it_interrupted_and_retryable(
    console: Console, watched: Watched
) -> None:
    page = open_page(watched, console)
    console.put("/api/training/channel", {"loss": 1.0})  # no acknowledgement comes back
    command_id = send_from_page(page, console, "circle", CIRCLE)
    wait_text(page, f"state-{command_id}", "transmitted")
    page.get_by_test_id("training-reset").click()
    wait_text(page, f"state-{command_id}", "interrupted")
    record = console.get(f"/api/commands/{command_id}")
    assert record["state"] == "interrupted" and record["reason"], record
    row = page.get_by_test_id(f"command-{command_id}")
    expect(row).to_have_class(re.compile(r"\bst-interrupted\b"))
    expect(row.get_by_test_id(f"command-detail-{command_id}")).to_have_text(record["reason"])

    # retried on a working channel (through the confirm dialog: a new command, checked from
    # where the vehicle is now), it is acknowledged; the interrupted one stays interrupted
    console.put("/api/training/channel", {"loss": 0.0})
    before = {r["id"] for r in commands(console)}
    row.get_by_test_id(f"retry-{command_id}").click()
    expect(page.locator("#confirm-title")).to_have_text(
        f"Retry command {command_id} (circle) as a new command?"
    )
    page.get_by_test_id("confirm-send").click()
    expect(page.get_by_test_id("confirm-dialog")).to_be_hidden()
    deadline = time.monotonic() + ACK_MS / 1000
    while True:
        done = [r for r in commands(console) if r["state"] == "acknowledged"]
        if done:
            break
        assert time.monotonic() < deadline, commands(console)
        time.sleep(0.1)
    retried = done[0]
    assert retried["id"] not in before and retried["retry_of"] == command_id, retried
    assert console.get(f"/api/commands/{command_id}")["state"] == "interrupted"
    assert_acknowledged_row(page, retried["id"])
    watched.assert_clean()


def test_a_newer_command_supersedes_one_whose_copies_are_still_going_out(
    console: Console, watched: Watched
) -> None:
    page = open_page(watched, console)
    # no acknowledgement comes back: the console keeps sending the first command's copies
    console.put("/api/training/channel", {"loss": 1.0})
    first = send_from_page(page, console, "circle", CIRCLE, copies=20)
    wait_text(page, f"state-{first}", "transmitted")
    expect(page.get_by_test_id(f"copies-{first}")).to_have_text(re.compile(r"^\d+/20 copies$"))
    expect(page.get_by_test_id(f"command-detail-{first}")).to_contain_text(
        "waiting for acknowledgement"
    )

    second = send_from_page(page, console, "circle", {**CIRCLE, "radius": 5})
    wait_text(page, f"state-{first}", "superseded")
    record = console.get(f"/api/commands/{first}")
    assert record["superseded_by"] == second, record
    k = record["copies_sent"]
    row = page.get_by_test_id(f"command-{first}")
    expect(row).to_have_class(re.compile(r"\bst-superseded\b"))
    expect(row.get_by_test_id(f"command-detail-{first}")).to_have_text(
        f"superseded by #{second} after {k} of 20 copies"
    )
    expect(row.get_by_test_id(f"copies-{first}")).to_have_text(f"{k}/20 copies")
    expect(row.get_by_test_id(f"retry-{first}")).to_be_enabled()
    page.get_by_test_id("log-filter-state").select_option("superseded")
    expect(page.get_by_test_id(f"log-row-{first}")).to_contain_text(f"superseded by #{second}")
    expect(page.get_by_test_id(f"log-row-{second}")).to_be_hidden()
    watched.assert_clean()


@pytest.mark.parametrize("console_env", [ONE_WAY], ids=["loop-modem"])
def test_one_way_link_sends_copies_without_promising_acknowledgement(
    console: Console, watched: Watched
) -> None:
    page = open_page(watched, console)
    link = console.get("/api/vehicle")["link"]
    assert link["capability"] == "none" and not link["acknowledges"], link
    indicator = page.get_by_test_id("link-indicator")
    expect(indicator).to_have_class(LEVEL)
    expect(indicator).to_contain_text("one-way (no acks)")
    # a modem sends nothing back: no telemetry is not "no data yet", it is none to come
    expect(page.locator("#status-age")).to_have_text("none on this link (one-way)")
    assert indicator.get_attribute("title"), "the indicator's title lists problems or none"
    surface = page.get_by_test_id("surface-button")
    n_surface = link["surface_copies"]
    assert isinstance(n_surface, int) and n_surface >= 1, link
    n_text = f"{n_surface} cop{'y' if n_surface == 1 else 'ies'}"
    tip = f"as {n_text} (this link gives no acknowledgement)"
    expect(surface).to_have_attribute("title", re.compile(re.escape(tip)))
    assert "until acknowledged" not in (surface.get_attribute("title") or "")
    copies = page.get_by_test_id("copies-input")
    expect(copies).to_have_attribute("placeholder", f"auto ({link['copies']})")

    # an override outside 1-20 is refused in the page, before anything is sent
    author(page, "circle", CIRCLE)
    copies.fill("25")
    page.get_by_test_id("send-button").click()
    expect(page.get_by_test_id("confirm-copies")).to_contain_text("from 1 to 20")
    page.get_by_test_id("confirm-send").click()
    expect(page.get_by_test_id("confirm-error")).to_contain_text("copies")
    page.get_by_test_id("confirm-cancel").click()
    assert commands(console) == []

    # three copies, chosen by the operator: all go out, nothing more can be known
    author(page, "circle", CIRCLE)
    copies.fill("3")
    page.get_by_test_id("send-button").click()
    expect(page.get_by_test_id("confirm-copies")).to_contain_text("copies: 3 (set by you")
    expect(page.get_by_test_id("confirm-copies")).to_contain_text("no acknowledgement")
    page.get_by_test_id("confirm-send").click()
    command_id = wait_command(console, "circle")["id"]
    wait_text(page, f"state-{command_id}", "sent")
    record = console.get(f"/api/commands/{command_id}")
    assert record["copies"] == 3 and record["copies_sent"] == 3 and not record["two_way"], record
    sent = re.compile(
        r"^sent 3 copies, p\(delivered\) (> )?[\d.]+ % at BER [\de.+-]+ "
        r"\(no acknowledgement on this link\)$"
    )
    expect(page.get_by_test_id(f"command-detail-{command_id}")).to_have_text(sent)
    expect(page.get_by_test_id(f"command-{command_id}")).to_have_class(re.compile(r"\bst-sent\b"))

    # SURFACE: a number of copies, not "repeating until acknowledged"
    surface.click()
    surface_id = wait_command(console, "surface")["id"]
    wait_text(page, f"state-{surface_id}", "sent")
    banner = page.get_by_test_id("surface-state")
    expect(banner).to_have_text(re.compile(rf"^surface sent: {n_text}, p\(delivered\) "))
    assert "until acknowledged" not in (banner.text_content() or "")

    # the mission log filters on the new state
    page.get_by_test_id("log-filter-state").select_option("sent")
    expect(page.get_by_test_id(f"log-row-{command_id}")).to_contain_text("sent 3 copies")
    expect(page.get_by_test_id(f"log-row-{surface_id}")).to_be_visible()
    watched.assert_clean()


# ---- the link assumptions form -------------------------------------------------------------


def link_puts(w: Watched) -> int:
    """How many PUT /api/link the page has made."""
    return sum(1 for m, u in w.requests if m == "PUT" and urlsplit(u).path == "/api/link")


def requests_settled(page: Page) -> None:
    """Wait for one request of the page's own to come back: the page's request events are
    delivered in order, so every request the page made before this one has been recorded."""
    status = page.evaluate("() => fetch('/api/session').then((r) => r.status)")
    assert status == 200, status


@pytest.mark.parametrize("console_env", [ONE_WAY], ids=["loop-modem"])
def test_link_assumptions_set_ber_and_target_and_refuse_out_of_range_values(
    console: Console, watched: Watched
) -> None:
    page = open_page(watched, console)
    assert console.get("/api/session")["mode"] != "training"
    before = console.get("/api/vehicle")["link"]
    ber = page.get_by_test_id("link-ber-input")
    target = page.get_by_test_id("delivery-target-input")
    apply = page.get_by_test_id("link-apply")
    result = page.get_by_test_id("link-apply-result")
    expect(ber).to_be_enabled()
    expect(page.get_by_test_id("link-ber-note")).to_be_hidden()
    expect(ber).not_to_have_attribute("placeholder", "")  # the assumed BER now
    assert float(ber.get_attribute("placeholder") or "nan") == before["ber"], before
    expect(target).to_have_attribute("placeholder", "0.999")
    expect(apply).to_be_enabled()
    expect(result).to_be_hidden()

    ber.fill("0.02")
    target.fill("0.9999")
    apply.click()
    expect(result).to_contain_text("copies per command now: 6")
    link = console.get("/api/vehicle")["link"]
    assert link["ber"] == 0.02 and link["copies"] == 6, link
    surface = link["surface_copies"]
    assert isinstance(surface, int), link  # one-way: a number of copies, not "until acked"
    expect(result).to_have_text(f"copies per command now: 6 (surface: {surface})")
    assert link_puts(watched) == 1
    expect(target).to_have_attribute("placeholder", "0.9999")  # the target set
    # the rest of the page follows the new link at once
    expect(page.get_by_test_id("copies-input")).to_have_attribute("placeholder", "auto (6)")
    expect(page.get_by_test_id("status-link")).to_contain_text("6 copies per command")

    # out of range: refused in the page, naming the field and the interval; nothing is sent
    ber.fill("0.7")
    apply.click()
    error = page.get_by_test_id("link-ber-error")
    expect(error).to_be_visible()
    expect(error).to_contain_text("link_ber")
    expect(error).to_contain_text("[0, 0.5)")
    expect(error).to_contain_text("0.7")  # the value typed, not a clamped one
    expect(ber).to_have_attribute("aria-invalid", "true")
    expect(ber).to_have_value("0.7")  # never clamped
    ber.fill("0.01")  # a valid BER beside an invalid target: still nothing is sent
    expect(error).to_be_hidden()
    target.fill("1")
    apply.click()
    target_error = page.get_by_test_id("delivery-target-error")
    expect(target_error).to_contain_text("delivery_target")
    expect(target_error).to_contain_text("(0, 1)")
    requests_settled(page)
    assert link_puts(watched) == 1, watched.requests
    assert console.get("/api/vehicle")["link"]["ber"] == 0.02
    watched.assert_clean()


def test_link_assumptions_in_training_leave_the_ber_to_the_channel(
    console: Console, watched: Watched
) -> None:
    page = open_page(watched, console)
    assert console.get("/api/session")["mode"] == "training"
    ber = page.get_by_test_id("link-ber-input")
    expect(ber).to_be_disabled()
    # closed in training (the channel sets the BER), one click opens it
    details = page.get_by_test_id("link-details")
    expect(details).not_to_have_attribute("open", "")
    details.locator("summary").click()
    expect(page.get_by_test_id("link-ber-note")).to_be_visible()
    expect(page.get_by_test_id("link-ber-note")).to_have_text("training: set by the channel")

    # the delivery target works in training too; acknowledged SURFACEs repeat until acked
    page.get_by_test_id("delivery-target-input").fill("0.99")
    page.get_by_test_id("link-apply").click()
    result = page.get_by_test_id("link-apply-result")
    link = console.get("/api/vehicle")["link"]
    expect(result).to_have_text(
        f"copies per command now: {link['copies']} (surface: until acknowledged)"
    )
    assert link["surface_copies"] is None, link

    # a page that believes it is on a real vehicle sends link_ber anyway: the backend's 409
    # is shown next to the field
    def as_vehicle(route: Route) -> None:
        response = route.fetch()
        route.fulfill(response=response, json={**response.json(), "mode": "vehicle"})

    page.route(re.compile(r"/api/session$"), as_vehicle)
    page.reload()
    expect(page.get_by_test_id("mode-badge")).to_have_text("VEHICLE")
    expect(ber).to_be_enabled()
    expect(page.get_by_test_id("link-apply")).to_be_enabled()
    ber.fill("0.01")
    page.get_by_test_id("link-apply").click()
    error = page.get_by_test_id("link-ber-error")
    expect(error).to_contain_text("in training the copies follow the emulated channel's BER")
    expect(result).to_have_text("not applied")
    assert console.get("/api/vehicle")["link"]["ber"] != 0.01
    watched.assert_clean()


def test_the_echo_check_last_sent_follows_the_newest_command(
    console: Console, watched: Watched
) -> None:
    """After a Surface, then a hover, "last sent" says hover, and nothing puts the older
    Surface back: not its repeats, not a poll of the vehicle, not a reload."""
    page = open_page(watched, console)
    surface = console.post("/api/surface", None, token=True)
    wait_command(console, "surface")
    hover = console.post(
        "/api/commands",
        {"pattern": "hover", "params": {"duration": 60, "depth": 2, "heading": 90}},
        token=True,
    )
    expect(page.get_by_test_id("echo-sent")).to_contain_text("hover", timeout=30_000)
    record = console.get(f"/api/commands/{surface['id']}")
    assert record["state"] in ("acknowledged", "superseded"), record
    page.wait_for_timeout(2500)  # longer than a Surface repeat: a check for absence
    expect(page.get_by_test_id("echo-sent")).to_contain_text("hover")
    assert console.get("/api/vehicle")["last_sent"]["id"] == hover["id"]
    page.reload()
    expect(page.get_by_test_id("echo-sent")).to_contain_text("hover", timeout=30_000)
    watched.assert_clean()


def test_a_rejection_says_its_reason_once(console: Console, watched: Watched) -> None:
    page = open_page(watched, console)
    body = {
        "pattern": "circle",
        "params": {"speed": 1.5, "depth": 3, "radius": 5, "direction": "cw"},
        "override": True,
    }
    sent = console.post("/api/commands", body, token=True)
    wait_text(page, f"state-{sent['id']}", "rejected", ACK_MS)
    record = console.get(f"/api/commands/{sent['id']}")
    detail = record["ack"]["detail"]
    assert detail and record["reason"].endswith(detail)
    row = page.get_by_test_id(f"command-detail-{sent['id']}")
    expect(row).to_contain_text(detail)
    assert row.inner_text().count(detail) == 1, row.inner_text()
    watched.assert_clean()


def test_toasts_stack_three_at_most_and_information_fades(
    console: Console, watched: Watched
) -> None:
    page = open_page(watched, console)
    body = {
        "pattern": "circle",
        "params": {"speed": 1.5, "depth": 3, "radius": 5, "direction": "cw"},
        "override": True,
    }
    ids = [console.post("/api/commands", body, token=True)["id"] for _ in range(4)]
    for command_id in ids:  # four rejections: four warnings
        wait_text(page, f"state-{command_id}", "rejected", ACK_MS)
    messages = page.get_by_test_id("messages").get_by_test_id("message")
    expect(messages.first).to_contain_text("rejected")
    assert messages.count() <= 3
    expect(messages).to_have_count(0, timeout=30_000)  # they fade; the rows keep the reasons
    expect(page.get_by_test_id(f"command-detail-{ids[-1]}")).to_contain_text("speed")
    watched.assert_clean()
