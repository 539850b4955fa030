"""A 1280x800 screenshot of the whole console as a new operator sees it (docs, closing notes).

Starts a real ``nemesys console`` (training, time scale 10, the real 3D view), opens the page
in Debian's chromium with the operator token, authors a lawnmower, waits for its preview on
the chart (link-reach shading) and its predicted track, sends it through the confirm dialog,
waits for the acknowledgement, and saves ``test-artifacts/console_1280x800.png``.

    .venv/bin/python scripts/screenshot.py [out.png]
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from playwright.sync_api import sync_playwright

from bench._server import start_console

REPO = Path(__file__).resolve().parents[1]
TOKEN = "screenshot-token-0123456789abcdef"
ARGS = ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]


def main() -> int:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else REPO / "test-artifacts/console_1280x800.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        db = Path(tmp) / "log.sqlite3"
        env = {"NEMESYS_DB_PATH": str(db), "NEMESYS_SIM_TIME_SCALE": "10"}
        console = start_console(Path(tmp) / "console.log", TOKEN, env=env)
        try:
            with sync_playwright() as pw:
                browser = pw.chromium.launch(executable_path="/usr/bin/chromium", args=ARGS)
                page = browser.new_page(viewport={"width": 1280, "height": 800})
                page.set_default_timeout(60_000)
                page.goto(f"{console.base_url}/?token={TOKEN}")
                page.get_by_test_id("pattern-select").select_option("lawnmower")
                page.locator("#chart .reach-in_range").first.wait_for()
                page.locator("#chart .chart-predicted").first.wait_for()
                page.get_by_test_id("send-button").click()
                page.get_by_test_id("confirm-send").click()
                page.locator("[data-testid^=state-]", has_text="acknowledged").first.wait_for()
                page.wait_for_timeout(4000)  # the vehicle sets off; the 3D view renders
                page.screenshot(path=str(out))
                browser.close()
        finally:
            console.stop()
    print(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
