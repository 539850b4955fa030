"""The live websocket: telemetry and command states out; authenticated control in."""

from __future__ import annotations

import asyncio
import contextlib
import json
from typing import Any

from fastapi import APIRouter, WebSocket, WebSocketDisconnect, status

from backend.api.deps import token_ok
from backend.api.models import check_copies
from backend.bounded_input import shorten
from backend.commands.manager import RateLimited
from backend.commands.service import SendRefused, SendRequest
from backend.console import Console
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
    """Server -> client: ``telemetry`` (10 Hz, latest wins), ``command``, ``vehicle`` and
    ``error`` messages. Client -> server: ``auth`` (answered ``auth_ok`` or ``auth_refused``)
    then ``surface`` or ``send``; control without the token is refused (the connection stays,
    read-only). A browser page from
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
                reply: dict[str, Any] = {
                    "type": "error",
                    "detail": "binary frames are not accepted",
                }
            else:
                reply = await _control(console, text, authed)
            if reply.get("type") == "auth_ok":
                authed = True
            await websocket.send_text(json.dumps(reply))
    except (WebSocketDisconnect, RuntimeError):
        pass
    finally:
        pump.cancel()
        with contextlib.suppress(asyncio.CancelledError, Exception):
            await pump


async def _control(console: Console, text: str, authed: bool) -> dict[str, Any]:
    if len(text) > MAX_CONTROL_BYTES or len(text.encode()) > MAX_CONTROL_BYTES:
        return {"type": "error", "detail": f"message over {MAX_CONTROL_BYTES} bytes"}
    if nesting_over(text, MAX_CONTROL_DEPTH):
        return {"type": "error", "detail": f"message nested deeper than {MAX_CONTROL_DEPTH}"}
    try:
        msg = json.loads(text, parse_constant=_no_constant)
    except _NotANumber as err:
        return {"type": "error", "detail": str(err)}
    except ValueError:
        return {"type": "error", "detail": "not JSON"}
    if not isinstance(msg, dict):
        return {"type": "error", "detail": "expected a JSON object with a 'type'"}
    invalid = lone_surrogate_in(msg)  # the REST rule (backend.strict_input), before any use
    if invalid is not None:
        loc, detail, _text = invalid
        return {"type": "error", "detail": detail, "field": ".".join(map(str, loc))}
    kind = msg.get("type")
    if kind == "auth":
        token = msg.get("token")
        if isinstance(token, str) and token_ok(console, token):
            return {"type": "auth_ok"}
        # a type of its own: a page told this on (re)connecting goes read-only at once (the
        # console restarted with a new token), not at the operator's next press
        return {"type": "auth_refused", "detail": "wrong operator token"}
    if kind not in ("surface", "send"):
        return {
            "type": "error",
            "detail": f"unknown message type {shorten(repr(kind), 40)}; use auth, surface, send",
        }
    if not authed:
        return {"type": "error", "detail": "token required: send {type: auth, token} first"}
    service = console.service
    if service is None:
        return {"type": "error", "detail": "the console is starting", "status": 503}
    try:
        if kind == "surface":
            outcome = await service.surface("ws")
        else:
            request = _send_request(msg)
            if isinstance(request, dict):
                return request
            outcome = await service.send(request)
    except (CodecError, PlanError) as err:
        field = getattr(err, "field", None)
        return {"type": "error", "detail": shorten(str(err)), "field": field, "status": 422}
    except SendRefused as err:
        violations = [v.as_json() for v in err.violations]
        detail = "; ".join([err.message, *(v["message"] for v in violations)])
        return {"type": "error", "detail": detail, "violations": violations, "status": err.status}
    except RateLimited as err:
        return {"type": "error", "detail": str(err), "status": 429}
    except LogWriteError as err:
        return {"type": "error", "detail": str(err), "status": 503}
    return {"type": "queued", "command": outcome.record}


def _send_request(msg: dict[str, Any]) -> SendRequest | dict[str, Any]:
    """A ``send`` message as the command service takes it, or the error reply naming the
    field: ``pattern`` (str), ``params`` (object), ``override`` (bool), ``copies``."""
    pattern, params = msg.get("pattern"), msg.get("params", {})
    if not isinstance(pattern, str) or not isinstance(params, dict):
        return _bad("send needs a pattern (str) and params (object)", "pattern")
    override = msg.get("override", False)
    if not isinstance(override, bool):
        return _bad(
            f"override must be true or false, got {shorten(repr(override), 40)}", "override"
        )
    copies = msg.get("copies")
    try:
        check_copies(copies)
    except ValueError as err:
        return _bad(str(err), "copies")
    return SendRequest(pattern, params, "ws", override=override, copies=copies)


def _bad(detail: str, field: str) -> dict[str, Any]:
    return {"type": "error", "detail": detail, "field": field, "status": 422}
