"""Shared dependencies: the running console, and the operator token check."""

from __future__ import annotations

import secrets
from typing import Annotated

from fastapi import Depends, HTTPException, Request, status

from backend.console import Console


def get_console(request: Request) -> Console:
    console: Console = request.app.state.console
    return console


ConsoleDep = Annotated[Console, Depends(get_console)]


def token_from(authorization: str | None, header_token: str | None) -> str | None:
    """The token a request carries: ``Authorization: Bearer <t>`` or ``X-Nemesys-Token``."""
    if authorization:
        scheme, _, value = authorization.partition(" ")
        if scheme.lower() == "bearer" and value:
            return value.strip()
    return header_token


def token_ok(console: Console, token: str | None) -> bool:
    return token is not None and secrets.compare_digest(
        token.encode(), console.settings.token.encode()
    )


def require_operator(request: Request, console: ConsoleDep) -> str:
    """Calls that transmit or change state need the operator's token: 401 without, 403 wrong."""
    token = token_from(request.headers.get("authorization"), request.headers.get("x-nemesys-token"))
    if token is None:
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "operator token required (Authorization: Bearer <token>); the page is read-only "
            "without it",
            headers={"WWW-Authenticate": "Bearer"},
        )
    if not token_ok(console, token):
        raise HTTPException(status.HTTP_403_FORBIDDEN, "wrong operator token")
    return console.settings.operator


OperatorDep = Annotated[str, Depends(require_operator)]
