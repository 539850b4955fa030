"""Pages at a chosen window size for the layout, theme and shortcut tests (the ``watched``
fixture of conftest.py is 1100 px wide, the page's one-column layout)."""

from __future__ import annotations

import re
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Literal

from playwright.sync_api import Browser, Page, expect
from playwright.sync_api import Error as PlaywrightError

from tests.frontend.conftest import ARTIFACTS, TOKEN, Console, Watched

POLL_MS = 100
#: The laptop and the desktop screen of issue 14.
SIZES = {"1280x800": (1280, 800), "1920x1080": (1920, 1080)}
PATTERNS = ("straight", "square", "lawnmower", "circle", "spiral", "helix", "hover", "box_orbit")


@contextmanager
def sized_page(
    browser: Browser,
    width: int,
    height: int,
    *,
    shot: str | None = None,
    scheme: Literal["dark", "light"] = "dark",
) -> Iterator[Watched]:
    """A fresh context (no stored token or theme) at ``width`` x ``height`` whose system
    colour scheme is ``scheme``; ``shot`` names a best-effort screenshot in test-artifacts/."""
    context = browser.new_context(viewport={"width": width, "height": height}, color_scheme=scheme)
    page = context.new_page()
    page.set_default_timeout(30_000)
    w = Watched(page)
    page.on("request", lambda r: w.requests.append((r.method, r.url)))
    page.on("pageerror", lambda err: w.errors.append(f"{err.name}: {err.message}"))
    try:
        yield w
        if shot:
            ARTIFACTS.mkdir(exist_ok=True)
            name = re.sub(r"[^A-Za-z0-9_.-]+", "_", shot)
            try:  # the viewport as the operator sees it, not the whole scrolled page
                page.screenshot(path=str(ARTIFACTS / f"{name}.png"), timeout=10_000)
            except PlaywrightError as err:
                warnings.warn(f"no screenshot {name}: {err}", stacklevel=1)
    finally:
        context.close()
    assert not w.errors, f"uncaught errors in the page: {w.errors}"


def open_sized(w: Watched, console: Console, *, token: bool = True) -> Page:
    """Load the page (the 3D view stubbed: see Watched.stub_viewer) and wait until the
    authoring form is built and the access state is known."""
    page = w.page
    w.stub_viewer()
    page.goto(f"{console.base}/?token={TOKEN}" if token else f"{console.base}/")
    page.wait_for_function(
        "() => document.querySelectorAll('#pattern-select option').length > 0"
        " && document.querySelector('#param-form [data-testid^=\"param-\"]') !== null",
        polling=POLL_MS,
    )
    expect(page.get_by_test_id("auth-state")).to_have_text(
        re.compile(r"^operator") if token else "read-only (observer)"
    )
    return page


def wait_preview(page: Page, pattern: str) -> None:
    """Pick ``pattern`` and wait until its preview is drawn: its frame's pattern section, the
    estimates' rows and the checks' verdict."""
    page.get_by_test_id("pattern-select").select_option(pattern)
    page.wait_for_function(
        "(pattern) => { const est = document.querySelector('#estimates');"
        " return est.dataset.pattern === pattern"
        " && est.querySelector('[data-key=duration]') !== null"
        " && document.querySelector('#violations li') !== null; }",
        arg=pattern,
        polling=POLL_MS,
    )
