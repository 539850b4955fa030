"""The link row's "Test link" button (frontend/link.js, POST /api/link/test; issue 21, item 7),
in Chromium, on a console in vehicle mode on a loopback TCP gateway double
(tests/station/gateways.py): the test checks the gateway and says so, sends not one byte, names
why when the gateway has gone (the indicator turns red), and passes again when it is back. A
page without the token cannot press it."""

from __future__ import annotations

import re
from collections.abc import Iterator

import pytest
from playwright.sync_api import expect

from tests.frontend.conftest import Console, Watched
from tests.frontend.pagekit import open_sized
from tests.station.gateways import Gateway


@pytest.fixture
def gateway() -> Iterator[Gateway]:
    g = Gateway("read")
    try:
        yield g
    finally:
        g.close()


@pytest.fixture
def console_env(gateway: Gateway) -> dict[str, str]:
    return {"NEMESYS_TARGET": gateway.target}


def test_test_link_checks_the_gateway_without_sending_a_frame(
    console: Console, watched: Watched, gateway: Gateway
) -> None:
    page = open_sized(watched, console)
    button = page.get_by_test_id("link-test")
    result = page.get_by_test_id("link-test-result")
    expect(button).to_be_enabled()
    expect(result).to_be_hidden()

    button.click()
    expect(result).to_have_text(f"link OK: modem {gateway.target} ok; no frame sent")
    gateway.wait_for("the console's connection", lambda: gateway.connections == 1)
    assert gateway.total() == 0

    gateway.stop()
    button.click()
    expect(result).to_contain_text(f"link FAILED: modem {gateway.target}: connection refused")
    expect(result).to_contain_text("; no frame sent")
    expect(result).to_have_class("error")
    expect(page.get_by_test_id("link-indicator")).to_have_class(re.compile(r"level-red"))

    gateway.restart()
    button.click()
    expect(result).to_have_text(f"link OK: modem {gateway.target} ok; no frame sent")
    expect(page.get_by_test_id("link-indicator")).to_have_class(re.compile(r"level-amber"))
    assert gateway.total() == 0  # no frame in all of it
    assert console.get("/api/vehicle")["link"]["frames"]["dive"]["frames"] == 0
    watched.assert_clean()


def test_a_page_without_the_token_cannot_test_the_link(
    console: Console, watched: Watched, gateway: Gateway
) -> None:
    page = open_sized(watched, console, token=False)
    expect(page.get_by_test_id("link-test")).to_be_disabled()
    assert not [u for m, u in watched.requests if m == "POST" and u.endswith("/api/link/test")]
    watched.assert_clean()
