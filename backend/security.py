"""The console's edges: which hosts and origins it answers, and tokens kept out of every log.

* **Host** (DNS rebinding): a request whose ``Host`` is neither a loopback name nor the bound
  address nor one configured in ``allowed_hosts`` is refused by :class:`HostGuard`: 400 with
  a JSON error naming the allowed names, or a refused websocket handshake (403). (Starlette's
  ``TrustedHostMiddleware`` does the same check but answers plain text without saying what
  is allowed, and mis-parses ``[::1]:8000``.)
* **Origin** (``/ws``): a browser's websocket is accepted only from the page's own origin or
  one configured in ``allowed_origins``; a client that sends no Origin (not a browser) is
  accepted, as the token still guards every control message.
* **Logs**: :func:`install_redaction` scrubs every log record at every level as it is made
  (and again at every handler): the operator token itself (in a path segment, a validation
  error's dump, anywhere), ``token=`` in query strings, ``"token": "..."`` in dumps,
  ``Bearer`` credentials and ``X-Nemesys-Token`` headers become ``***``; the record keeps
  its shape, so no formatter fails on it, and checking it never raises.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable, Iterable, Mapping
from typing import Any, Final
from urllib.parse import quote, urlsplit

from starlette.datastructures import Headers
from starlette.responses import JSONResponse
from starlette.types import ASGIApp, Receive, Scope, Send

#: Host names that always reach a console bound to loopback.
LOOPBACK_HOSTS: Final = ("localhost", "127.0.0.1", "::1", "[::1]")

_QUERY_TOKEN: Final = re.compile(r"(?i)(token=)[^&\s\"']+")
_KEY_TOKEN: Final = re.compile(r"""(?i)(["']token["']\s*:\s*b?["'])[^"']+""")
_BEARER: Final = re.compile(r"(?i)(bearer\s+)[^\s\"',]+")
_HEADER_TOKEN: Final = re.compile(
    r"(?i)(x-nemesys-token['\"]?\s*[:,=]\s*['\"]?b?['\"]?)[^\s\"',)]+"
)


def allowed_hosts(bound_host: str, extra: Iterable[str] = ()) -> list[str]:
    """Host names the console answers: loopback names, the bound address (unless it is a
    wildcard) and the configured ones."""
    hosts = [*LOOPBACK_HOSTS, *extra]
    if bound_host not in ("0.0.0.0", "::", ""):
        hosts.append(bound_host)
    return list(dict.fromkeys(hosts))


def host_name(host_header: str) -> str:
    """The name in a Host header, without its port (``[::1]:8000`` -> ``[::1]``)."""
    host = host_header.strip().lower()
    if host.startswith("["):
        return host[: host.find("]") + 1] if "]" in host else host
    return host.split(":", 1)[0]


class HostGuard:
    """ASGI middleware: only requests naming one of ``allowed`` hosts reach the app."""

    def __init__(self, app: ASGIApp, allowed: Iterable[str]) -> None:
        self.app = app
        self.allowed = frozenset(name.lower() for name in allowed)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        host = Headers(scope=scope).get("host", "")
        if host_name(host) in self.allowed:
            await self.app(scope, receive, send)
            return
        if scope["type"] == "websocket":
            await send({"type": "websocket.close", "code": 1008})
            return
        detail = (
            f"Host {host[:60]!r} is not this console's (DNS rebinding guard); allowed: "
            f"{', '.join(sorted(self.allowed))} (setting allowed_hosts adds names)"
        )
        await JSONResponse({"detail": detail}, status_code=400)(scope, receive, send)


def origin_allowed(origin: str | None, host: str | None, extra: Iterable[str] = ()) -> bool:
    """Whether a websocket from ``origin`` may connect to a console reached as ``host``
    (the request's Host header). No Origin: not a browser, allowed."""
    if origin is None:
        return True
    if origin in extra:
        return True
    parts = urlsplit(origin)
    return parts.scheme in ("http", "https") and host is not None and parts.netloc == host


def redact(text: str, secrets: Iterable[str] = ()) -> str:
    """``text`` with tokens replaced by ``***``: each of ``secrets`` (and its URL-quoted
    form) anywhere, and whatever follows ``token=``, ``"token": "``, ``Bearer`` or an
    ``X-Nemesys-Token`` header name."""
    for secret in secrets:
        if secret:
            text = text.replace(secret, "***")
            quoted = quote(secret, safe="")
            if quoted != secret:
                text = text.replace(quoted, "***")
    text = _QUERY_TOKEN.sub(r"\1***", text)
    text = _KEY_TOKEN.sub(r"\1***", text)
    text = _BEARER.sub(r"\1***", text)
    return _HEADER_TOKEN.sub(r"\1***", text)


class _Shown(str):
    """An argument of a log call whose text held a token: its text redacted, and its
    ``repr`` (what ``%r`` shows) redacted apart, so the record keeps its shape."""

    __slots__ = ("shown",)
    shown: str

    def __new__(cls, text: str, shown: str) -> _Shown:
        self = super().__new__(cls, text)
        self.shown = shown
        return self

    def __repr__(self) -> str:
        return self.shown


#: What a record says when it could not be checked (it is never let through unchecked).
WITHHELD = "log record withheld: it could not be checked for the operator token ({})"


def scrub(record: logging.LogRecord, secrets: Iterable[str] = ()) -> logging.LogRecord:
    """Make ``record`` safe to write anywhere, in place: no token in its message, its
    arguments, its exception or its stack text. Never raises.

    The arguments keep their number and order (uvicorn's access formatter unpacks them: a
    record whose ``args`` became ``None`` made every access line a logging error whose dump
    held the token): each one whose text holds a token is replaced by its redacted text. An
    exception's traceback holding a token is formatted here, redacted, and kept as
    ``exc_text`` (what formatters print) with ``exc_info`` dropped. A record that cannot be
    checked (its message cannot be formatted, an argument's ``str`` raises) is withheld: its
    message says so, nothing of the original is kept."""
    try:
        _scrub(record, tuple(secrets))
    except Exception as err:  # never raise from logging; never let an unchecked record out
        record.msg, record.args = WITHHELD.format(type(err).__name__), None
        record.exc_info = record.exc_text = record.stack_info = None
    return record


def _scrub(record: logging.LogRecord, secrets: tuple[str, ...]) -> None:
    message = record.getMessage()
    if redact(message, secrets) != message:
        args = record.args
        if isinstance(args, Mapping):
            record.args = {key: _clean_arg(value, secrets) for key, value in args.items()}
        elif isinstance(args, tuple):
            record.args = tuple(_clean_arg(value, secrets) for value in args)
        again = record.getMessage()
        if redact(again, secrets) != again:  # the token spans the text and an argument
            record.msg, record.args = redact(message, secrets), None
    if record.exc_info and not record.exc_text:
        trace = logging.Formatter().formatException(record.exc_info)
        if redact(trace, secrets) != trace:  # else the exception stays, for any formatter
            record.exc_text, record.exc_info = redact(trace, secrets), None
    elif record.exc_text:
        record.exc_text = redact(record.exc_text, secrets)
    if record.stack_info:
        record.stack_info = redact(record.stack_info, secrets)


def _clean_arg(value: object, secrets: tuple[str, ...]) -> object:
    if isinstance(value, str):
        return redact(value, secrets)
    if value is None or isinstance(value, int | float):
        return value  # what %d and %f need; a number holds no token
    text, shown = str(value), repr(value)
    clean_text, clean_shown = redact(text, secrets), redact(shown, secrets)
    if clean_text == text and clean_shown == shown:
        return value
    return _Shown(clean_text, clean_shown)


class TokenRedactor(logging.Filter):
    """Redacts tokens from every record that passes it (:func:`scrub`); never raises and
    never drops a record."""

    def __init__(self, secrets: Iterable[str] = ()) -> None:
        super().__init__("nemesys-token-redactor")
        self.secrets = tuple(secrets)

    def filter(self, record: logging.LogRecord) -> bool:
        scrub(record, self.secrets)
        return True


class _Secrets:
    """Every token :func:`install_redaction` was given in this process: redacted from every
    record made from then on (a token of a console that stopped stays secret). A tuple
    replaced whole, never changed in place: a record made on another thread meanwhile reads
    the old one or the new one."""

    known: tuple[str, ...] = ()


def _scrubbed_factory(make: Callable[..., logging.LogRecord]) -> Callable[..., logging.LogRecord]:
    def factory(*args: Any, **kwargs: Any) -> logging.LogRecord:
        return scrub(make(*args, **kwargs), _Secrets.known)

    factory.scrubs = True  # type: ignore[attr-defined]
    return factory


def install_redaction(secrets: Iterable[str]) -> TokenRedactor:
    """Keep ``secrets`` out of every log line at every level: every record is scrubbed as it
    is made (a log record factory, so a handler added later, a test's among them, sees no
    token either), and a :class:`TokenRedactor` is put on every handler of the root logger
    and of every logger configured so far (uvicorn's among them), for records made another
    way. Returns the redactor; installing again replaces the earlier one's secrets on the
    handlers."""
    secrets = tuple(s for s in secrets if s)
    _Secrets.known = tuple(dict.fromkeys((*_Secrets.known, *secrets)))
    current = logging.getLogRecordFactory()
    if not getattr(current, "scrubs", False):
        logging.setLogRecordFactory(_scrubbed_factory(current))
    redactor = TokenRedactor(secrets)
    loggers = [logging.getLogger()]
    loggers += [
        logger
        for logger in logging.Logger.manager.loggerDict.values()
        if isinstance(logger, logging.Logger)
    ]
    for logger in loggers:
        for handler in logger.handlers:
            for old in [f for f in handler.filters if isinstance(f, TokenRedactor)]:
                handler.removeFilter(old)
            handler.addFilter(redactor)
    return redactor
