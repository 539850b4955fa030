"""The mission log's write failures as answers: 503, naming the reason.

A command is logged before it is transmitted; when the log cannot be written (disk full, the
file made read-only, locked by another process), the send fails with 503 and says what was
done about it ("nothing was transmitted"), so the operator can fix the disk and send again.
"""

from __future__ import annotations

from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse

from backend.mission_log.store import LogWriteError

#: Seconds the client is told to wait before trying again (the disk must be fixed first).
RETRY_AFTER_S = 5


def register(app: FastAPI) -> None:
    """Answer :class:`backend.mission_log.store.LogWriteError` with 503 and its message as
    ``detail``."""

    @app.exception_handler(LogWriteError)
    async def log_write_error(_request: Request, err: LogWriteError) -> JSONResponse:
        return JSONResponse(
            {"detail": str(err)},
            status_code=503,
            headers={"Retry-After": str(RETRY_AFTER_S)},
        )
