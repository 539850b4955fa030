"""``nemesys bench fleet_cost``: what 20 telemetry pages cost the operator, with 1 vehicle
and with a fleet of 10, as ratios measured in one run.

Two training consoles in turn (``nemesys console`` subprocesses, as ``nemesys bench
console`` starts them): the single vehicle, and a fleet of 10 (``NEMESYS_VEHICLES=10``: each
send and preview names its vehicle, the sends to the vehicles in turn). Each console is
measured three times: with no page, with 20 telemetry pages connected (a child process, as
other people's browsers; with 10 vehicles each page gets every vehicle's telemetry, 10 a
second each, in one ``fleet_telemetry`` message a period), and with no page again; the two
unloaded phases pooled are the reference, so a drift of the machine's background load over
the run cancels. Each phase:

- send -> acknowledgement (:mod:`bench.console_send`): sends 0.1-0.3 s apart, the excess
  beyond the frame's airtime (an addressed frame's with a fleet); target: the median with 20
  pages at most 10 ms above the median without;
- a paced preview: one page POSTing ``/api/preview`` for every pattern at its defaults in
  turn, one per 150 ms (the page's debounce); target: with 20 pages, p50 at most 1.2x and
  p99 at most 3x those without.

Beside them, each phase's telemetry rate per page and the CPU (:mod:`bench.console_server`).
Timings are single runs on a shared machine: read the medians; the p99s are the tail.
"""

from __future__ import annotations

import asyncio
import multiprocessing
import random
import statistics
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

import httpx

from bench._server import ConsoleProcess
from bench._timing import ms_cell, percentile, table, verdict
from bench.console_api import PAGE_DEBOUNCE_S, default_bodies
from bench.console_send import Sender, SendRun, ack_watcher, send_series
from bench.console_server import CpuMeter, CpuShare, console_server
from bench.console_telemetry import NO_EFFECT_MS, TelemetryClient
from codec import ADDRESSED_FRAME_BITS, FRAME_BITS

PAGES = 20
FLEET = 10
#: With the pages, a paced preview's p50 and p99 at most these times the unloaded ones.
TARGET_P50_RATIO = 1.2
TARGET_P99_RATIO = 3.0
#: How long a console's vehicles may take to be heard, and the pages to connect.
READY_TIMEOUT_S = 60.0


@dataclass(frozen=True)
class Sizes:
    """Sends per phase, and seconds of paced preview per phase."""

    sends: int
    preview_s: float


QUICK = Sizes(sends=10, preview_s=3.0)
FULL = Sizes(sends=30, preview_s=15.0)


@dataclass
class Phase:
    """One phase of a console: its pages, sends, previews and what the pages got."""

    pages: int
    sends: SendRun
    preview_ms: list[float] = field(default_factory=list)
    preview_errors: list[str] = field(default_factory=list)
    #: Telemetry messages a second each page got (every vehicle's), and the pages' errors.
    page_hz: list[float] = field(default_factory=list)
    page_errors: list[str] = field(default_factory=list)
    cpu: CpuShare | None = None


@dataclass
class ConsoleRun:
    """A console's three phases: no page, ``PAGES`` pages, no page again."""

    vehicles: int
    phases: list[Phase]

    @property
    def loaded(self) -> Phase:
        return self.phases[1]

    def unloaded(self) -> tuple[SendRun, list[float]]:
        """The sends and previews of the phases with no page, pooled."""
        quiet = [p for p in self.phases if not p.pages]
        sends = SendRun("no page", 0.0, [x for p in quiet for x in p.sends.excess_ms])
        return sends, [x for p in quiet for x in p.preview_ms]


async def _pages_until(url: str, clients: int, ready: Any, stop: Any) -> tuple[Any, ...]:
    """``clients`` page websockets; ``ready`` once all are connected, counting telemetry
    until ``stop``."""
    done = asyncio.Event()
    pages = [TelemetryClient() for _ in range(clients)]
    tasks = [asyncio.create_task(p.run(url, done)) for p in pages]
    deadline = time.perf_counter() + READY_TIMEOUT_S
    while not all(p.settled for p in pages) and time.perf_counter() < deadline:
        await asyncio.sleep(0.05)
    await asyncio.sleep(0.5)  # every page past its first messages
    start = time.perf_counter()
    for p in pages:
        p.start_window(start)
    ready.set()
    await asyncio.to_thread(stop.wait)
    end = time.perf_counter()
    for p in pages:
        p.end_window(end)
    done.set()
    await asyncio.gather(*tasks)
    return [p.messages / (end - start) for p in pages], [e for p in pages for e in p.errors]


def _pages_process(url: str, clients: int, ready: Any, stop: Any, out: Any) -> None:
    """Child process: the pages are other people's browsers, apart from this event loop."""
    out.put(asyncio.run(_pages_until(url, clients, ready, stop)))


async def paced_preview(
    base_url: str, bodies: Sequence[dict[str, Any]], duration_s: float, phase: Phase
) -> None:
    """One page's previews, one per :data:`PAGE_DEBOUNCE_S`, every pattern in turn."""
    async with httpx.AsyncClient(base_url=base_url, timeout=30.0, trust_env=False) as http:
        await http.get("/api/session")  # connected before the clock starts
        deadline = time.perf_counter() + duration_s
        i = 0
        while (start := time.perf_counter()) < deadline:
            body = bodies[i % len(bodies)]
            i += 1
            try:
                r = await http.post("/api/preview", json=body)
            except httpx.HTTPError as err:
                phase.preview_errors.append(f"{type(err).__name__}: {err}")
            else:
                if r.status_code == 200:
                    phase.preview_ms.append((time.perf_counter() - start) * 1e3)
                else:
                    phase.preview_errors.append(f"HTTP {r.status_code}: {r.text[:200]}")
            await asyncio.sleep(max(0.0, start + PAGE_DEBOUNCE_S - time.perf_counter()))


async def measure_phase(
    server: ConsoleProcess,
    sender: Sender,
    bodies: Sequence[dict[str, Any]],
    pages: int,
    sizes: Sizes,
    rng: random.Random,
) -> Phase:
    phase = Phase(pages, SendRun(f"{pages} pages", 0.0))
    ctx = multiprocessing.get_context("spawn")
    ready, stop, out = ctx.Event(), ctx.Event(), ctx.Queue()
    child = None
    if pages:
        child = ctx.Process(
            target=_pages_process, args=(server.ws_url, pages, ready, stop, out), daemon=True
        )
        child.start()
    try:
        if child is not None and not await asyncio.to_thread(ready.wait, READY_TIMEOUT_S):
            raise RuntimeError(f"the {pages} pages did not connect within {READY_TIMEOUT_S:g} s")
        meter = CpuMeter(server.pid)
        await send_series(sender, phase.sends, sizes.sends, rng)
        await paced_preview(server.base_url, bodies, sizes.preview_s, phase)
        phase.cpu = meter.share()
        if child is not None:
            stop.set()
            phase.page_hz, phase.page_errors = await asyncio.to_thread(
                out.get, True, READY_TIMEOUT_S
            )
    finally:
        if child is not None:
            stop.set()
            child.join(10)
            if child.is_alive():
                child.kill()
    return phase


async def _heard(http: httpx.AsyncClient, names: Sequence[str]) -> None:
    """Wait until every vehicle of the fleet has reported a pose."""
    deadline = time.perf_counter() + READY_TIMEOUT_S
    while time.perf_counter() < deadline:
        views = (await http.get("/api/vehicles")).json()
        if all(v.get("pose") for v in views if v["name"] in names) and len(views) >= len(names):
            return
        await asyncio.sleep(0.2)
    raise RuntimeError(f"the fleet's vehicles were not all heard within {READY_TIMEOUT_S:g} s")


async def measure_console(server: ConsoleProcess, vehicles: int, sizes: Sizes) -> ConsoleRun:
    headers = {"Authorization": f"Bearer {server.token}"}
    async with (
        httpx.AsyncClient(
            base_url=server.base_url, headers=headers, timeout=30.0, trust_env=False
        ) as http,
        ack_watcher(server.ws_url) as watcher,
    ):
        names = [f"auv{i}" for i in range(1, vehicles + 1)] if vehicles > 1 else []
        if names:
            await _heard(http, names)
        bodies = default_bodies((await http.get("/api/dictionary")).json())
        # at a speed the training vehicle can fly: faster is a top-speed violation (409)
        circle = {**next(b["params"] for b in bodies if b["pattern"] == "circle"), "speed": 0.18}
        channel = (await http.get("/api/training")).json()["channel"]
        bits = ADDRESSED_FRAME_BITS if names else FRAME_BITS
        sender = Sender(http, watcher, circle, bits / float(channel["bitrate_bps"]), names)
        warm = SendRun("warm-up", 0.0)
        for _ in range(max(1, len(names))):  # a plan for each to join from, as previews do
            await sender.send(warm)
        if warm.failures:
            raise RuntimeError(f"a warm-up send was not acknowledged: {warm.failures[0]}")
        previews = [
            {**b, "vehicle": names[i % len(names)]} if names else b for i, b in enumerate(bodies)
        ]
        rng = random.Random(vehicles)
        phases = [
            await measure_phase(server, sender, previews, pages, sizes, rng)
            for pages in (0, PAGES, 0)
        ]
    return ConsoleRun(vehicles, phases)


def _ratio(a: float, b: float) -> float:
    return a / b if b > 0 else float("nan")


def cost_table(runs: Sequence[ConsoleRun]) -> str:
    """The graded figures: with the pages against without, each console."""
    rows = []
    for run in runs:
        base_sends, base_preview = run.unloaded()
        loaded = run.loaded
        name = f"{run.vehicles} vehicle{'s' if run.vehicles > 1 else ''}"
        diff = loaded.sends.median - base_sends.median
        rows.append(
            [
                name,
                "send->ack excess median ms",
                ms_cell(base_sends.median),
                ms_cell(loaded.sends.median),
                f"{diff:+.1f} ms ({_ratio(loaded.sends.median, base_sends.median):.2f}x)",
                f"<= +{NO_EFFECT_MS:g} ms",
                verdict(diff <= NO_EFFECT_MS and not loaded.sends.failures),
            ]
        )
        for q, target in ((50, TARGET_P50_RATIO), (99, TARGET_P99_RATIO)):
            without = percentile(base_preview, q)
            with_pages = percentile(loaded.preview_ms, q)
            ratio = _ratio(with_pages, without)
            rows.append(
                [
                    "",
                    f"preview p{q} ms",
                    ms_cell(without),
                    ms_cell(with_pages),
                    f"{ratio:.2f}x",
                    f"<= {target:g}x",
                    verdict(ratio <= target and not loaded.preview_errors),
                ]
            )
    headers = ["console", "figure", "0 pages", f"{PAGES} pages", "ratio", "target", ""]
    return table(headers, rows)


def phase_table(runs: Sequence[ConsoleRun]) -> str:
    """Each phase as measured: counts, telemetry per page, errors and CPU."""
    rows = []
    for run in runs:
        for k, p in enumerate(run.phases):
            when = ("before", "with", "after")[k]
            rows.append(
                [
                    f"{run.vehicles} vehicle{'s' if run.vehicles > 1 else ''}" if k == 0 else "",
                    f"{p.pages} pages ({when})",
                    f"{len(p.sends.excess_ms)}/{p.sends.sends}",
                    ms_cell(p.sends.p99),
                    f"{len(p.preview_ms)}",
                    f"{statistics.median(p.page_hz):.1f}" if p.page_hz else "-",
                    f"{min(p.page_hz):.1f}" if p.page_hz else "-",
                    str(len(p.sends.failures) + len(p.preview_errors) + len(p.page_errors)),
                    str(p.cpu) if p.cpu else "-",
                ]
            )
    headers = [
        "console",
        "phase",
        "acked",
        "excess p99 ms",
        "previews",
        "telemetry/page Hz p50",
        "min",
        "errors",
        "CPU server / bench / others",
    ]
    return table(headers, rows)


def run(out: TextIO, quick: bool = False, sizes: Sizes | None = None) -> int:
    """Measure both consoles and print the tables; ``sizes`` (the tests') overrides ``quick``."""
    sizes = sizes or (QUICK if quick else FULL)
    runs = []
    for vehicles in (1, FLEET):
        env = {"NEMESYS_VEHICLES": str(vehicles)} if vehicles > 1 else {}
        with (
            tempfile.TemporaryDirectory(prefix="nemesys-bench-fleet-") as tmp,
            console_server(Path(tmp), env) as server,
        ):
            out.write(f"Console with {vehicles} vehicle(s): pid {server.pid}, {server.base_url}\n")
            out.flush()
            runs.append(asyncio.run(measure_console(server, vehicles, sizes)))
    out.write(
        f"\nWith {PAGES} telemetry pages against none (no page: before + after pooled); "
        f"{sizes.sends} sends and {sizes.preview_s:g} s of previews (one per "
        f"{PAGE_DEBOUNCE_S * 1e3:.0f} ms) per phase\n\n"
    )
    out.write(cost_table(runs) + "\n\n")
    out.write(phase_table(runs) + "\n")
    for r in runs:
        for p in r.phases:
            errors = [*p.sends.failures, *p.preview_errors, *p.page_errors]
            if errors:
                out.write(f"\n{r.vehicles} vehicle(s), {p.pages} pages: " + "; ".join(errors[:3]))
    return 0
