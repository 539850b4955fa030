"""``nemesys bench relay``: send -> acknowledgement through the relay, beside a direct send on
the same machine (issue 24's figure).

Two ``nemesys console`` processes share one PostgreSQL mission log (``NEMESYS_DATABASE_URL``,
an empty database: the consoles make their tables): the ship in training, holding the
simulated vehicle's transmitter (the emulated channel's delay set to 0, the rate limit
raised), and the shore with no transmitter (``NEMESYS_TARGET=relay``). In rounds, the ship in
control sends :data:`ROUND` circles itself (direct), then hands control to the shore, which
sends :data:`ROUND` through the relay (its checks, the outbox row, the notification, the ship's
claim, checks and record, the transmission), and takes it back: both series on the same
machine, interleaved, so a noisy neighbour slows both alike.

A send's time is the operator's: from the ``POST /api/commands`` on the sending console to
its own page's ``/ws`` telling it the command is ``acknowledged`` (on the shore that message
comes through the live sync: the ship's commit, the notification, the shore's re-read). Also
the ``POST`` -> answer (202) time: on the shore it waits for the ship's decision.

The figure: p50 and p99 of each, their ratio, and the relay's cost (relay p50 - direct p50)
beside the target: under 1 s (the issue's sync bound, which the relay crosses twice: the row
to the ship, the record back).
"""

from __future__ import annotations

import asyncio
import random
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Final, TextIO

import httpx

from backend.mission_log.database import masked
from bench._server import ConsoleProcess, shared_log_url, start_console
from bench._timing import ms_cell, percentile, table, verdict
from bench.console_send import ack_watcher

TOKEN: Final = "relay-bench-token-0123456789abcdef"
AUTH: Final = {"Authorization": f"Bearer {TOKEN}"}
ENV: Final = {"NEMESYS_MAX_SENDS_PER_MINUTE": "600", "NO_PROXY": "127.0.0.1,localhost"}
#: Sends of each kind per run (``--quick``: fewer), in rounds of :data:`ROUND` each.
SENDS: Final = 60
QUICK_SENDS: Final = 10
ROUND: Final = 5
#: The relay's cost the figure is judged by (ms): relay p50 - direct p50.
TARGET_OVERHEAD_MS: Final = 1000.0
ACK_TIMEOUT_S: Final = 15.0
CIRCLE: Final = {"speed": 0.18, "depth": 3, "direction": "cw"}


@dataclass
class Series:
    """One kind of send: per acknowledged send, POST -> 202 and POST -> acknowledged (ms)."""

    label: str
    answer_ms: list[float] = field(default_factory=list)
    ack_ms: list[float] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)


async def _send(
    console: ConsoleProcess, series: Series, radius: float, loop: asyncio.AbstractEventLoop
) -> None:
    async with (
        ack_watcher(console.ws_url) as watcher,
        httpx.AsyncClient(
            base_url=console.base_url, headers=AUTH, timeout=30.0, trust_env=False
        ) as http,
    ):
        body = {"pattern": "circle", "params": {**CIRCLE, "radius": radius}}
        t0 = loop.time()
        r = await http.post("/api/commands", json=body)
        t_answer = loop.time()
        if r.status_code != 202:
            series.failures.append(f"HTTP {r.status_code}: {r.text[:200]}")
            return
        state, _t = await watcher.wait(int(r.json()["id"]), ACK_TIMEOUT_S)
        t_final = loop.time()
        if state != "acknowledged":
            series.failures.append(state)
            return
        series.answer_ms.append((t_answer - t0) * 1e3)
        series.ack_ms.append((t_final - t0) * 1e3)


async def _act(console: ConsoleProcess, action: str) -> str:
    async with httpx.AsyncClient(base_url=console.base_url, trust_env=False) as http:
        r = await http.post("/api/control", json={"action": action}, headers=AUTH)
        r.raise_for_status()
        return str(r.json()["outcome"])


async def _hand_over(asker: ConsoleProcess, owner: ConsoleProcess) -> None:
    if await _act(asker, "request") != "pending" or await _act(owner, "grant") != "granted":
        raise RuntimeError("control could not be handed over")


async def _drive(ship: ConsoleProcess, shore: ConsoleProcess, sends: int) -> list[Series]:
    direct, relay = Series("direct (ship)"), Series("relay (shore -> ship)")
    loop = asyncio.get_running_loop()
    rng = random.Random(24)
    async with httpx.AsyncClient(base_url=ship.base_url, headers=AUTH, trust_env=False) as http:
        channel = (await http.get("/api/training")).json()["channel"]
        r = await http.put("/api/training/channel", json={**channel, "delay_s": 0.0})
        r.raise_for_status()
    count = 0
    while len(direct.ack_ms) + len(direct.failures) < sends:
        for console, series in ((ship, direct), (shore, relay)):
            if console is shore:
                await _hand_over(shore, ship)
            for _ in range(ROUND):
                count += 1
                await _send(console, series, 4.0 if count % 2 else 5.0, loop)
                await asyncio.sleep(rng.uniform(0.1, 0.3))
            if console is shore:
                await _hand_over(ship, shore)
    return [direct, relay]


def _start(workdir: Path, name: str, url: str, **env: str) -> ConsoleProcess:
    more = {**ENV, "NEMESYS_DATABASE_URL": url, "NEMESYS_CONSOLE_NAME": name, **env}
    return start_console(
        workdir / f"{name}.log", TOKEN, "--db", str(workdir / f"{name}.sqlite3"), env=more
    )


def measure(url: str, sends: int, workdir: Path) -> list[Series]:
    """The ship (started first: in control) and the shore on ``url``; ``sends`` of each."""
    with (
        _start(workdir, "ship", url) as ship,
        _start(workdir, "shore", url, NEMESYS_TARGET="relay") as shore,
    ):
        return asyncio.run(_drive(ship, shore, sends))


def overhead_ms(direct: Series, relay: Series) -> float:
    return percentile(relay.ack_ms, 50) - percentile(direct.ack_ms, 50)


def format_report(runs: Sequence[Series], where: str) -> str:
    direct, relay = runs
    rows = []
    for name, pick in (("POST -> 202", "answer_ms"), ("send -> ack", "ack_ms")):
        d, r = getattr(direct, pick), getattr(relay, pick)
        for q in (50, 99):
            ratio = percentile(r, q) / percentile(d, q) if d else float("nan")
            rows.append(
                [
                    f"{name} p{q}",
                    ms_cell(percentile(d, q)),
                    ms_cell(percentile(r, q)),
                    f"{ratio:.2f}x",
                    "-",
                    "-",
                ]
            )
    cost = overhead_ms(direct, relay)
    ok = cost < TARGET_OVERHEAD_MS and not direct.failures and not relay.failures
    rows.append(
        [
            "relay's cost (ack p50)",
            "-",
            ms_cell(cost),
            "-",
            f"< {TARGET_OVERHEAD_MS:.0f}",
            verdict(ok),
        ]
    )
    head = (
        f"Send -> ack through the relay compared with a direct send on the same machine "
        f"({where}; training vehicle, channel delay 0): {len(direct.ack_ms)} direct and "
        f"{len(relay.ack_ms)} relayed acknowledged sends, interleaved in rounds of {ROUND}\n"
    )
    failed = [f"{s.label}: {f}" for s in runs for f in s.failures]
    tail = "".join(f"failed: {f}\n" for f in failed)
    headers = ["figure", "direct ms", "relay ms", "relay/direct", "target ms", "verdict"]
    return head + table(headers, rows) + "\n" + tail


def met(runs: Sequence[Series]) -> bool:
    direct, relay = runs
    failed = direct.failures or relay.failures
    return not failed and overhead_ms(direct, relay) < TARGET_OVERHEAD_MS


def run(out: TextIO, *, quick: bool = False) -> int:
    url = shared_log_url("relay", out)
    if url is None:
        return 2
    with tempfile.TemporaryDirectory(prefix="nemesys-relay-") as tmp:
        runs = measure(url, QUICK_SENDS if quick else SENDS, Path(tmp))
    out.write(format_report(runs, masked(url)))
    return 0 if met(runs) else 1
