"""The console app: ``create_app(settings)`` builds it; its lifespan owns the runtime.

Nothing starts at import time. The lifespan starts the :class:`backend.console.Console` (the
mission log, in training mode the simulated vehicle and its rosbridge, the vehicle link, the
viser view) and, when ``foxglove_port`` is set, the live Foxglove view
(:mod:`backend.foxglove_live`), and stops them on shutdown. One uvicorn worker only: viser
and the simulator live in the process.
"""

from __future__ import annotations

import math
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

from fastapi import Depends, FastAPI, Request
from fastapi.responses import FileResponse, JSONResponse
from fastapi.staticfiles import StaticFiles
from starlette.exceptions import HTTPException
from starlette.types import Scope

from backend.api import (
    authoring,
    chart,
    commands,
    control,
    errors_db,
    live,
    predict,
    scripts,
    survey,
    training,
)
from backend.api import dives as dives_api
from backend.api import vehicles as vehicles_api
from backend.api import view as view_api
from backend.api.openapi import security_schemes
from backend.bounded_input import BodyLimit, shorten, validation_errors
from backend.clock import SYSTEM_CLOCK, Clock
from backend.commands.manager import RateLimited
from backend.commands.service import SendRefused, VehicleRefused, refusal_detail
from backend.console import Console
from backend.foxglove_live import live_view
from backend.security import HostGuard, allowed_hosts, install_redaction
from backend.settings import Settings
from backend.strict_input import strict_json_body
from backend.token_file import with_kept_token
from codec import EncodeError
from planner import PlanError
from station.link import Link

FRONTEND = Path(__file__).resolve().parent.parent / "frontend"
#: The page's chart and plot libraries, installed from npm by the Makefile (no CDN at sea):
#: only their ``dist`` directories are served, at /vendor/<name>.
VENDOR = {
    "leaflet": FRONTEND / "vendor" / "node_modules" / "leaflet" / "dist",
    "uplot": FRONTEND / "vendor" / "node_modules" / "uplot" / "dist",
}


def create_app(
    settings: Settings | None = None,
    *,
    viewer: bool = True,
    link: Link | None = None,
    clock: Clock = SYSTEM_CLOCK,
) -> FastAPI:
    """The FastAPI app for ``settings`` (default: from the environment). ``link`` and
    ``clock`` replace the settings' link (and the simulator) and the system clock: the tests'
    light app on an in-memory vehicle (:class:`backend.console.Console`). Without an
    explicit token it takes the one kept beside the mission log, so that pages keep working
    across a restart (``backend.token_file.TokenFileError`` if that file is unsafe or
    unreadable)."""
    cfg = with_kept_token(settings or Settings.load())

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        # after the server configured its logging: no token reaches any log output
        install_redaction([cfg.token])
        console = Console(cfg, link=link, clock=clock)
        app.state.console = console
        await console.start(viewer=viewer)
        try:
            async with live_view(console):  # the Foxglove view, when foxglove_port is set
                yield
        finally:
            await console.stop()

    app = FastAPI(
        title="NemeSys Console",
        summary="Author, preview, send and watch 100-bit retasking commands for the NemeSys AUV.",
        version="0.1.0",
        lifespan=lifespan,
        # a JSON body with a lone surrogate anywhere is a 422 naming the field, before
        # anything reads it (no 500, the connection stays open)
        dependencies=[Depends(strict_json_body)],
    )
    app.state.settings = cfg
    # No CORS middleware: cross-origin browser calls are refused (closed by default).
    # Bodies over the cap are refused (413) before routing, authentication or parsing.
    app.add_middleware(BodyLimit, max_bytes=cfg.max_body_bytes)
    # Requests naming another Host are refused (400) before anything else: DNS rebinding.
    app.add_middleware(HostGuard, allowed=allowed_hosts(cfg.host, cfg.allowed_hosts))
    for router in (
        authoring.router,
        commands.router,
        control.router,
        training.router,
        scripts.router,
        live.router,
        chart.router,
        predict.router,
        dives_api.router,
        survey.router,
        vehicles_api.router,
    ):
        app.include_router(router)
    app.include_router(view_api.router)  # a page's own 3D view
    _errors(app)
    _static(app)
    security_schemes(app)
    return app


def _errors(app: FastAPI) -> None:
    validation_errors(app)
    errors_db.register(app)

    @app.exception_handler(EncodeError)
    async def encode_error(_request: Request, err: EncodeError) -> JSONResponse:
        loc = ["body", "params", err.field] if err.field else ["body", "pattern"]
        return JSONResponse(
            {"detail": [{"loc": loc, "msg": shorten(str(err)), "type": "value_error"}]},
            status_code=422,
        )

    @app.exception_handler(PlanError)
    async def plan_error(_request: Request, err: PlanError) -> JSONResponse:
        loc = ["body", "params", err.field] if err.field else ["body", "params"]
        return JSONResponse(
            {"detail": [{"loc": loc, "msg": shorten(str(err)), "type": "plan_error"}]},
            status_code=422,
        )

    @app.exception_handler(SendRefused)
    async def send_refused(_request: Request, err: SendRefused) -> JSONResponse:
        """The command service's refusals, with the status every path gives them (a request
        naming no vehicle of the console's: a validation error at its ``vehicle``)."""
        if isinstance(err, VehicleRefused):
            where = {"loc": ["body", "vehicle"], "msg": err.message, "type": "vehicle"}
            return JSONResponse({"detail": [where]}, status_code=422)
        return JSONResponse({"detail": refusal_detail(err)}, status_code=err.status)

    @app.exception_handler(RateLimited)
    async def rate_limited(_request: Request, err: RateLimited) -> JSONResponse:
        return JSONResponse(
            {"detail": str(err)},
            status_code=429,
            headers={"Retry-After": str(math.ceil(err.retry_after_s))},
        )


def _static(app: FastAPI) -> None:
    @app.get("/", include_in_schema=False)
    def index() -> FileResponse:
        return FileResponse(FRONTEND / "index.html", headers={"Cache-Control": "no-cache"})

    @app.get("/viewer/", include_in_schema=False)
    def viewer_page() -> FileResponse:
        """viser's own client page, served same-origin; it connects to viser's port."""
        from backend.viewer.client_page import client_html_path

        return FileResponse(client_html_path())

    for name, directory in VENDOR.items():
        # not installed (no npm): no mount; the page then says the chart is unavailable
        if directory.is_dir():
            app.mount(f"/vendor/{name}", StaticFiles(directory=directory), name=f"vendor-{name}")
    app.mount("/static", _Frontend(directory=FRONTEND), name="static")


class _Frontend(StaticFiles):
    """frontend/ without frontend/vendor/ (npm's tree: package files and sources that are
    not the page's; its ``dist`` directories are served at /vendor/ instead)."""

    def get_path(self, scope: Scope) -> str:
        path = super().get_path(scope)
        if Path(path).parts[:1] == ("vendor",):
            raise HTTPException(status_code=404)
        return path
