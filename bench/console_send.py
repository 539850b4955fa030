"""``nemesys bench console``, measurement 2: send -> acknowledgement in training mode.

:class:`Sender` POSTs ``/api/commands`` with the token, circles of radius 4 m and 5 m in turn
(never a duplicate), and :class:`AckWatcher` reads ``/ws`` for the command's ``transmitted``
and final states. Each acknowledged send's excess is the time from the POST to the
``acknowledged`` message minus the frame's airtime and the channel's delay (see
:mod:`bench.console`).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import random
import statistics
import time
from collections.abc import AsyncIterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import httpx
from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed

from backend.mission_log.store import FINAL_STATES
from bench._timing import ms_cell, percentile, table, verdict

TARGET_EXCESS_MS = 50.0
CHANNEL_DELAY_S = 0.5
ACK_TIMEOUT_S = 15.0


class AckWatcher:
    """Reads ``/ws`` and notes when each command was reported transmitted and when it reached
    a final state (perf_counter times)."""

    def __init__(self) -> None:
        self._final: dict[int, asyncio.Future[tuple[str, float]]] = {}
        self.transmitted: dict[int, float] = {}

    def _future(self, command_id: int) -> asyncio.Future[tuple[str, float]]:
        fut = self._final.get(command_id)
        if fut is None:
            fut = asyncio.get_running_loop().create_future()
            self._final[command_id] = fut
        return fut

    async def read(self, ws: ClientConnection) -> None:
        async for message in ws:
            now = time.perf_counter()
            doc = json.loads(message)
            if doc.get("type") != "command":
                continue
            record = doc["command"]
            if record.get("state") == "transmitted":
                self.transmitted.setdefault(int(record["id"]), now)
            elif record.get("state") in FINAL_STATES:
                fut = self._future(int(record["id"]))
                if not fut.done():
                    fut.set_result((record["state"], now))

    async def wait(self, command_id: int, timeout_s: float) -> tuple[str, float]:
        """The command's final state and when it was reported; ("no answer", now) on timeout."""
        try:
            return await asyncio.wait_for(asyncio.shield(self._future(command_id)), timeout_s)
        except TimeoutError:
            return "no answer", time.perf_counter()


@contextlib.asynccontextmanager
async def ack_watcher(ws_url: str) -> AsyncIterator[AckWatcher]:
    async with connect(ws_url) as ws:
        watcher = AckWatcher()
        task = asyncio.create_task(watcher.read(ws))
        try:
            yield watcher
        finally:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError, ConnectionClosed):
                await task


@dataclass
class SendRun:
    """One series of sends: per acknowledged send, the excess beyond airtime + delay."""

    label: str
    delay_s: float
    excess_ms: list[float] = field(default_factory=list)
    post_ms: list[float] = field(default_factory=list)
    transmitted_ms: list[float] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)

    @property
    def sends(self) -> int:
        return len(self.excess_ms) + len(self.failures)

    @property
    def median(self) -> float:
        return statistics.median(self.excess_ms) if self.excess_ms else float("nan")

    @property
    def p99(self) -> float:
        return percentile(self.excess_ms, 99)


class Sender:
    """Sends circles of radius 4 m and 5 m in turn (never a duplicate of the active one); to
    a fleet's ``vehicles`` in turn, each vehicle's radius in turn."""

    def __init__(
        self,
        http: httpx.AsyncClient,
        watcher: AckWatcher,
        circle: dict[str, Any],
        airtime_s: float,
        vehicles: Sequence[str] = (),
    ) -> None:
        self.http = http
        self.watcher = watcher
        self.circle = circle
        self.airtime_s = airtime_s
        self.vehicles = list(vehicles)
        self.count = 0

    async def send(self, run: SendRun) -> None:
        n = max(1, len(self.vehicles))
        radius = 4.0 if (self.count // n) % 2 == 0 else 5.0
        body: dict[str, Any] = {"pattern": "circle", "params": {**self.circle, "radius": radius}}
        if self.vehicles:
            body["vehicle"] = self.vehicles[self.count % n]
        self.count += 1
        t0 = time.perf_counter()
        r = await self.http.post("/api/commands", json=body)
        t_post = time.perf_counter()
        if r.status_code != 202:
            run.failures.append(f"HTTP {r.status_code}: {r.text[:200]}")
            return
        command_id = int(r.json()["id"])
        state, t_final = await self.watcher.wait(command_id, ACK_TIMEOUT_S + run.delay_s)
        if state != "acknowledged":
            run.failures.append(state)
            return
        run.post_ms.append((t_post - t0) * 1e3)
        if (t_sent := self.watcher.transmitted.get(command_id)) is not None:
            run.transmitted_ms.append((t_sent - t0) * 1e3)
        run.excess_ms.append((t_final - t0 - self.airtime_s - run.delay_s) * 1e3)


async def send_series(sender: Sender, run: SendRun, count: int, rng: random.Random) -> SendRun:
    """``count`` sends one after another, 0.1-0.3 s apart (random phase against the tick)."""
    for _ in range(count):
        await sender.send(run)
        await asyncio.sleep(rng.uniform(0.1, 0.3))
    return run


async def send_spread(
    sender: Sender, run: SendRun, count: int, duration_s: float, rng: random.Random
) -> SendRun:
    """``count`` sends spread evenly over ``duration_s`` (each +-0.05 s at random)."""
    start = time.perf_counter()
    step = duration_s / count
    for k in range(count):
        at = start + (k + 0.25) * step + rng.uniform(-0.05, 0.05)
        await asyncio.sleep(max(0.0, at - time.perf_counter()))
        await sender.send(run)
    return run


async def set_delay(http: httpx.AsyncClient, delay_s: float) -> None:
    """The emulated channel's delay (the rest of its settings as they are)."""
    channel = (await http.get("/api/training")).json()["channel"]
    r = await http.put("/api/training/channel", json={**channel, "delay_s": delay_s})
    r.raise_for_status()


def send_table(runs: Sequence[SendRun]) -> str:
    rows = []
    for run in runs:
        rows.append(
            [
                run.label,
                f"{len(run.excess_ms)}/{run.sends}",
                ms_cell(percentile(run.post_ms, 50)),
                ms_cell(percentile(run.transmitted_ms, 50)),
                ms_cell(run.median),
                ms_cell(run.p99),
                ms_cell(max(run.excess_ms, default=float("nan"))),
                f"<= {TARGET_EXCESS_MS:g}",
                verdict(run.median <= TARGET_EXCESS_MS and not run.failures),
            ]
        )
    headers = [
        "channel",
        "acked",
        "POST->202 p50 ms",
        "->transmitted p50 ms",
        "excess median ms",
        "excess p99 ms",
        "excess max ms",
        "target median ms",
        "",
    ]
    return table(headers, rows)
