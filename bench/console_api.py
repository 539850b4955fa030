"""``nemesys bench console``, measurement 1: preview/encode latency under concurrent clients.

Each client is an asyncio task with its own ``httpx.AsyncClient``, POSTing ``/api/preview``
then ``/api/encode`` for every pattern at its defaults in turn, either back to back or one
pair per :data:`PAGE_DEBOUNCE_S` (the page's preview debounce); only the paced load is graded
against the targets, the back-to-back ones are references (see :mod:`bench.console`).
"""

from __future__ import annotations

import asyncio
import random
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import httpx

from bench._server import ConsoleProcess
from bench._timing import ms_cell, percentile, table, verdict
from bench.console_server import CpuMeter, CpuShare

TARGET_P50_MS = 5.0
TARGET_P99_MS = 25.0
API_CLIENTS = 20
#: The page's preview debounce (frontend/authoring.js): a typing operator's fastest rate.
PAGE_DEBOUNCE_S = 0.15


@dataclass
class ApiRun:
    """One load phase of preview/encode requests."""

    label: str
    latencies_ms: dict[str, list[float]]
    errors: int
    wall_s: float
    cpu: CpuShare
    #: One pair per client at the page's pace (graded against the targets), not back to back.
    paced: bool

    def both(self) -> list[float]:
        return [x for v in self.latencies_ms.values() for x in v]


def default_bodies(dictionary: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Every pattern at its defaults, as ``{pattern, params}`` request bodies."""
    return [
        {"pattern": p["name"], "params": {f["name"]: f["default"] for f in p["fields"]}}
        for p in dictionary
    ]


async def api_load(
    server: ConsoleProcess,
    bodies: Sequence[dict[str, Any]],
    *,
    label: str,
    clients: int,
    duration_s: float,
    interval_s: float = 0.0,
) -> ApiRun:
    """``clients`` tasks, each with its own connection, POST preview then encode for the
    patterns in turn for ``duration_s``; one pair per ``interval_s`` each (0: back to back)."""
    latencies: dict[str, list[float]] = {"preview": [], "encode": []}
    errors = 0
    opened = asyncio.Event()
    ready = 0
    timeout = httpx.Timeout(30.0)

    async def client(k: int) -> None:
        nonlocal errors, ready
        async with httpx.AsyncClient(base_url=server.base_url, timeout=timeout) as http:
            await http.get("/api/session")  # connect before the clock starts
            ready += 1
            if ready == clients:
                opened.set()
            await opened.wait()
            rng = random.Random(k)
            if interval_s:
                await asyncio.sleep(rng.uniform(0.0, interval_s))  # spread the phases
            deadline = time.perf_counter() + duration_s
            i = k
            while (start := time.perf_counter()) < deadline:
                body = bodies[i % len(bodies)]
                i += 1
                for kind in ("preview", "encode"):
                    t0 = time.perf_counter()
                    try:
                        r = await http.post(f"/api/{kind}", json=body)
                    except httpx.HTTPError:
                        errors += 1
                        continue
                    elapsed_ms = (time.perf_counter() - t0) * 1e3
                    if r.status_code == 200:
                        latencies[kind].append(elapsed_ms)
                    else:
                        errors += 1
                if interval_s:
                    await asyncio.sleep(max(0.0, start + interval_s - time.perf_counter()))

    meter = CpuMeter(server.pid)
    t0 = time.perf_counter()
    await asyncio.gather(*(client(k) for k in range(clients)))
    wall = time.perf_counter() - t0
    return ApiRun(label, latencies, errors, wall, meter.share(), paced=interval_s > 0)


def api_table(runs: Sequence[ApiRun]) -> str:
    rows = []
    for run in runs:
        # graded: 20 clients at the page's pace; a closed loop with no pause is a saturation
        # test (its latency is 20 / throughput), shown for reference
        graded = run.paced
        kinds = [("preview", run.latencies_ms["preview"]), ("encode", run.latencies_ms["encode"])]
        kinds.append(("both", run.both()))
        for kind, values in kinds:
            p50, p99 = percentile(values, 50), percentile(values, 99)
            target = f"<= {TARGET_P50_MS:g} / <= {TARGET_P99_MS:g}" if graded else "(reference)"
            ok = p50 <= TARGET_P50_MS and p99 <= TARGET_P99_MS
            rows.append(
                [
                    run.label if kind == "preview" else "",
                    kind,
                    str(len(values)),
                    f"{len(values) / run.wall_s:.0f}",
                    ms_cell(p50),
                    ms_cell(p99),
                    target,
                    verdict(ok) if graded else "",
                    str(run.errors) if kind == "both" else "",
                    str(run.cpu) if kind == "both" else "",
                ]
            )
    headers = [
        "load",
        "request",
        "count",
        "per s",
        "p50 ms",
        "p99 ms",
        "target p50 / p99 ms",
        "",
        "errors",
        "CPU server / bench / others",
    ]
    return table(headers, rows)
