"""A throw-away PostgreSQL server for the tests: ``initdb`` and ``pg_ctl`` (Debian's
``postgresql`` package) in a temporary directory, on 127.0.0.1 and a free port.

PostgreSQL refuses to run as root: when the tests run as root (CI, these machines) the server
runs as the ``postgres`` system user (``runuser -u postgres``; its data directory is a
temporary directory given to that user), otherwise as the current user. It listens on
127.0.0.1 only and on a unix socket in its own directory, never the system's. The login is
a password one (scram-sha-256) so the URLs the tests use carry a password, as a real one does.
``fsync`` is off: the tests kill consoles, not the server, and what a console committed is
the server's whichever way it writes its files; a server that dies loses nothing the tests
need.

Without PostgreSQL the fixture fails (never a silent skip), saying how to install it:
:data:`INSTALL_HINT`.
"""

from __future__ import annotations

import glob
import itertools
import os
import pwd
import shutil
import socket
import subprocess
import tempfile
import time
from pathlib import Path

import psycopg

INSTALL_HINT = (
    "PostgreSQL's server programs (initdb, pg_ctl) were not found (pg_config --bindir, "
    "/usr/lib/postgresql/*/bin): install Debian's package, `apt-get install postgresql` "
    "(.ci/run does so when it is missing)"
)
#: The server's superuser and its password (the URLs' ``user:password``).
USER = "nemesys"
PASSWORD = "test-password-0123"
START_TIMEOUT_S = 60
#: Attempts at a free port (another process may take the one found before the server binds).
PORT_TRIES = 5


class PostgresMissing(RuntimeError):
    """No PostgreSQL server programs on this machine."""


def bindir() -> Path:
    """The directory of ``initdb`` and ``pg_ctl``: ``pg_config --bindir``, else the newest
    ``/usr/lib/postgresql/*/bin``.

    Raises:
        PostgresMissing: neither has them (:data:`INSTALL_HINT`).
    """
    candidates: list[Path] = []
    if shutil.which("pg_config"):
        found = subprocess.run(
            ["pg_config", "--bindir"], capture_output=True, text=True, check=False
        ).stdout.strip()
        if found:
            candidates.append(Path(found))
    versions = glob.glob("/usr/lib/postgresql/*/bin")
    candidates += sorted((Path(p) for p in versions), key=_version, reverse=True)
    for path in candidates:
        if (path / "initdb").is_file() and (path / "pg_ctl").is_file():
            return path
    raise PostgresMissing(INSTALL_HINT)


def _version(path: Path) -> tuple[int, ...]:
    try:
        return tuple(int(part) for part in path.parent.name.split("."))
    except ValueError:
        return (0,)


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
        return port


class PgServer:
    """A running server; :meth:`stop` ends it and removes its directory."""

    def __init__(self) -> None:
        self.bin = bindir()
        self.root = Path(tempfile.mkdtemp(prefix="nemesys-pg-"))
        self.data = self.root / "data"
        self.log = self.root / "server.log"
        self.port = 0
        self._as: list[str] = []
        self._names = itertools.count(1)
        self._admin: psycopg.Connection[tuple[object, ...]] | None = None
        if os.geteuid() == 0:  # PostgreSQL will not run as root
            self._as = ["runuser", "-u", "postgres", "--"]
            user = pwd.getpwnam("postgres")
            os.chown(self.root, user.pw_uid, user.pw_gid)
        try:
            self._start()
        except BaseException:
            self.stop()
            raise

    def _run(self, *args: str, timeout_s: float = START_TIMEOUT_S) -> None:
        done = subprocess.run(
            [*self._as, *args],
            capture_output=True,
            text=True,
            timeout=timeout_s,
            check=False,
            cwd=self.root,
        )
        if done.returncode != 0:
            log = self.log.read_text(errors="replace")[-2000:] if self.log.exists() else ""
            raise RuntimeError(
                f"{Path(args[0]).name} failed ({done.returncode}): {done.stderr.strip()}\n{log}"
            )

    def _start(self) -> None:
        pwfile = self.root / "pw"
        pwfile.write_text(PASSWORD + "\n")
        if self._as:
            user = pwd.getpwnam("postgres")
            os.chown(pwfile, user.pw_uid, user.pw_gid)
        self._run(
            str(self.bin / "initdb"),
            *("-D", str(self.data), "-U", USER, "--pwfile", str(pwfile), "-E", "UTF8"),
            *("--auth-local", "trust", "--auth-host", "scram-sha-256", "--no-sync"),
        )
        pwfile.unlink()
        options = self._options()
        for attempt in range(PORT_TRIES):
            self.port = free_port()
            try:
                self._run(
                    str(self.bin / "pg_ctl"),
                    *("-D", str(self.data), "-l", str(self.log), "-w"),
                    *("-t", str(START_TIMEOUT_S), "-o", f"-p {self.port} {options}", "start"),
                    timeout_s=START_TIMEOUT_S + 10,
                )
                return
            except RuntimeError:
                if attempt == PORT_TRIES - 1:
                    raise

    def _options(self) -> str:
        return " ".join(
            (
                "-c listen_addresses=127.0.0.1",
                f"-c unix_socket_directories={self.root}",
                "-c fsync=off -c full_page_writes=off -c synchronous_commit=off",
                "-c shared_buffers=16MB -c max_connections=60",
            )
        )

    def url(self, database: str = "postgres", *, password: str | None = PASSWORD) -> str:
        """A ``postgresql://`` URL of ``database`` on this server."""
        login = USER if password is None else f"{USER}:{password}"
        return f"postgresql://{login}@127.0.0.1:{self.port}/{database}"

    def admin(self) -> psycopg.Connection[tuple[object, ...]]:
        """A connection to the ``postgres`` database (autocommit) for creating databases."""
        if self._admin is None or self._admin.closed:
            self._admin = psycopg.connect(self.url(), autocommit=True)
        return self._admin

    def new_database(self) -> str:
        """A fresh, empty database's name (a copy of ``template0``)."""
        name = f"test_{os.getpid()}_{next(self._names)}"
        self.admin().execute(f'CREATE DATABASE "{name}" TEMPLATE template0')
        return name

    def drop_database(self, name: str) -> None:
        """Drop ``name``, ending whatever connections a test left to it (a killed console's
        server side may still be closing)."""
        self.admin().execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')

    def halt(self) -> None:
        """Stop the server and keep its data (its clients see "terminating connection due to
        administrator command", then refused connections): :meth:`resume` starts it again on
        the same port."""
        if self._admin is not None:
            self._admin.close()
        self._run(str(self.bin / "pg_ctl"), "-D", str(self.data), "-m", "fast", "-w", "stop")

    def resume(self) -> None:
        """Start the halted server again, on the same port and with the same data."""
        options = self._options()
        self._run(
            str(self.bin / "pg_ctl"),
            *("-D", str(self.data), "-l", str(self.log), "-w"),
            *("-t", str(START_TIMEOUT_S), "-o", f"-p {self.port} {options}", "start"),
            timeout_s=START_TIMEOUT_S + 10,
        )

    def stop(self) -> None:
        if self._admin is not None:
            self._admin.close()
        if (self.data / "postmaster.pid").exists():
            deadline = time.monotonic() + 30
            try:
                self._run(str(self.bin / "pg_ctl"), "-D", str(self.data), "-m", "immediate", "stop")
            except (RuntimeError, subprocess.TimeoutExpired):
                while (self.data / "postmaster.pid").exists() and time.monotonic() < deadline:
                    time.sleep(0.1)
        shutil.rmtree(self.root, ignore_errors=True)
