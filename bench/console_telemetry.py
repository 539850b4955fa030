"""``nemesys bench console``, measurement 3: many telemetry websocket clients, and the send
latency beside them.

The clients stand for other people's browsers, so they run in a child process (not on the
event loop of the operator's websocket that times the acknowledgements): each counts the
telemetry messages it gets in the window, the longest gap between two, and any error message
or close. Meanwhile sends are spread over the window (see :mod:`bench.console`).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import multiprocessing
import random
import statistics
import time
from dataclasses import dataclass
from typing import Any

from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed, WebSocketException

from bench._server import ConsoleProcess
from bench._timing import table, verdict
from bench.console_send import TARGET_EXCESS_MS, Sender, SendRun, send_spread
from bench.console_server import CpuMeter, CpuShare

TARGET_TELEMETRY_HZ = 10.0
MIN_TELEMETRY_HZ = 9.0
#: "No effect": median excess with the telemetry clients at most this much above without.
NO_EFFECT_MS = 10.0
WS_CLIENTS = 50


class TelemetryClient:
    """One page's websocket: counts telemetry in the window, notes errors and closes."""

    def __init__(self) -> None:
        self.settled = False  # connected, or given up
        self.counting = False
        self.messages = 0
        self.max_gap_s = 0.0
        self.errors: list[str] = []
        self._last: float | None = None

    def start_window(self, now: float) -> None:
        self.messages = 0
        self._last = now
        self.counting = True

    def end_window(self, now: float) -> None:
        if self._last is not None:
            self.max_gap_s = max(self.max_gap_s, now - self._last)
        self.counting = False

    async def run(self, url: str, stop: asyncio.Event) -> None:
        try:
            async with connect(url, open_timeout=30) as ws:
                self.settled = True
                reader = asyncio.create_task(self._read(ws))
                await stop.wait()
                reader.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await reader
        except (OSError, TimeoutError, WebSocketException) as err:
            self.errors.append(f"{type(err).__name__}: {err}")
        finally:
            self.settled = True

    async def _read(self, ws: ClientConnection) -> None:
        try:
            async for message in ws:
                now = time.perf_counter()
                doc = json.loads(message)
                kind = doc.get("type")
                # a fleet's vehicles come in one message a period: each vehicle's counts
                vehicles = len(doc["telemetry"]) if kind == "fleet_telemetry" else 1
                if kind in ("telemetry", "fleet_telemetry") and self.counting:
                    self.messages += vehicles
                    if self._last is not None:
                        self.max_gap_s = max(self.max_gap_s, now - self._last)
                    self._last = now
                elif kind == "error":
                    self.errors.append(f"error message: {doc.get('detail')}")
        except ConnectionClosed as err:
            self.errors.append(f"closed: {err}")
            return
        self.errors.append("closed by the server")


@dataclass
class TelemetryRun:
    rates_hz: list[float]
    max_gap_s: float
    errors: list[str]
    cpu: CpuShare
    sends: SendRun


#: Per-client telemetry rates (Hz), the longest gap (s) and every error, from the child.
TelemetryStats = tuple[list[float], float, list[str]]


async def _pages(url: str, clients: int, duration_s: float, ready: Any) -> TelemetryStats:
    """Run ``clients`` page websockets; signal ``ready`` once all are connected, then count
    telemetry over ``duration_s``."""
    stop = asyncio.Event()
    pages = [TelemetryClient() for _ in range(clients)]
    tasks = [asyncio.create_task(p.run(url, stop)) for p in pages]
    deadline = time.perf_counter() + 30.0
    while not all(p.settled for p in pages) and time.perf_counter() < deadline:
        await asyncio.sleep(0.05)
    await asyncio.sleep(0.5)  # every client past its first message
    ready.set()
    start = time.perf_counter()
    for p in pages:
        p.start_window(start)
    await asyncio.sleep(duration_s)
    end = time.perf_counter()
    for p in pages:
        p.end_window(end)
    stop.set()
    await asyncio.gather(*tasks)
    wall = end - start
    return (
        [p.messages / wall for p in pages],
        max(p.max_gap_s for p in pages),
        [e for p in pages for e in p.errors],
    )


def _pages_process(url: str, clients: int, duration_s: float, ready: Any, out: Any) -> None:
    """Child process: the telemetry clients are other people's browsers, so they run apart
    from the operator's (this process's) websocket that times the acknowledgements."""
    out.put(asyncio.run(_pages(url, clients, duration_s, ready)))


async def telemetry_load(
    server: ConsoleProcess, sender: Sender, clients: int, duration_s: float, sends: int, seed: int
) -> TelemetryRun:
    ctx = multiprocessing.get_context("spawn")
    ready, out = ctx.Event(), ctx.Queue()
    child = ctx.Process(
        target=_pages_process, args=(server.ws_url, clients, duration_s, ready, out), daemon=True
    )
    child.start()
    try:
        if not await asyncio.to_thread(ready.wait, 60.0):
            raise RuntimeError("the telemetry clients did not connect within 60 s")
        run = SendRun(f"delay 0 s, {clients} telemetry clients", 0.0)
        meter = CpuMeter(server.pid)
        await send_spread(sender, run, sends, duration_s, random.Random(seed))
        cpu = meter.share()
        rates, max_gap_s, errors = await asyncio.to_thread(out.get, True, duration_s + 60.0)
    finally:
        child.join(10)
        if child.is_alive():
            child.kill()
    return TelemetryRun(rates_hz=rates, max_gap_s=max_gap_s, errors=errors, cpu=cpu, sends=run)


def telemetry_table(t: TelemetryRun, base: SendRun) -> str:
    loaded = t.sends
    rmin, rmed = min(t.rates_hz), statistics.median(t.rates_hz)
    diff = loaded.median - base.median
    ratio = loaded.median / base.median if base.median > 0 else float("nan")
    rows = [
        [
            "telemetry per client, min",
            f"{rmin:.2f} Hz",
            f">= {MIN_TELEMETRY_HZ:g} Hz ({TARGET_TELEMETRY_HZ:g} Hz nominal)",
            verdict(rmin >= MIN_TELEMETRY_HZ),
        ],
        ["telemetry per client, median", f"{rmed:.2f} Hz", "", ""],
        ["longest gap between two telemetry messages", f"{t.max_gap_s * 1e3:.0f} ms", "", ""],
        ["errors and closes, all clients", str(len(t.errors)), "0", verdict(not t.errors)],
        [
            "send->ack excess median, with clients",
            f"{loaded.median:.1f} ms ({len(loaded.excess_ms)}/{loaded.sends} acked)",
            f"<= {TARGET_EXCESS_MS:g} ms",
            verdict(loaded.median <= TARGET_EXCESS_MS and not loaded.failures),
        ],
        [
            "send->ack excess median, without",
            f"{base.median:.1f} ms (before + after, {len(base.excess_ms)} sends)",
            "",
            "",
        ],
        [
            "with - without (medians)",
            f"{diff:+.1f} ms (ratio {ratio:.2f})",
            f"<= +{NO_EFFECT_MS:g} ms: no effect",
            verdict(diff <= NO_EFFECT_MS),
        ],
        [
            "send->ack excess p99, with / without",
            f"{loaded.p99:.1f} / {base.p99:.1f} ms",
            "",
            "",
        ],
        ["CPU server / bench / others", str(t.cpu), "", ""],
    ]
    return table(["case", "measured", "target", ""], rows)
