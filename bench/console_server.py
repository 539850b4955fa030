"""``nemesys bench console``, the server harness: ``nemesys console`` in training mode on a
free loopback port, and the CPU each phase costs.

The server is started as a subprocess (the simulated vehicle behind its rosbridge, the viser
view on, a throw-away SQLite log, a random operator token, the send rate limit raised so it
never interferes); :func:`console_server` stops it on the way out, whatever happened.

CPU is percent of one core over a phase (200 % is the whole machine): the server's from
``/proc/<pid>/stat``, this process's (the load generators) from ``time.process_time``, and
everything else on the machine from ``/proc/stat``.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from bench._server import ConsoleProcess, start_console

SENDS_PER_MINUTE = 600
START_TIMEOUT_S = 60.0


def cpu_s(pid: int) -> float | None:
    """CPU seconds (user + system) used so far by process ``pid``; None off Linux."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = stat.rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def machine_busy_s() -> float | None:
    """CPU seconds all cores spent busy so far (everything but idle and iowait)."""
    try:
        line = Path("/proc/stat").read_text().splitlines()[0]
    except (OSError, IndexError):
        return None
    ticks = [int(x) for x in line.split()[1:9]]  # user nice system idle iowait irq softirq steal
    return (sum(ticks) - ticks[3] - ticks[4]) / os.sysconf("SC_CLK_TCK")


@dataclass
class CpuShare:
    """Percent of one core over a phase: the server, this process, and everything else."""

    server: float | None
    bench: float
    others: float | None

    def __str__(self) -> str:
        def pct(x: float | None) -> str:
            return "-" if x is None else f"{x:.0f}"

        return f"{pct(self.server)} / {pct(self.bench)} / {pct(self.others)} %"


class CpuMeter:
    """Measures a phase's :class:`CpuShare` from ``/proc`` and ``time.process_time``."""

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self._start = self._read()

    def _read(self) -> tuple[float, float | None, float, float | None]:
        return time.perf_counter(), cpu_s(self.pid), time.process_time(), machine_busy_s()

    def share(self) -> CpuShare:
        (w0, s0, b0, m0), (w1, s1, b1, m1) = self._start, self._read()
        wall = w1 - w0
        server = 100.0 * (s1 - s0) / wall if s0 is not None and s1 is not None else None
        bench = 100.0 * (b1 - b0) / wall
        others = None
        if server is not None and m0 is not None and m1 is not None:
            others = max(0.0, 100.0 * (m1 - m0) / wall - server - bench)
        return CpuShare(server, bench, others)


@contextlib.contextmanager
def console_server(workdir: Path, env: dict[str, str] | None = None) -> Iterator[ConsoleProcess]:
    """``nemesys console`` on a free loopback port, training mode; stopped on exit. ``env``:
    more of its environment (a fleet: ``NEMESYS_VEHICLES``)."""
    token = secrets.token_urlsafe(24)
    with start_console(
        workdir / "console.log",
        token,
        *("--target", "sim", "--db", str(workdir / "missions.sqlite3")),
        env={"NEMESYS_MAX_SENDS_PER_MINUTE": str(SENDS_PER_MINUTE), **(env or {})},
        timeout_s=START_TIMEOUT_S,
    ) as server:
        if server.token != token:
            raise RuntimeError("the console printed another token than it was given")
        with server.client() as http:
            if http.get("/api/session").json().get("mode") != "training":
                raise RuntimeError("the console did not start in training mode")
        yield server
