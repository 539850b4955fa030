"""The console's edges: which hosts and origins it answers, and tokens kept out of every log.

* **Host** (DNS rebinding): a request whose ``Host`` is neither a loopback name nor the bound
  address nor one configured in ``allowed_hosts`` is refused by :class:`HostGuard`: 400 with
  a JSON error naming the allowed names, or a refused websocket handshake (403). (Starlette's
  ``TrustedHostMiddleware`` does the same check but answers plain text without saying what
  is allowed, and mis-parses ``[::1]:8000``.)
* **Origin** (``/ws``): a browser's websocket is accepted only from the page's own origin or
  one configured in ``allowed_origins``; a client that sends no Origin (not a browser) is
  accepted, as the token still guards every control message.
* **Logs**: :class:`TokenRedactor` rewrites every record that passes a handler, at every
  level: the operator token itself, ``token=`` in query strings and ``Bearer`` credentials
  become ``***``.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterable
from typing import Final
from urllib.parse import urlsplit

from starlette.datastructures import Headers
from starlette.responses import JSONResponse
from starlette.types import ASGIApp, Receive, Scope, Send

#: Host names that always reach a console bound to loopback.
LOOPBACK_HOSTS: Final = ("localhost", "127.0.0.1", "::1", "[::1]")

_QUERY_TOKEN: Final = re.compile(r"(?i)(token=)[^&\s\"']+")
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
    """``text`` with tokens replaced by ``***``."""
    for secret in secrets:
        if secret:
            text = text.replace(secret, "***")
    text = _QUERY_TOKEN.sub(r"\1***", text)
    text = _BEARER.sub(r"\1***", text)
    return _HEADER_TOKEN.sub(r"\1***", text)


class TokenRedactor(logging.Filter):
    """Redacts tokens from every record (message and arguments, formatted once)."""

    def __init__(self, secrets: Iterable[str] = ()) -> None:
        super().__init__("nemesys-token-redactor")
        self.secrets = tuple(secrets)

    def filter(self, record: logging.LogRecord) -> bool:
        message = record.getMessage()
        clean = redact(message, self.secrets)
        if clean != message:
            record.msg, record.args = clean, None
        return True


def install_redaction(secrets: Iterable[str]) -> TokenRedactor:
    """Put a :class:`TokenRedactor` on every handler of the root logger and of every logger
    configured so far (uvicorn's among them), so no record reaches an output unredacted.
    Returns it; installing again replaces the earlier one's secrets."""
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
