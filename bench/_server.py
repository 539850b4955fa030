"""``nemesys console`` as a subprocess on a free loopback port, for the console benchmark and
the end-to-end and browser tests.

:func:`start_console` runs ``python -m cli.main console`` from the repository (the viser
view on a port of its own choosing), with no ``NEMESYS_*`` variable of the caller's (a
target, a settings file) but the operator token and what the caller adds; its output goes
to a log file. It parses the URL the console prints and polls ``/api/session`` until it
answers 200; whatever fails on the way stops the process and raises :class:`RuntimeError`
with the end of the log.
"""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO
from urllib.parse import urlsplit

import httpx

REPO = Path(__file__).resolve().parents[1]
#: The line ``nemesys console`` prints: base URL, then the operator token.
URL_LINE = re.compile(r"(http://[^/\s]+)/\?token=(\S+)")
START_TIMEOUT_S = 30.0


def free_port() -> int:
    """A loopback port free right now (the server binds it a moment later)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
        return port


@dataclass
class ConsoleProcess:
    """A running ``nemesys console``: ``port`` is the one it was given, ``base_url`` and
    ``token`` what it printed. As a context manager, stopped on exit."""

    proc: subprocess.Popen[bytes]
    port: int
    base_url: str
    token: str
    log_path: Path

    @property
    def pid(self) -> int:
        return self.proc.pid

    @property
    def host(self) -> str | None:
        return urlsplit(self.base_url).hostname

    @property
    def ws_url(self) -> str:
        return self.base_url.replace("http://", "ws://", 1) + "/ws"

    def client(self, timeout_s: float = 10.0) -> httpx.Client:
        """A REST client of this console (no proxy from the environment: loopback only)."""
        return httpx.Client(base_url=self.base_url, timeout=timeout_s, trust_env=False)

    def log_tail(self, lines: int = 20) -> str:
        return _tail(self.log_path, lines)

    def stop(self, timeout_s: float = 15.0) -> None:
        """SIGTERM (uvicorn shuts the lifespan down), SIGKILL if it does not exit in time."""
        _stop(self.proc, timeout_s)

    def kill(self) -> None:
        """SIGKILL: no shutdown, no flush, no lifespan exit."""
        self.proc.kill()
        self.proc.wait(timeout=10)

    def __enter__(self) -> ConsoleProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def start_console(
    log_path: Path,
    token: str | None,
    *args: str,
    env: Mapping[str, str] | None = None,
    timeout_s: float = START_TIMEOUT_S,
    port: int | None = None,
) -> ConsoleProcess:
    """Start ``nemesys console --port <port> --viewer-port 0 *args`` with ``NEMESYS_TOKEN``
    ``token`` (None: none, the console uses the token kept beside its log) and ``env`` added
    to the environment; return it once ``/api/session`` answers. ``port``: a free one if not
    given (a restart passes the one of the console it replaces)."""
    port = port or free_port()
    child_env = {k: v for k, v in os.environ.items() if not k.startswith("NEMESYS_")}
    if token is not None:
        child_env["NEMESYS_TOKEN"] = token
    child_env.update(env or {})
    cmd = [sys.executable, "-m", "cli.main", "console", "--port", str(port)]
    cmd += ["--viewer-port", "0", *args]
    with log_path.open("wb") as log:
        proc = subprocess.Popen(
            cmd,
            cwd=REPO,
            env=child_env,
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=subprocess.STDOUT,
        )
    try:
        deadline = time.monotonic() + timeout_s
        base_url, printed_token = _printed_url(proc, log_path, deadline)
        console = ConsoleProcess(proc, port, base_url, printed_token, log_path)
        _wait_ready(console, deadline)
    except BaseException:
        _stop(proc, 10.0)
        raise
    return console


def _printed_url(proc: subprocess.Popen[bytes], log_path: Path, deadline: float) -> tuple[str, str]:
    while True:
        match = URL_LINE.search(log_path.read_text(errors="replace"))
        if match:
            return match.group(1), match.group(2)
        if proc.poll() is not None or time.monotonic() > deadline:
            raise RuntimeError(f"the console printed no URL:\n{_tail(log_path)}")
        time.sleep(0.05)


def _wait_ready(console: ConsoleProcess, deadline: float) -> None:
    """Poll ``/api/session`` until it answers 200."""
    with console.client(timeout_s=2.0) as http:
        while True:
            if console.proc.poll() is not None:
                code = console.proc.returncode
                raise RuntimeError(f"the console exited ({code}):\n{console.log_tail()}")
            try:
                if http.get("/api/session").status_code == 200:
                    return
            except httpx.TransportError:
                pass
            if time.monotonic() > deadline:
                raise RuntimeError(f"GET /api/session never answered:\n{console.log_tail()}")
            time.sleep(0.05)


def _tail(path: Path, lines: int = 20) -> str:
    try:
        text = path.read_text(errors="replace")
    except OSError:
        return ""
    return "\n".join(text.splitlines()[-lines:])


def _stop(proc: subprocess.Popen[bytes], timeout_s: float) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout_s)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def shared_log_url(bench: str, out: TextIO) -> str | None:
    """``NEMESYS_DATABASE_URL``, the PostgreSQL database the consoles of ``bench`` share; None
    (having said on ``out`` how to give one) when it names none."""
    from backend.mission_log.database import is_postgres_url

    url = os.environ.get("NEMESYS_DATABASE_URL", "")
    if is_postgres_url(url):
        return url
    out.write(
        f"bench {bench} needs a PostgreSQL database both consoles share: set "
        "NEMESYS_DATABASE_URL=postgresql://user:password@127.0.0.1:5432/database "
        "(an empty one: the consoles make the tables)\n"
    )
    return None
