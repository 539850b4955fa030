"""Fixtures of the browser tests: a real ``nemesys console`` subprocess (training mode, time
scale 10) and Debian's chromium driven by Playwright's sync API.

The browser is Debian's ``chromium`` (``.ci/run`` installs it); Playwright's own browser
download is never used. Without chromium these tests fail, they do not skip.
``NEMESYS_CHROMIUM`` names another binary.
"""

from __future__ import annotations

import os
import re
import shutil
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
import pytest
from playwright.sync_api import Browser, Page, Request, sync_playwright

REPO = Path(__file__).resolve().parents[2]
#: Screenshots of every test (artefacts, not committed: see .gitignore).
ARTIFACTS = REPO / "test-artifacts"
TOKEN = "frontend-test-token-0123456789abcdef"
#: Chromium flags that give WebGL through SwiftShader on a machine without a GPU.
CHROMIUM_ARGS = ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]
START_TIMEOUT_S = 20.0


def chromium_path() -> str:
    """The chromium binary, or a test failure saying how to get one."""
    chosen = os.environ.get("NEMESYS_CHROMIUM")
    candidates = [chosen] if chosen else ["/usr/bin/chromium", shutil.which("chromium")]
    for path in candidates:
        if path and os.path.isfile(path) and os.access(path, os.X_OK):
            return path
    where = f"NEMESYS_CHROMIUM={chosen}" if chosen else "/usr/bin/chromium and PATH"
    pytest.fail(
        f"chromium not found (looked at {where}): the "
        "browser tests need Debian's chromium; install it with `apt-get install chromium` "
        "(.ci/run does) or point NEMESYS_CHROMIUM at a Chromium binary. "
        "Do not run `playwright install`.",
        pytrace=False,
    )


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


@dataclass
class Console:
    """A running console: its base URL, the operator URL and a REST client."""

    proc: subprocess.Popen[bytes]
    port: int
    base: str
    operator_url: str
    log: Path
    http: httpx.Client = field(init=False)

    def __post_init__(self) -> None:
        self.http = httpx.Client(base_url=self.base, timeout=10.0)

    def get(self, path: str, **params: str) -> Any:
        r = self.http.get(path, params=params)
        r.raise_for_status()
        return r.json()

    def post(self, path: str, body: Any, *, token: bool = False) -> Any:
        headers = {"Authorization": f"Bearer {TOKEN}"} if token else {}
        r = self.http.post(path, json=body, headers=headers)
        r.raise_for_status()
        return r.json()

    def output(self) -> str:
        return self.log.read_text(errors="replace")


def _start(tmp_path: Path) -> Console:
    port = free_port()
    log = tmp_path / "console.log"
    # only our settings: none of the caller's NEMESYS_* variables (operator name, settings file)
    env = {k: v for k, v in os.environ.items() if not k.startswith("NEMESYS_")}
    env["NEMESYS_TOKEN"] = TOKEN
    cmd = [
        sys.executable,
        "-m",
        "backend.cli",
        "console",
        "--port",
        str(port),
        "--viewer-port",
        "0",
        "--db",
        str(tmp_path / "log.sqlite3"),
        "--time-scale",
        "10",
    ]
    with log.open("wb") as out:
        proc = subprocess.Popen(cmd, cwd=REPO, env=env, stdout=out, stderr=subprocess.STDOUT)
    deadline = time.monotonic() + START_TIMEOUT_S
    url = None
    try:
        while time.monotonic() < deadline:
            if proc.poll() is not None:
                raise RuntimeError(f"the console exited ({proc.returncode}):\n{log.read_text()}")
            m = re.search(r"http://\S+/\?token=\S+", log.read_text(errors="replace"))
            if m:
                url = m.group(0)
                break
            time.sleep(0.05)
        if url is None:
            raise RuntimeError(f"the console printed no URL:\n{log.read_text()}")
        base = url.split("/?", 1)[0]
        assert base == f"http://127.0.0.1:{port}", url
        console = Console(proc, port, base, url, log)
        while time.monotonic() < deadline:
            if proc.poll() is not None:
                raise RuntimeError(f"the console exited ({proc.returncode}):\n{log.read_text()}")
            try:
                if console.http.get("/api/session").status_code == 200:
                    return console
            except httpx.TransportError:
                pass
            time.sleep(0.05)
        raise RuntimeError(f"GET /api/session never answered:\n{log.read_text()}")
    except BaseException:
        _stop(proc)
        raise


def _stop(proc: subprocess.Popen[bytes]) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)


@pytest.fixture
def console(tmp_path: Path) -> Iterator[Console]:
    """A fresh console per test (it starts in well under a second); stopped afterwards."""
    c = _start(tmp_path)
    try:
        yield c
    finally:
        c.http.close()
        _stop(c.proc)


@pytest.fixture(scope="module")
def browser() -> Iterator[Browser]:
    """One headless chromium per test module."""
    path = chromium_path()
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=path, headless=True, args=CHROMIUM_ARGS)
        try:
            yield b
        finally:
            b.close()


@dataclass
class Watched:
    """A page with every request it made and every uncaught error it raised."""

    page: Page
    #: (method, url) of every request of the page and its iframes, in order.
    requests: list[tuple[str, str]] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)

    def assert_clean(self) -> None:
        """No uncaught error in the page, and no error message shown to the operator (the
        page turns unhandled promise rejections into such messages instead of page errors)."""
        assert not self.errors, f"uncaught errors in the page: {self.errors}"
        shown = self.page.locator("[data-testid=message].message-error").all_text_contents()
        assert not shown, f"error messages shown in the page: {shown}"

    def stub_viewer(self) -> None:
        """Serve a placeholder instead of the 3D view (before the page is opened).

        For tests that do not look at the 3D view: loading viser's client (an 800 KB bundle,
        WebGL through SwiftShader) takes seconds of the page's main thread on a 2-CPU machine
        and slows every click while it runs. The tests that check the 3D view and the
        network audit load the real one.
        """
        self.page.route(
            re.compile(r"^http://127\.0\.0\.1:\d+/viewer/"),
            lambda route: route.fulfill(
                status=200,
                content_type="text/html",
                body="<!doctype html><title>3D view</title><body style='background:#111820;"
                "color:#9aa;font:14px sans-serif'>3D view not loaded in this test</body>",
            ),
        )


@pytest.fixture
def watched(browser: Browser, request: pytest.FixtureRequest) -> Iterator[Watched]:
    """A fresh page (own context, so no stored token) that records requests and page errors;
    a screenshot of it goes to test-artifacts/ whatever the outcome, and the test fails on an
    uncaught page error."""
    # 1100 px wide: the page's one-column layout, where the 3D view starts below the fold.
    # Chromium then does not render it until the screenshot, which saves ~6 s of SwiftShader
    # start-up per test on a 2-CPU machine; its scene tree (what the tests check) still
    # follows every message. The full-page screenshot shows the rendered view.
    context = browser.new_context(viewport={"width": 1100, "height": 800})
    page = context.new_page()
    page.set_default_timeout(15_000)
    w = Watched(page)

    def on_request(r: Request) -> None:
        w.requests.append((r.method, r.url))

    page.on("request", on_request)
    page.on("pageerror", lambda err: w.errors.append(f"{err.name}: {err.message}"))
    try:
        yield w
    finally:
        ARTIFACTS.mkdir(exist_ok=True)
        name = re.sub(r"[^A-Za-z0-9_.-]+", "_", request.node.name)
        try:
            page.evaluate("() => window.scrollTo(0, 0)")  # the sticky header back on top
            page.screenshot(path=str(ARTIFACTS / f"{name}.png"), full_page=True)
        finally:
            context.close()
    # a page error after the test's own assert_clean() (e.g. while it was being closed)
    assert not w.errors, f"uncaught errors in the page: {w.errors}"
