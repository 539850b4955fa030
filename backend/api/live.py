"""The live websocket: telemetry and command states out; authenticated control in. Every
message is a model of :mod:`backend.api.schemas.live` (``docs/live.md``)."""

from __future__ import annotations

import asyncio
import contextlib
import json
from typing import Any

from fastapi import APIRouter, WebSocket, WebSocketDisconnect, status
from pydantic import ValidationError

from backend.api.deps import token_ok
from backend.api.schemas.common import LimitViolation
from backend.api.schemas.live import (
    CLIENT_MESSAGE,
    CLIENT_TYPES,
    AuthMessage,
    AuthOk,
    AuthRefused,
    ErrorReply,
    Queued,
    SurfaceMessage,
)
from backend.bounded_input import shorten
from backend.commands.manager import RateLimited
from backend.commands.service import SendRefused, SendRequest, VehicleRefused
from backend.console import Console
from backend.messages import message_json
from backend.mission_log.store import LogWriteError
from backend.security import origin_allowed
from backend.strict_input import lone_surrogate_in
from codec import CodecError
from planner import PlanError

router = APIRouter(tags=["live"])

#: Largest control message accepted (bytes); uvicorn's own limit (``ws_max_size``) must be
#: larger, so that an over-size message gets this error reply rather than a closed socket.
MAX_CONTROL_BYTES = 4096
#: Deepest nesting of arrays and objects in a control message (checked before parsing).
MAX_CONTROL_DEPTH = 32

#: The answer to a control message.
Reply = AuthOk | AuthRefused | Queued | ErrorReply


def nesting_over(text: str, limit: int) -> bool:
    """Whether the JSON ``text`` nests arrays and objects deeper than ``limit``: a scan of
    the brackets outside strings, without parsing (no recursion, whatever the input)."""
    depth = 0
    in_string = escaped = False
    for char in text:
        if in_string:
            if escaped:
                escaped = False
            elif char == "\\":
                escaped = True
            elif char == '"':
                in_string = False
        elif char == '"':
            in_string = True
        elif char in "[{":
            depth += 1
            if depth > limit:
                return True
        elif char in "]}":
            depth -= 1
    return False


class _NotANumber(ValueError):
    """``NaN``, ``Infinity`` or ``-Infinity``, which Python's JSON parser would accept."""


def _no_constant(name: str) -> Any:
    raise _NotANumber(f"{name} is not a JSON number")


@router.websocket("/ws")
async def live(websocket: WebSocket) -> None:
    """Server -> client: ``telemetry`` (10 Hz, latest wins), ``command``, ``vehicle``,
    ``active_path``, ``link`` and ``event`` news, and the answers to the page's own messages.
    Client -> server: ``auth`` (answered ``auth_ok`` or ``auth_refused``) then ``surface`` or
    ``send`` (answered ``queued`` or ``error``); control without the token is refused (the
    connection stays, read-only). Every message: ``docs/live.md``. A browser page from
    another origin is refused at the handshake (403)."""
    console: Console = websocket.app.state.console
    headers = websocket.headers
    allowed = console.settings.allowed_origins
    if not origin_allowed(headers.get("origin"), headers.get("host"), allowed):
        await websocket.close(code=status.WS_1008_POLICY_VIOLATION)
        return
    await websocket.accept()
    pump = asyncio.create_task(console.hub.serve(websocket))
    authed = False
    try:
        while True:
            message = await websocket.receive()
            if message["type"] == "websocket.disconnect":
                break
            text = message.get("text")
            if text is None:
                reply: Reply = ErrorReply(detail="binary frames are not accepted")
            else:
                reply = await _control(console, text, authed)
            if isinstance(reply, AuthOk):
                authed = True
            await websocket.send_text(message_json(reply))
    except (WebSocketDisconnect, RuntimeError):
        pass
    finally:
        pump.cancel()
        with contextlib.suppress(asyncio.CancelledError, Exception):
            await pump


async def _control(console: Console, text: str, authed: bool) -> Reply:
    if len(text) > MAX_CONTROL_BYTES or len(text.encode()) > MAX_CONTROL_BYTES:
        return ErrorReply(detail=f"message over {MAX_CONTROL_BYTES} bytes")
    if nesting_over(text, MAX_CONTROL_DEPTH):
        return ErrorReply(detail=f"message nested deeper than {MAX_CONTROL_DEPTH}")
    try:
        msg = json.loads(text, parse_constant=_no_constant)
    except _NotANumber as err:
        return ErrorReply(detail=str(err))
    except ValueError:
        return ErrorReply(detail="not JSON")
    if not isinstance(msg, dict):
        return ErrorReply(detail="expected a JSON object with a 'type'")
    invalid = lone_surrogate_in(msg)  # the REST rule (backend.strict_input), before any use
    if invalid is not None:
        loc, detail, _text = invalid
        return ErrorReply(detail=detail, field=".".join(map(str, loc)), status=422)
    kind = msg.get("type")
    if kind not in CLIENT_TYPES:
        use = ", ".join(CLIENT_TYPES)
        return ErrorReply(detail=f"unknown message type {shorten(repr(kind), 40)}; use {use}")
    if kind != "auth":
        if not authed:
            return ErrorReply(detail="token required: send {type: auth, token} first")
        if console.service is None:
            return ErrorReply(detail="the console is starting", status=503)
    try:
        parsed = CLIENT_MESSAGE.validate_python(msg)
    except ValidationError as err:
        if kind == "auth":  # a token that is not text is no token
            return AuthRefused(detail="wrong operator token")
        return _invalid(err)
    if isinstance(parsed, AuthMessage):
        if token_ok(console, parsed.token):
            return AuthOk()
        # a type of its own: a page told this on (re)connecting goes read-only at once (the
        # console restarted with a new token), not at the operator's next press
        return AuthRefused(detail="wrong operator token")
    service = console.service
    assert service is not None
    try:
        if isinstance(parsed, SurfaceMessage):
            outcome = await service.surface("ws", vehicle=parsed.vehicle)
        else:
            request = SendRequest(
                parsed.pattern,
                parsed.params,
                "ws",
                override=parsed.override,
                copies=parsed.copies,
                vehicle=parsed.vehicle,
            )
            outcome = await service.send(request)
    except (CodecError, PlanError) as err:
        field = getattr(err, "field", None)
        return ErrorReply(detail=shorten(str(err)), field=field, status=422)
    except VehicleRefused as err:
        return ErrorReply(detail=err.message, field=err.field, status=err.status)
    except SendRefused as err:
        violations = [LimitViolation.model_validate(v.as_json()) for v in err.violations]
        detail = "; ".join([err.message, *(v.message for v in violations)])
        return ErrorReply(detail=detail, violations=violations, status=err.status)
    except RateLimited as err:
        return ErrorReply(detail=str(err), status=429)
    except LogWriteError as err:
        return ErrorReply(detail=str(err), status=503)
    if len(outcome.records) > 1:  # a Surface to all: every vehicle's record
        return Queued(command=outcome.record, commands=list(outcome.records))
    return Queued(command=outcome.record)


def _invalid(err: ValidationError) -> ErrorReply:
    """A control message that does not fit its model: its first error, naming the field
    (a parameter by its name, as the codec names it)."""
    first = err.errors(include_url=False)[0]
    loc = [str(part) for part in first["loc"][1:] if part != "[key]"]  # after the type's tag
    where = ".".join(loc) or "message"
    detail = shorten(f"{where}: {first['msg']}")
    return ErrorReply(detail=detail, field=loc[-1] if loc else None, status=422)
