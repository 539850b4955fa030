"""Shared dependencies: the running console, the operator token check, the vehicle a read
names, and the bounds of integers that reach the mission log (SQLite's INTEGER is signed
64-bit)."""

from __future__ import annotations

import secrets
from typing import Annotated

from fastapi import Depends, HTTPException, Path, Query, Request, status
from fastapi.exceptions import RequestValidationError
from pydantic import Field

from backend.commands.service import CommandService, VehicleRefused
from backend.console import Console


async def get_console(request: Request) -> Console:
    # async: FastAPI runs a sync dependency in its thread pool, a hop on every request
    console: Console = request.app.state.console
    return console


ConsoleDep = Annotated[Console, Depends(get_console)]


async def get_service(console: ConsoleDep) -> CommandService:
    """The one checked path to the vehicle; 503 while the console starts."""
    if console.service is None:
        raise HTTPException(503, "the console is starting")
    return console.service


ServiceDep = Annotated[CommandService, Depends(get_service)]


async def get_query_vehicle(
    console: ConsoleDep,
    vehicle: Annotated[
        str | None,
        Query(
            max_length=32,
            description="with a fleet: the vehicle it is of (required: one of the fleet's "
            "names); without one: absent, or the single vehicle's name, nemesys",
        ),
    ] = None,
) -> str | None:
    """The vehicle a read's ``vehicle`` query names, checked as every request's vehicle is
    (:meth:`backend.console.Console.checked_vehicle`): a fleet's name, None without a fleet.
    A fleet's read that names none, or a name the console has not, is a 422 at
    ``["query", "vehicle"]`` naming the vehicles (a fleet's reads never mix vehicles)."""
    return required_vehicle(console, vehicle, ("query", "vehicle"))


#: A read of one vehicle's: its name, checked (None: the single vehicle).
QueryVehicleDep = Annotated[str | None, Depends(get_query_vehicle)]


def required_vehicle(console: Console, vehicle: str | None, where: tuple[str, ...]) -> str | None:
    """The vehicle a request names at ``where`` (a query's or a body's ``vehicle``), checked:
    with a fleet one of its names (none, or another: a 422 at ``where`` naming them); None
    without a fleet (absent or its one name, nemesys)."""
    try:
        return console.checked_vehicle(vehicle)
    except VehicleRefused as err:
        raise RequestValidationError(
            [{"type": "vehicle", "loc": where, "msg": err.message, "input": vehicle}]
        ) from None


def filter_vehicle(console: Console, vehicle: str | None, where: tuple[str, ...]) -> str | None:
    """A log filter's ``vehicle`` (at ``where`` in the request), checked: absent is every
    vehicle's rows (None); a name must be one of the console's vehicles (422 at ``where``
    naming them, never an empty answer for a misspelt name). Without a fleet the single
    vehicle's name stands for all rows (None)."""
    return None if vehicle is None else required_vehicle(console, vehicle, where)


#: The largest integer SQLite stores (signed 64-bit); beyond it a query would raise
#: ``OverflowError`` (a 500): every integer that reaches the log is bounded to 422 first.
SQLITE_INT_MAX = (1 << 63) - 1
SQLITE_INT_MIN = -(1 << 63)

#: A row id of the mission log (command id, dive number) as a path parameter: 1 and up.
IdPath = Annotated[int, Path(ge=1, le=SQLITE_INT_MAX)]
#: The same as a field of a query or body model (``LogFilter.dive``).
IdField = Annotated[int, Field(ge=1, le=SQLITE_INT_MAX)]


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
