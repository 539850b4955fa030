"""Bounded input: the request body cap, and 422 bodies that quote only an excerpt of the input.

:class:`BodyLimit` is pure ASGI (no ``BaseHTTPMiddleware``: nothing is buffered): a body whose
``Content-Length`` is over the cap is refused with 413 before the app runs, so before
authentication, parsing or reading a byte of it; a body without ``Content-Length`` (chunked)
is counted as the app reads it, and the moment the count passes the cap the 413 goes out and
the app sees the client disconnect (Starlette's ``Request.body`` raises ``ClientDisconnect``;
whatever the app answers after that is dropped). The 413 closes the connection: the rest of
an over-size body is never read.

:func:`validation_errors` replaces FastAPI's 422 handler: each error keeps ``loc``, ``msg``
and ``type``, with ``input`` cut to a short excerpt and no ``ctx`` or ``url``; a body the
JSON parser cannot read at all (not Unicode text, nested too deeply) is a 422 as well. Every
text of a 422 can be written (a lone surrogate is quoted as its escape: rendering it raised,
a 500) and holds no operator token (a client that put it in a path gets ``***`` back).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exception_handlers import http_exception_handler
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from backend.security import redact
from backend.strict_input import error_message, lone_surrogate, printable

#: Longest ``input`` echoed in a 422 (characters of its JSON text), and longest ``loc`` item.
EXCERPT_CHARS = 80
LOC_CHARS = 40
#: Longest ``msg`` in a 422: every message of ours is shorter; a longer one quotes input.
MSG_CHARS = 300


class BodyLimit:
    """Refuse request bodies over ``max_bytes`` with 413 ``{"detail": "request body over N
    bytes"}``: at once when ``Content-Length`` says so, else as soon as the bytes read pass
    the cap (at most one server read beyond it is ever held)."""

    def __init__(self, app: ASGIApp, max_bytes: int) -> None:
        self.app = app
        self.max_bytes = max_bytes
        self.body = json.dumps({"detail": f"request body over {max_bytes} bytes"}).encode()

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        length = content_length(scope)
        if length is not None and length > self.max_bytes:
            await self.reject(send)
            return
        await _Guard(self, receive, send).run(scope)

    async def reject(self, send: Send) -> None:
        await send(
            {
                "type": "http.response.start",
                "status": 413,
                "headers": [
                    (b"content-type", b"application/json"),
                    (b"content-length", str(len(self.body)).encode()),
                    (b"connection", b"close"),
                ],
            }
        )
        await send({"type": "http.response.body", "body": self.body})


class _Guard:
    """One request's byte count: ``receive`` and ``send`` as the app sees them."""

    def __init__(self, limit: BodyLimit, receive: Receive, send: Send) -> None:
        self.limit = limit
        self._receive = receive
        self._send = send
        self.received = 0
        self.started = False  # the app began its response
        self.over = False  # the cap was passed: the app reads a disconnect from now on
        self.rejected = False  # our 413 went out: the app's response is dropped

    async def run(self, scope: Scope) -> None:
        await self.limit.app(scope, self.receive, self.send)

    async def receive(self) -> Message:
        if self.over:
            return {"type": "http.disconnect"}
        message = await self._receive()
        if message["type"] == "http.request":
            self.received += len(message.get("body", b""))
            if self.received > self.limit.max_bytes:
                self.over = True
                if not self.started:
                    self.rejected = True
                    await self.limit.reject(self._send)
                return {"type": "http.disconnect"}
        return message

    async def send(self, message: Message) -> None:
        if self.rejected:
            return
        if message["type"] == "http.response.start":
            self.started = True
        await self._send(message)


def content_length(scope: Scope) -> int | None:
    """The request's ``Content-Length``, ``None`` when absent or not a number (the server
    refuses a malformed one before the app runs)."""
    for name, value in scope.get("headers", ()):
        if name == b"content-length":
            text = value.decode("latin-1").strip()
            return int(text) if text.isascii() and text.isdigit() else None
    return None


def excerpt(value: Any) -> Any:
    """``value`` when its JSON is short, else the start of its JSON text (``…`` at the cut);
    never NaN or infinity (JSON has neither: they become text)."""
    if value is None or isinstance(value, bool):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    if isinstance(value, int):
        if value.bit_length() <= 200:
            return value
        return f"<an integer of {value.bit_length()} bits>"
    if isinstance(value, str):
        value = printable(value)  # a lone surrogate cannot be written: its escape is
        return value if len(value) <= EXCERPT_CHARS else value[: EXCERPT_CHARS - 1] + "…"
    if isinstance(value, bytes | bytearray):  # a body FastAPI did not parse (not JSON): text
        return excerpt(bytes(value).decode("utf-8", errors="replace"))
    native = True
    try:
        try:
            text = json.dumps(value, ensure_ascii=False)
        except TypeError:  # something JSON has no form for (bytes inside): quoted as text
            native = False
            text = json.dumps(value, ensure_ascii=False, default=repr)
    except (TypeError, ValueError, RecursionError):  # a long integer, a deep structure
        return f"<{type(value).__name__}>"
    if lone_surrogate(text) is not None:
        native, text = False, printable(text)
    short = len(text) <= EXCERPT_CHARS
    if native and short and "NaN" not in text and "Infinity" not in text:
        return value
    return text if short else text[: EXCERPT_CHARS - 1] + "…"


def shorten(text: str, limit: int = MSG_CHARS) -> str:
    """``text`` cut to ``limit`` characters (``…`` at the cut)."""
    return text if len(text) <= limit else text[: limit - 1] + "…"


def short_error(error: dict[str, Any], secrets: Sequence[str] = ()) -> dict[str, Any]:
    """One validation error as the console answers it: ``loc``, ``msg``, ``type`` and an
    excerpt of ``input``; every text printable (a lone surrogate as its escape) and with
    ``secrets`` (the operator token: a client put it in a path, say) redacted."""

    def text(value: str, limit: int) -> str:
        return shorten(redact(printable(value), secrets), limit)

    loc = [text(i, LOC_CHARS) if isinstance(i, str) else i for i in error.get("loc", ())]
    msg = error_message(error)  # with the ASCII rule when a number's digits broke it
    if error.get("type") == "json_invalid":  # FastAPI puts the parser's reason in ctx
        reason = (error.get("ctx") or {}).get("error")
        if reason:
            msg = f"{msg}: {reason}"
    given = error.get("input")
    out: dict[str, Any] = {"loc": loc, "msg": text(msg, MSG_CHARS), "type": error.get("type")}
    if "input" in error:
        shown = excerpt(given)
        if isinstance(shown, list | dict):  # short JSON: its text, if that holds a token
            as_text = json.dumps(shown, ensure_ascii=False)
            shown = as_text if redact(as_text, secrets) != as_text else shown
        out["input"] = text(shown, EXCERPT_CHARS) if isinstance(shown, str) else shown
    return out


def body_parse_error(err: BaseException | None) -> dict[str, Any] | None:
    """The validation error of a JSON body the parser gave up on other than with a
    ``JSONDecodeError`` (which FastAPI answers 422 ``json_invalid`` itself), else ``None``:
    bytes that are not Unicode text (``UnicodeDecodeError``), or arrays and objects nested
    deeper than the parser goes (``RecursionError``). FastAPI answers those 400 "There was an
    error parsing the body", a status no operation documents; they are invalid input."""
    if isinstance(err, UnicodeDecodeError):
        msg = f"JSON decode error: the body is not Unicode text ({err.reason})"
        return {"loc": ["body", err.start], "msg": msg, "type": "json_invalid", "input": {}}
    if isinstance(err, RecursionError):
        msg = "JSON decode error: nested too deeply"
        return {"loc": ["body"], "msg": msg, "type": "json_invalid", "input": {}}
    return None


def validation_errors(app: FastAPI) -> None:
    """Install the 422 handler that never echoes more than an excerpt of the input, and
    answer a JSON body that cannot be parsed at all (:func:`body_parse_error`) with the same
    422 as malformed JSON instead of FastAPI's undocumented 400."""

    @app.exception_handler(RequestValidationError)
    async def request_validation(request: Request, err: RequestValidationError) -> JSONResponse:
        secrets = [request.app.state.settings.token]
        return JSONResponse(
            {"detail": [short_error(dict(e), secrets) for e in err.errors()]}, status_code=422
        )

    @app.exception_handler(StarletteHTTPException)
    async def http_error(request: Request, err: StarletteHTTPException) -> Response:
        error = body_parse_error(err.__cause__) if err.status_code == 400 else None
        if error is not None:
            return JSONResponse({"detail": [error]}, status_code=422)
        return await http_exception_handler(request, err)
