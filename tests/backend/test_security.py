"""The console's edges, unit by unit: allowed hosts, websocket origins, token redaction
(every form of it, a record's shape kept, and never a raise)."""

from __future__ import annotations

import io
import logging
import sys
from typing import Any

import pytest

from backend.security import (
    LOOPBACK_HOSTS,
    TokenRedactor,
    allowed_hosts,
    host_name,
    install_redaction,
    origin_allowed,
    redact,
    scrub,
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


def access_record(path: str) -> logging.LogRecord:
    """A record as uvicorn's access logger makes it: five arguments its formatter unpacks."""
    args = ("127.0.0.1:5000", "GET", path, "1.1", 200)
    msg = '%s - "%s %s HTTP/%s" %d'
    return logging.LogRecord("uvicorn.access", logging.INFO, __file__, 1, msg, args, None)


def test_a_scrubbed_access_record_keeps_its_arguments_for_uvicorns_formatter() -> None:
    from uvicorn.logging import AccessFormatter

    record = scrub(access_record(f"/api/session?token={SECRET}"), [SECRET])
    assert isinstance(record.args, tuple) and len(record.args) == 5  # was None: a TypeError
    line = AccessFormatter('%(client_addr)s - "%(request_line)s" %(status_code)s').format(record)
    assert line == '127.0.0.1:5000 - "GET /api/session?token=*** HTTP/1.1" 200 OK'


class _Loud:
    def __str__(self) -> str:
        return f"holder of {SECRET}"


class _Broken:
    def __str__(self) -> str:
        raise RuntimeError("no text")


@pytest.mark.parametrize(
    ("msg", "args", "shown"),
    [
        ("%s and %r", (SECRET, SECRET.encode()), "*** and b'***'"),
        ("%(who)s", ({"who": SECRET},), "***"),
        ("object %s", (_Loud(),), "object holder of ***"),
        ("token=%s", ("abc",), "token=***"),  # a token split between text and argument
        ("%s %s", (SECRET,), "log record withheld"),  # unformattable: withheld, not raised
        ("%s", (_Broken(),), "log record withheld"),
    ],
)
def test_scrub_never_raises_and_leaves_no_token(msg: str, args: Any, shown: str) -> None:
    record = logging.LogRecord("x", logging.DEBUG, __file__, 1, msg, args, None)
    assert shown in scrub(record, [SECRET]).getMessage()
    assert SECRET not in record.getMessage()


def test_an_exceptions_text_is_redacted_and_a_clean_one_kept() -> None:
    try:
        raise ValueError(f"bad input {SECRET!r}")
    except ValueError:
        dirty = logging.LogRecord("x", logging.ERROR, __file__, 1, "failed", (), sys.exc_info())
    scrub(dirty, [SECRET])
    assert dirty.exc_info is None and dirty.exc_text and "bad input '***'" in dirty.exc_text
    assert SECRET not in logging.Formatter().format(dirty)
    try:
        raise ValueError("nothing secret")
    except ValueError:
        clean = logging.LogRecord("x", logging.ERROR, __file__, 1, "failed", (), sys.exc_info())
    assert scrub(clean, [SECRET]).exc_info is not None  # any formatter still gets it


def test_installed_redaction_reaches_a_handler_added_later() -> None:
    """Records are scrubbed as they are made: a handler added after the console started (a
    test's, a debugger's) sees no token, at any level."""
    install_redaction([SECRET])
    stream = io.StringIO()
    handler = logging.StreamHandler(stream)
    logger = logging.getLogger("test.security.later")
    logger.addHandler(handler)
    logger.setLevel(logging.DEBUG)
    logger.propagate = False
    try:
        logger.debug("GET /api/commands/%s", SECRET)
        logger.debug("scope %s", {"headers": [(b"authorization", f"Bearer {SECRET}".encode())]})
    finally:
        logger.removeHandler(handler)
    assert SECRET not in stream.getvalue() and stream.getvalue().count("***") == 2
