"""``nemesys console``: run the console (FastAPI on uvicorn, viser, and in training mode the
simulated vehicle) and print the operator URL with its token, as Jupyter does.

Imported by every ``nemesys`` command for its parser: the console's dependencies (pydantic,
FastAPI, uvicorn) are imported only when the console runs."""

from __future__ import annotations

import argparse
import errno
import os
import socket
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TextIO

from backend.token_file import TokenFileError, token_path, with_kept_token
from codec import int_from_text, number_from_text

if TYPE_CHECKING:
    import uvicorn

    from backend.mission_log.store import MissionLog
    from backend.settings import Settings

#: The exit status of bad input (``cli.common.EXIT_USAGE``): a setting, the mission log,
#: the port.
EXIT_USAGE = 2


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "console",
        help="run the operator console (browser page, API, 3D view; training mode by default)",
        description="Run the console. Settings come from NEMESYS_* environment variables or the "
        "file named by NEMESYS_SETTINGS; these options override them. Default: training mode "
        "with the simulated vehicle, a local SQLite log, everything on 127.0.0.1.",
    )
    p.add_argument("--host", help="interface for the page and API (default 127.0.0.1)")
    p.add_argument("--port", type=int_from_text, help="port of the page and API (default 8000)")
    p.add_argument("--viewer-port", type=int_from_text, help="viser's port (default 8080; 0 = any)")
    p.add_argument(
        "--target",
        help="sim (default: the simulated vehicle), ws://host:port (a rosbridge vehicle), "
        "serial:///dev/ttyUSB0 or tcp://host:port (an ME modem)",
    )
    p.add_argument(
        "--db", dest="db_path", help="mission log file (default .nemesys/missions.sqlite3)"
    )
    p.add_argument(
        "--time-scale", dest="sim_time_scale", type=number_from_text, help="simulator speed-up"
    )
    p.add_argument(
        "--new-token",
        action="store_true",
        help="write a new operator token (kept owner-only beside the mission log, reused at "
        "every start); pages holding the old one become read-only",
    )


def _recover(log: MissionLog, settings: Settings, out: TextIO) -> str | None:
    """What an earlier run left on its way made ``interrupted`` (on a log consoles share, only
    this console's own) and said; or why this console's name cannot be used.

    Raises:
        LogWriteError: the log cannot be written.
    """
    from backend.control.identity import ConsoleNameError, recovered_by

    try:
        recovered = log.recover_interrupted(recovered_by(settings))
    except ConsoleNameError as err:
        return str(err)
    _report_recovered(recovered, out)
    return None


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
        from backend.strict_input import error_message

        first = err.errors()[0]
        where = ".".join(str(p) for p in first["loc"])
        # a rule between settings (a model validator) has no field to name
        return _usage(f"setting{' ' if where else 's'}{where}: {error_message(first)}")
    from backend.mission_log.opening import LogError, elsewhere, open_checked
    from backend.mission_log.store import LogWriteError

    # before the URL: the log is usable, what an earlier run left on its way is interrupted,
    # not stuck, and the token kept beside the log is read (or made, or replaced)
    try:
        log = open_checked(settings.mission_log)
    except LogError as err:
        return _usage(str(err))
    try:
        if (refused := _recover(log, settings, out)) is not None:
            return _usage(refused)
        settings, kept = _with_token(settings, rotate=args.new_token)
    except LogWriteError as err:
        return _usage(
            f"mission log {settings.mission_log_name} cannot be written ({err.reason}): free "
            f"some space or make it writable, {elsewhere(settings.mission_log)}"
        )
    except TokenFileError as err:
        return _usage(str(err))
    finally:
        log.close()
    try:
        sockets = listen_sockets(settings.host, settings.port)
    except OSError as err:
        return _usage(port_problem(settings.host, settings.port, err))
    port = sockets[0].getsockname()[1]  # the one chosen, if asked for port 0
    url = f"http://{settings.host}:{port}/?token={settings.token}"
    mode = (
        "training (simulated vehicle)"
        if settings.training
        else "relay (no transmitter here: the console holding it sends)"
        if settings.relay
        else f"vehicle at {settings.target}"
    )

    def announce() -> None:
        out.write(
            f"NemeSys console, {mode}; mission log {settings.mission_log_name}\n"
            f"Open this URL (it holds the operator token; without it the page is read-only):\n"
            f"    {url}\n{kept}"
        )
        out.flush()

    config = uvicorn.Config(
        create_app(settings),
        host=settings.host,
        port=settings.port,
        log_level=os.environ.get("NEMESYS_LOG_LEVEL", "warning"),
        ws="websockets-sansio",
        # /ws answers an over-size message itself (live.py); above the body cap uvicorn
        # closes the connection (1009) rather than hold up to its default 16 MiB
        ws_max_size=settings.max_body_bytes,
        # no permessage-deflate: compressing is per connection (each page its own zlib
        # context), so a telemetry message compressed for 20 pages is 20 encodings. Sent
        # uncompressed, it is serialised once and the same bytes go to every page (issue 23:
        # the pages' cost must not grow with the fleet); ~60 KB/s a page for 10 vehicles.
        ws_per_message_deflate=False,
    )
    server = _server(config, announce)
    try:
        server.run(sockets=sockets)
    except OSError as err:  # uvicorn could not serve on the sockets
        if server.started:
            raise
        return _usage(port_problem(settings.host, port, err))
    except SystemExit as exc:  # uvicorn: the app did not start (it logged why)
        if server.started:
            raise
        print("nemesys console: the console did not start (the error is above)", file=sys.stderr)
        return exc.code if isinstance(exc.code, int) else 1
    finally:
        for sock in sockets:
            sock.close()
    return 0


def _report_recovered(recovered: int, out: TextIO) -> None:
    """Say how many commands an earlier run left on their way (now interrupted), if any."""
    if recovered:
        one = recovered == 1
        out.write(
            f"{recovered} command{'' if one else 's'} an earlier run left queued or transmitted "
            f"{'is' if one else 'are'} now interrupted (retry {'it' if one else 'them'} from "
            "the log)\n"
        )


def _with_token(settings: Settings, *, rotate: bool) -> tuple[Settings, str]:
    """``settings`` with the token kept beside the log (unless set explicitly: the URL a page
    was opened with stays good across restarts, until ``--new-token``), and the line that says
    so under the URL.

    Raises:
        backend.token_file.TokenFileError: the file is unsafe or unreadable.
    """
    explicit = "token" in settings.model_fields_set
    settings = with_kept_token(settings, rotate=rotate)
    if rotate:
        return settings, (
            "New operator token: pages opened with the old one are read-only until opened with "
            "this URL.\n"
        )
    if explicit:
        return settings, ""
    where = token_path(settings.db_path)
    return settings, f"(the token is kept in {where}; --new-token replaces it)\n"


def _usage(message: str) -> int:
    """One line on stderr, exit status 2 (as the CLI's ``UsageError``: raising that from here
    would not reach ``python -m cli.main``'s handler, a second copy of the module)."""
    print(f"nemesys console: {message}", file=sys.stderr)
    return EXIT_USAGE


def listen_sockets(host: str, port: int) -> list[socket.socket]:
    """Bound sockets for every address of ``host`` (as asyncio's ``create_server`` binds
    them), handed to uvicorn: a busy port is found here, before anything starts, and nobody
    can take it in between. (Only a socket bound with ``SO_REUSEADDR`` but not listening
    could still make uvicorn's ``listen`` fail: that is handled where it runs.)

    Raises:
        OSError: the port is in use, or the address is not one of this machine's.
    """
    infos = socket.getaddrinfo(host or None, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    sockets: list[socket.socket] = []
    try:
        for family, kind, proto, _name, address in dict.fromkeys(infos):
            sock = socket.socket(family, kind, proto)
            sockets.append(sock)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            if family == socket.AF_INET6:
                sock.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
            sock.bind(address)  # not listening yet: uvicorn listens once the app has started
    except OSError:
        for sock in sockets:
            sock.close()
        raise
    return sockets


def port_problem(host: str, port: int, err: OSError) -> str:
    """The one line ``nemesys console`` prints when it cannot listen on ``host:port``."""
    if err.errno == errno.EADDRINUSE:
        return f"port {port} on {host} is in use: another console? choose --port"
    if isinstance(err, socket.gaierror) or err.errno == errno.EADDRNOTAVAIL:
        return f"cannot listen on {host}: not an address of this machine; choose --host"
    if err.errno == errno.EACCES:
        return f"port {port} on {host} is not allowed to this user: choose --port above 1023"
    return f"cannot listen on port {port} on {host} ({err.strerror or err}): choose --port"


def _server(config: uvicorn.Config, on_started: Callable[[], None]) -> uvicorn.Server:
    """uvicorn's server, calling ``on_started`` once it listens (the lifespan has started the
    console by then: a request to the URL succeeds)."""
    import uvicorn

    class Server(uvicorn.Server):
        async def startup(self, sockets: list[socket.socket] | None = None) -> None:
            try:
                await super().startup(sockets=sockets)
            except OSError:  # listen() failed: the console stops, as uvicorn's own bind does
                await self.lifespan.shutdown()
                raise
            if self.started:
                on_started()

    return Server(config)
