"""The mission log's failures as answers: 503, naming the reason.

A command is logged before it is transmitted; when the log cannot be written (disk full, the
file made read-only, locked by another process), the send fails with 503 and says what was
done about it ("nothing was transmitted"), so the operator can fix the disk and send again.
A read of the log that cannot reach it (a PostgreSQL server gone, a SQLite file locked or
unreadable) is a 503 naming the driver's reason too, never a 500: the console keeps running
and answers again once the database is back.
"""

from __future__ import annotations

import sqlite3

import psycopg
from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse

from backend.mission_log.database import one_line
from backend.mission_log.store import LogWriteError

#: The drivers' errors of a database out of reach (not of our own misuse, which stays a 500:
#: a bug to fix): a lost or refused connection, a locked or unreadable file.
UNREACHABLE_ERRORS: tuple[type[Exception], ...] = (
    sqlite3.OperationalError,
    psycopg.OperationalError,
    psycopg.InterfaceError,
)

#: Seconds the client is told to wait before trying again (the disk must be fixed first).
RETRY_AFTER_S = 5


def register(app: FastAPI) -> None:
    """Answer :class:`backend.mission_log.store.LogWriteError` with 503 and its message as
    ``detail``, and a read that cannot reach the log (:data:`UNREACHABLE_ERRORS`) with 503
    and the driver's reason."""

    @app.exception_handler(LogWriteError)
    async def log_write_error(_request: Request, err: LogWriteError) -> JSONResponse:
        return JSONResponse(
            {"detail": str(err)},
            status_code=503,
            headers={"Retry-After": str(RETRY_AFTER_S)},
        )

    async def log_unreachable(_request: Request, err: Exception) -> JSONResponse:
        return JSONResponse(
            {
                "detail": "the mission log cannot be read right now "
                f"({one_line(str(err))}); try again when the database is back"
            },
            status_code=503,
            headers={"Retry-After": str(RETRY_AFTER_S)},
        )

    for error in UNREACHABLE_ERRORS:
        app.add_exception_handler(error, log_unreachable)
