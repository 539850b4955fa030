"""The console's edges, unit by unit: allowed hosts, websocket origins, token redaction."""

from __future__ import annotations

import io
import logging

import pytest

from backend.security import (
    LOOPBACK_HOSTS,
    TokenRedactor,
    allowed_hosts,
    host_name,
    install_redaction,
    origin_allowed,
    redact,
)

SECRET = "k" * 24


def test_allowed_hosts_are_loopback_the_bound_address_and_the_configured() -> None:
    assert allowed_hosts("127.0.0.1") == list(LOOPBACK_HOSTS)
    assert "10.0.0.5" in allowed_hosts("10.0.0.5")
    assert "0.0.0.0" not in allowed_hosts("0.0.0.0")  # a wildcard bind is not a host name
    assert "console.ship" in allowed_hosts("0.0.0.0", ["console.ship"])
    assert "evil.example" not in allowed_hosts("127.0.0.1")


@pytest.mark.parametrize(
    ("origin", "host", "extra", "ok"),
    [
        (None, "127.0.0.1:8000", (), True),  # not a browser
        ("http://127.0.0.1:8000", "127.0.0.1:8000", (), True),
        ("http://localhost:8000", "localhost:8000", (), True),
        ("http://evil.example", "127.0.0.1:8000", (), False),
        ("http://127.0.0.1:9999", "127.0.0.1:8000", (), False),  # another port is another site
        ("null", "127.0.0.1:8000", (), False),
        ("http://chart.ship:3000", "127.0.0.1:8000", ("http://chart.ship:3000",), True),
    ],
)
def test_origin_rule(origin: str | None, host: str, extra: tuple[str, ...], ok: bool) -> None:
    assert origin_allowed(origin, host, extra) is ok


@pytest.mark.parametrize(
    "line",
    [
        f'127.0.0.1:5000 - "GET /?token={SECRET} HTTP/1.1" 200',
        f'"GET /static/app.js?v=1&token={SECRET}&x=2 HTTP/1.1"',
        f"Authorization: Bearer {SECRET}",
        f"[(b'authorization', b'Bearer {SECRET}'), (b'x-nemesys-token', b'{SECRET}')]",
        f"X-Nemesys-Token: {SECRET}",
        f"the token is {SECRET} itself",
    ],
)
def test_redact_removes_every_form_of_the_token(line: str) -> None:
    clean = redact(line, [SECRET])
    assert SECRET not in clean and "***" in clean


def test_redactor_on_a_handler_cleans_records_at_every_level() -> None:
    stream = io.StringIO()
    handler = logging.StreamHandler(stream)
    logger = logging.getLogger("test.security.redactor")
    logger.addHandler(handler)
    logger.setLevel(logging.DEBUG)
    logger.propagate = False
    try:
        install_redaction([SECRET])
        assert any(isinstance(f, TokenRedactor) for f in handler.filters)
        logger.debug("%s - %s", "GET", f"/?token={SECRET}")
        logger.info("headers %r", [(b"authorization", f"Bearer {SECRET}".encode())])
        logger.warning("raw %s", SECRET)
        install_redaction([SECRET])  # again: one redactor per handler, not two
        assert sum(isinstance(f, TokenRedactor) for f in handler.filters) == 1
    finally:
        logger.removeHandler(handler)
    text = stream.getvalue()
    assert SECRET not in text and text.count("***") >= 3


@pytest.mark.parametrize(
    ("header", "name"),
    [
        ("127.0.0.1:8000", "127.0.0.1"),
        ("[::1]:8000", "[::1]"),
        ("LocalHost", "localhost"),
        ("", ""),
    ],
)
def test_host_name_strips_the_port(header: str, name: str) -> None:
    assert host_name(header) == name
