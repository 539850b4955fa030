"""``nemesys console``: run the console (FastAPI on uvicorn, viser, and in training mode the
simulated vehicle) and print the operator URL with its token, as Jupyter does.

Imported by every ``nemesys`` command for its parser: the console's dependencies (pydantic,
FastAPI, uvicorn) are imported only when the console runs."""

from __future__ import annotations

import argparse
import os
from typing import Any, TextIO


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "console",
        help="run the operator console (browser page, API, 3D view; training mode by default)",
        description="Run the console. Settings come from NEMESYS_* environment variables or the "
        "file named by NEMESYS_SETTINGS; these options override them. Default: training mode "
        "with the simulated vehicle, a local SQLite log, everything on 127.0.0.1.",
    )
    p.add_argument("--host", help="interface for the page and API (default 127.0.0.1)")
    p.add_argument("--port", type=int, help="port of the page and API (default 8000)")
    p.add_argument("--viewer-port", type=int, help="viser's port (default 8080; 0 = any)")
    p.add_argument(
        "--target",
        help="sim (default: the simulated vehicle), ws://host:port (a rosbridge vehicle), "
        "serial:///dev/ttyUSB0 or tcp://host:port (an ME modem)",
    )
    p.add_argument(
        "--db", dest="db_path", help="mission log file (default .nemesys/missions.sqlite3)"
    )
    p.add_argument("--time-scale", dest="sim_time_scale", type=float, help="simulator speed-up")


def cmd_console(args: argparse.Namespace, out: TextIO) -> int:
    import uvicorn
    from pydantic import ValidationError

    from backend.app import create_app
    from backend.settings import Settings

    overrides: dict[str, Any] = {
        k: v
        for k, v in {
            "host": args.host,
            "port": args.port,
            "viewer_port": args.viewer_port,
            "target": args.target,
            "db_path": args.db_path,
            "sim_time_scale": args.sim_time_scale,
        }.items()
        if v is not None
    }
    try:
        settings = Settings.load(**overrides)
    except ValidationError as err:
        first = err.errors()[0]
        where = ".".join(str(p) for p in first["loc"])
        from backend.cli import UsageError

        raise UsageError(f"setting {where}: {first['msg']}") from None
    from backend.store import MissionLog

    # before the URL: what an earlier run left on its way is interrupted, not stuck
    log = MissionLog(settings.db_path)
    try:
        recovered = log.recover_interrupted()
    finally:
        log.close()
    if recovered:
        one = recovered == 1
        out.write(
            f"{recovered} command{'' if one else 's'} an earlier run left queued or transmitted "
            f"{'is' if one else 'are'} now interrupted (retry {'it' if one else 'them'} from "
            "the log)\n"
        )
    url = f"http://{settings.host}:{settings.port}/?token={settings.token}"
    mode = "training (simulated vehicle)" if settings.training else f"vehicle at {settings.target}"
    out.write(
        f"NemeSys console, {mode}; mission log {settings.db_path}\n"
        f"Open this URL (it holds the operator token; without it the page is read-only):\n"
        f"    {url}\n"
    )
    out.flush()
    uvicorn.run(
        create_app(settings),
        host=settings.host,
        port=settings.port,
        log_level=os.environ.get("NEMESYS_LOG_LEVEL", "warning"),
        ws="websockets-sansio",
    )
    return 0
