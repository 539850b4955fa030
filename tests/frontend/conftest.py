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
import warnings
from collections.abc import Generator, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
import pytest
from playwright.sync_api import Browser, Page, Request, expect, sync_playwright
from playwright.sync_api import Error as PlaywrightError

from bench._gateway import FrameGateway
from bench._server import ConsoleProcess, start_console

REPO = Path(__file__).resolve().parents[2]
#: Screenshots of failed tests (artefacts, not committed: see .gitignore).
ARTIFACTS = REPO / "test-artifacts"
#: ``NEMESYS_TEST_SCREENSHOTS=all``: a screenshot of every test, passed or not. By default
#: only of a failed one: the full-page screenshot makes Chromium render the 3D view below the
#: fold (seconds of SwiftShader per test on a 2-core machine, a third of a passing test).
ALL_SCREENSHOTS = os.environ.get("NEMESYS_TEST_SCREENSHOTS") == "all"
#: Set on a test item whose setup or call failed.
FAILED = pytest.StashKey[bool]()
TOKEN = "frontend-test-token-0123456789abcdef"
#: Chromium flags that give WebGL through SwiftShader on a machine without a GPU.
CHROMIUM_ARGS = ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]
START_TIMEOUT_S = 20.0
#: How long an ``expect`` waits for its condition (ms), as long as the pages' actions may take
#: (``set_default_timeout(30_000)``): Playwright's own 5 s was exceeded on this shared 2-core
#: machine with a core kept busy (a retry's dialog waits for a fresh preview). A condition
#: met sooner ends the wait at once.
EXPECT_TIMEOUT_MS = 30_000
expect.set_options(timeout=EXPECT_TIMEOUT_MS)


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


@dataclass
class Console:
    """A running console (``server``) and a REST client of it."""

    server: ConsoleProcess
    http: httpx.Client

    @property
    def base(self) -> str:
        return self.server.base_url

    @property
    def port(self) -> int:
        return self.server.port

    def get(self, path: str, **params: str) -> Any:
        r = self.http.get(path, params=params)
        r.raise_for_status()
        return r.json()

    def post(self, path: str, body: Any, *, token: bool = False) -> Any:
        headers = {"Authorization": f"Bearer {TOKEN}"} if token else {}
        r = self.http.post(path, json=body, headers=headers)
        r.raise_for_status()
        return r.json()

    def put(self, path: str, body: Any) -> Any:
        """PUT with the operator token (the training controls)."""
        r = self.http.put(path, json=body, headers={"Authorization": f"Bearer {TOKEN}"})
        r.raise_for_status()
        return r.json()


@pytest.fixture
def console_env() -> dict[str, str]:
    """``NEMESYS_*`` settings added to the console's environment. A test changes them by
    parametrizing this name, e.g. ``@pytest.mark.parametrize("console_env",
    [{"NEMESYS_ACK_TIMEOUT_S": "1"}])`` (a shorter acknowledgement timeout) or
    ``{"NEMESYS_TARGET": "loop://"}`` (vehicle mode on a one-way modem link)."""
    return {}


@pytest.fixture
def console(tmp_path: Path, console_env: dict[str, str]) -> Iterator[Console]:
    """A fresh console per test (it starts in well under a second); stopped afterwards."""
    db = str(tmp_path / "log.sqlite3")
    with (
        start_console(
            tmp_path / "console.log",
            TOKEN,
            *("--db", db, "--time-scale", "10"),
            env=console_env,
            timeout_s=START_TIMEOUT_S,
        ) as server,
        server.client() as http,
    ):
        assert server.base_url == f"http://127.0.0.1:{server.port}", server.base_url
        yield Console(server, http)


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


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item,
) -> Generator[None, pytest.TestReport, pytest.TestReport]:
    """Remember a failed setup or call, for the screenshot at teardown."""
    report = yield
    if report.failed:
        item.stash[FAILED] = True
    return report


@pytest.fixture
def watched(browser: Browser, request: pytest.FixtureRequest) -> Iterator[Watched]:
    """A fresh page (own context, so no stored token) that records requests and page errors;
    a screenshot of it goes to test-artifacts/ when the test failed (or always: see
    :data:`ALL_SCREENSHOTS`), and the test fails on an uncaught page error."""
    # 1100 px wide: the page's one-column layout, where the 3D view starts below the fold.
    # Chromium then does not render it until the screenshot, which saves ~6 s of SwiftShader
    # start-up per test on a 2-CPU machine; its scene tree (what the tests check) still
    # follows every message. A full-page screenshot shows the rendered view.
    context = browser.new_context(viewport={"width": 1100, "height": 800})
    page = context.new_page()
    page.set_default_timeout(30_000)  # a loaded 2-core machine: conditions, not sleeps
    w = Watched(page)

    def on_request(r: Request) -> None:
        w.requests.append((r.method, r.url))

    page.on("request", on_request)
    page.on("pageerror", lambda err: w.errors.append(f"{err.name}: {err.message}"))
    try:
        yield w
    finally:
        name = re.sub(r"[^A-Za-z0-9_.-]+", "_", request.node.name)
        try:
            if ALL_SCREENSHOTS or request.node.stash.get(FAILED, False):
                ARTIFACTS.mkdir(exist_ok=True)
                # an artefact, best effort: a busy machine may not take it in time
                page.evaluate("() => window.scrollTo(0, 0)")  # the sticky header back on top
                page.screenshot(path=str(ARTIFACTS / f"{name}.png"), full_page=True, timeout=10_000)
        except PlaywrightError as err:
            warnings.warn(f"no screenshot of {name}: {err}", stacklevel=1)
        finally:
            context.close()
    # a page error after the test's own assert_clean() (e.g. while it was being closed)
    assert not w.errors, f"uncaught errors in the page: {w.errors}"


@pytest.fixture
def gateway() -> Iterator[FrameGateway]:
    """A loopback ME modem gateway that decodes every frame it is given (a one-way link)."""
    g = FrameGateway()
    try:
        yield g
    finally:
        g.close()
        assert not g.rejected, f"frames the gateway could not decode: {g.rejected}"
