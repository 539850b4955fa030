"""A console restart with a page open (issue 19, item 6): the token is kept beside the mission
log, so the page still operates after a restart; after a restart with ``--new-token`` the
page says it is read-only as soon as it reconnects, without anything being pressed, and says
what to do. The console is a real ``nemesys console`` without ``NEMESYS_TOKEN``, restarted on
the same port and mission log."""

from __future__ import annotations

import re
import time
from pathlib import Path

from playwright.sync_api import Browser, expect

from bench._server import ConsoleProcess, start_console
from tests.frontend.conftest import START_TIMEOUT_S
from tests.frontend.pagekit import POLL_MS, sized_page

#: Time for the page to notice the console went and came back (its reconnect backoff).
RECONNECT_MS = 30_000


def start(tmp_path: Path, n: int, db: Path, *extra: str, port: int | None = None) -> ConsoleProcess:
    """``nemesys console`` number ``n`` on ``db`` (and ``port``): the token it keeps."""
    return start_console(
        tmp_path / f"console-{n}.log",
        None,
        *("--db", str(db), "--time-scale", "10", *extra),
        timeout_s=START_TIMEOUT_S,
        port=port,
    )


def surfaces(console: ConsoleProcess) -> int:
    with console.client() as http:
        records = http.get("/api/commands").json()
    return sum(1 for r in records if r.get("pattern") == "surface")


def test_a_page_keeps_operating_across_restarts_and_says_read_only_at_once_on_a_new_token(
    tmp_path: Path, browser: Browser
) -> None:
    db = tmp_path / "log.sqlite3"
    consoles = [start(tmp_path, 0, db)]
    try:
        port, token = consoles[0].port, consoles[0].token
        with sized_page(browser, 1280, 800) as w:
            page = w.page
            w.stub_viewer()
            page.goto(f"{consoles[0].base_url}/?token={token}")
            auth = page.get_by_test_id("auth-state")
            conn = page.get_by_test_id("conn-state")
            notice = page.get_by_test_id("auth-notice")
            expect(auth).to_have_text(re.compile(r"^operator"))
            expect(conn).to_have_text("connected")

            # restart, same token (kept beside the log): the page still operates
            consoles[0].stop()
            expect(conn).not_to_have_text("connected", timeout=RECONNECT_MS)
            consoles.append(start(tmp_path, 1, db, port=port))
            assert consoles[1].token == token
            expect(conn).to_have_text("connected", timeout=RECONNECT_MS)
            page.keyboard.press("Control+Shift+S")  # the page's token, on the new console
            deadline = time.monotonic() + 15.0
            while surfaces(consoles[1]) < 1:
                assert time.monotonic() < deadline, "no SURFACE after the restart"
                page.wait_for_timeout(POLL_MS)
            expect(auth).to_have_text(re.compile(r"^operator"))
            expect(notice).to_be_hidden()
            expect(page.get_by_test_id("surface-button")).to_be_enabled()

            # restart with --new-token: read-only on reconnecting, before anything is pressed
            consoles[1].stop()
            expect(conn).not_to_have_text("connected", timeout=RECONNECT_MS)
            consoles.append(start(tmp_path, 2, db, "--new-token", port=port))
            assert consoles[2].token != token
            expect(auth).to_have_text("token refused: read-only", timeout=RECONNECT_MS)
            expect(notice).to_be_visible()
            expect(notice).to_contain_text("refuses this page's operator token")
            expect(notice).to_contain_text("open the URL with the new token")
            expect(notice).to_contain_text(f"{consoles[2].base_url}/?token=")
            expect(page.get_by_test_id("surface-button")).to_be_disabled()
            expect(page.get_by_test_id("send-button")).to_be_disabled()
            expect(page.get_by_test_id("token-form")).to_be_visible()
            pressed = [r for r in w.requests if r[1].endswith("/api/surface")]
            assert pressed == [("POST", f"{consoles[0].base_url}/api/surface")], pressed

            # what the notice says to do works: the new token, operator again
            page.get_by_test_id("token-input").fill(consoles[2].token)
            page.get_by_test_id("token-save").click()
            expect(auth).to_have_text(re.compile(r"^operator"))
            expect(notice).to_be_hidden()
            expect(page.get_by_test_id("surface-button")).to_be_enabled()
    finally:
        for console in consoles:
            console.stop()
