"""``nemesys bench console``: the console's API and live latencies against a real server.

The server is ``nemesys console`` itself, started as a subprocess (training mode: the
simulated vehicle behind its rosbridge, the viser view on, a throw-away SQLite log, a random
operator token, the send rate limit raised to 600 a minute so it never interferes) on a free
loopback port; the URL it prints is parsed and ``/api/session`` polled until it answers. The
load generators run in this process on asyncio, so they compete with the server for the
machine's cores as a browser on the same machine would. Every phase is timed on this side of
the socket: what an operator's page would see.

1. Preview/encode latency under 20 concurrent clients (``bench/console_api.py``): 20 asyncio
   tasks, each with its own ``httpx.AsyncClient``, each POSTing ``/api/preview`` then
   ``/api/encode`` for every pattern at its defaults (from ``/api/dictionary``) in turn, one
   pair per 150 ms each (the page's preview debounce: 20 operators typing without pause, ~270
   requests/s), for a fixed time (quick 3 s, full 15 s): p50 and p99 of each request kind and
   of both together (target p50 <= 5 ms, p99 <= 25 ms). The preview also draws the path in the
   viser view (off the request path, latest wins). Beside it, for reading the figures: one
   client back to back (the unloaded latency) and 20 clients back to back with no pause, a
   saturation test: a closed loop measures queueing as much as work, its latency is about 20 /
   throughput (Little's law), so it shows the server's capacity, not the latency a client sees.
2. Send -> acknowledgement in training mode, beyond the emulated channel
   (``bench/console_send.py``): POST ``/api/commands`` with the token, alternating circle
   radius 4 m and 5 m (never a duplicate), timed from the POST to the ``/ws`` websocket's
   ``command`` message with state ``acknowledged`` for that id, minus the frame's airtime (100
   bits at the channel's bit rate) and the channel's delay. Sends are spaced 0.1-0.3 s apart at
   random so they sample every phase of the simulator's 20 ms clock tick. 30 sends (quick 10)
   per series: first with ``delay_s`` 0.5 s (simulated seconds, time scale 1) to show the delay
   is what is subtracted, then with the default delay (0 s) right before and right after
   measurement 3. Median and p99 of the excess (target: median <= 50 ms). Beside it, the POST's
   own time (to its 202) and the time to the ``transmitted`` message; the rest is the rosbridge
   hop, the wait for the simulator's next 20 ms clock tick (10 ms on average) and the
   acknowledgement's way back (the log write, then ``/ws``).
3. 50 telemetry websocket clients for 60 s (quick 10 s; ``bench/console_telemetry.py``), in a
   child process (they stand for other people's browsers, so they do not share an event loop
   with the operator's websocket that times the acknowledgements): each counts the telemetry
   messages it gets in the window (the hub sends about 10 a second, latest wins), the longest
   gap between two, and any error message or close. Meanwhile measurement 2 runs again, its
   sends spread over the window. Targets: no errors, every client >= 9 Hz, and no effect on the
   send latency, defined as: median excess with the 50 clients <= median without + 10 ms, where
   "without" pools the series right before and right after (so a drift of the machine's
   background load over the window cancels); the ratio of the medians is shown beside it.

4. Prediction (``bench/console_predict.py``): ``POST /api/predict`` for a 10-minute horizon
   (a repeating circle: the whole 600 s simulated), back to back, p50 and p99 (target p50
   <= 1.5 s, p99 <= 3 s), with one page previewing at its pace meanwhile (the preview
   targets).

CPU (``bench/console_server.py``, with the server) is shown as percent of one core over each
phase (200 % is the whole machine): the server's from ``/proc/<pid>/stat``, this process's (the
load generators) from ``time.process_time``, and everything else on the machine from
``/proc/stat``. When the server and the generators together are well under 200 % while the
requests queue, the cores were busy with other work: read such a run as noise, not as the
console's cost. Timings are single runs on a shared, noisy machine: read the medians, and the
p99s as the tail they are.
"""

from __future__ import annotations

import asyncio
import os
import random
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

import httpx

from bench._server import ConsoleProcess
from bench.console_api import (
    API_CLIENTS,
    PAGE_DEBOUNCE_S,
    TARGET_P50_MS,
    TARGET_P99_MS,
    ApiRun,
    api_load,
    api_table,
    default_bodies,
)
from bench.console_predict import PredictRun, predict_load, predict_table
from bench.console_send import (
    ACK_TIMEOUT_S,
    CHANNEL_DELAY_S,
    TARGET_EXCESS_MS,
    AckWatcher,
    Sender,
    SendRun,
    ack_watcher,
    send_series,
    send_spread,
    send_table,
    set_delay,
)
from bench.console_server import (
    SENDS_PER_MINUTE,
    START_TIMEOUT_S,
    CpuMeter,
    CpuShare,
    console_server,
    cpu_s,
    machine_busy_s,
)
from bench.console_telemetry import (
    MIN_TELEMETRY_HZ,
    NO_EFFECT_MS,
    TARGET_TELEMETRY_HZ,
    WS_CLIENTS,
    TelemetryClient,
    TelemetryRun,
    TelemetryStats,
    telemetry_load,
    telemetry_table,
)
from codec import FRAME_BITS

# The phases live in bench.console_{server,api,send,telemetry,predict}; their names are
# re-exported here.
__all__ = [
    "ACK_TIMEOUT_S",
    "API_CLIENTS",
    "CHANNEL_DELAY_S",
    "FULL",
    "MIN_TELEMETRY_HZ",
    "NO_EFFECT_MS",
    "PAGE_DEBOUNCE_S",
    "QUICK",
    "SENDS_PER_MINUTE",
    "START_TIMEOUT_S",
    "TARGET_EXCESS_MS",
    "TARGET_P50_MS",
    "TARGET_P99_MS",
    "TARGET_TELEMETRY_HZ",
    "WS_CLIENTS",
    "AckWatcher",
    "ApiRun",
    "CpuMeter",
    "CpuShare",
    "PredictRun",
    "Results",
    "SendRun",
    "Sender",
    "Sizes",
    "TelemetryClient",
    "TelemetryRun",
    "TelemetryStats",
    "ack_watcher",
    "api_load",
    "api_table",
    "console_server",
    "cpu_s",
    "default_bodies",
    "machine_busy_s",
    "measure",
    "predict_load",
    "predict_table",
    "run",
    "send_series",
    "send_spread",
    "send_table",
    "set_delay",
    "telemetry_load",
    "telemetry_table",
]


@dataclass(frozen=True)
class Sizes:
    """Seconds per preview/encode load (a third for the one client), sends per series, and
    seconds of the telemetry clients."""

    api_s: float
    sends: int
    telemetry_s: float
    predictions: int


QUICK = Sizes(api_s=3.0, sends=10, telemetry_s=10.0, predictions=3)
FULL = Sizes(api_s=15.0, sends=30, telemetry_s=60.0, predictions=10)


@dataclass
class Results:
    sizes: Sizes
    api: list[ApiRun]
    sends: list[SendRun]
    telemetry: TelemetryRun
    airtime_ms: float
    predict: PredictRun


async def measure(server: ConsoleProcess, sizes: Sizes) -> Results:
    api_s, sends = sizes.api_s, sizes.sends
    rng = random.Random(1)
    headers = {"Authorization": f"Bearer {server.token}"}
    async with (
        httpx.AsyncClient(base_url=server.base_url, headers=headers, timeout=30.0) as http,
        ack_watcher(server.ws_url) as watcher,
    ):
        dictionary = (await http.get("/api/dictionary")).json()
        bodies = default_bodies(dictionary)
        # at a speed the training vehicle can fly: faster is a top-speed violation (409)
        circle = {**next(b["params"] for b in bodies if b["pattern"] == "circle"), "speed": 0.18}
        channel = (await http.get("/api/training")).json()["channel"]
        airtime = FRAME_BITS / float(channel["bitrate_bps"])
        sender = Sender(http, watcher, circle, airtime)
        warm = SendRun("warm-up", 0.0)
        await sender.send(warm)  # a plan to join from: previews then carry the join and diff
        if warm.failures:
            raise RuntimeError(f"the warm-up send was not acknowledged: {warm.failures[0]}")

        api = [
            await api_load(
                server,
                bodies,
                label="1 client, back to back (unloaded reference)",
                clients=1,
                duration_s=api_s / 3,
            ),
            await api_load(
                server,
                bodies,
                label=f"{API_CLIENTS} clients, back to back",
                clients=API_CLIENTS,
                duration_s=api_s,
            ),
            await api_load(
                server,
                bodies,
                label=f"{API_CLIENTS} clients, 1 pair / {PAGE_DEBOUNCE_S * 1e3:.0f} ms each",
                clients=API_CLIENTS,
                duration_s=api_s,
                interval_s=PAGE_DEBOUNCE_S,
            ),
        ]

        predict = await predict_load(server.base_url, bodies, sizes.predictions)

        await set_delay(http, CHANNEL_DELAY_S)
        try:
            delayed = await send_series(
                sender, SendRun(f"delay {CHANNEL_DELAY_S:g} s", CHANNEL_DELAY_S), sends, rng
            )
        finally:
            await set_delay(http, 0.0)
        # the baseline right before and right after the telemetry clients (drift cancels)
        before = await send_series(
            sender, SendRun("delay 0 s (default), before the clients", 0.0), sends, rng
        )
        telemetry = await telemetry_load(
            server, sender, WS_CLIENTS, sizes.telemetry_s, sends, seed=2
        )
        after = await send_series(
            sender, SendRun("delay 0 s (default), after the clients", 0.0), sends, rng
        )
    return Results(sizes, api, [before, after, delayed], telemetry, airtime * 1e3, predict)


def run(out: TextIO, quick: bool = False, sizes: Sizes | None = None) -> int:
    """Measure and print every table; ``sizes`` (the tests' smaller run) overrides ``quick``."""
    with (
        tempfile.TemporaryDirectory(prefix="nemesys-bench-console-") as tmp,
        console_server(Path(tmp)) as server,
    ):
        out.write(
            f"Server: nemesys console (training mode, viewer on), pid {server.pid}, "
            f"{server.base_url}; load generators in this process (pid {os.getpid()}); "
            f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at the start\n\n"
        )
        out.flush()
        res = asyncio.run(measure(server, sizes or (QUICK if quick else FULL)))
    api_s = res.sizes.api_s
    out.write(
        f"Preview/encode latency: POST /api/preview then /api/encode, every pattern at its "
        f"defaults in turn,\n{api_s:g} s per load ({api_s / 3:g} s for one client); the preview "
        "also draws in the viser view\n\n"
    )
    out.write(api_table(res.api) + "\n\n")
    out.write(
        f"Prediction: POST /api/predict back to back ({res.sizes.predictions}), one page "
        "previewing at its pace meanwhile\n\n"
    )
    out.write(predict_table(res.predict) + "\n\n")
    out.write(
        "Send -> acknowledged on /ws, training mode, minus airtime "
        f"({res.airtime_ms:.3f} ms) and the channel's delay;\ncircle radius 4 m / 5 m in turn, "
        "0.1-0.3 s apart\n\n"
    )
    out.write(send_table(res.sends) + "\n\n")
    t = res.telemetry
    out.write(
        f"{WS_CLIENTS} telemetry websocket clients on /ws for "
        f"{res.sizes.telemetry_s:g} s, {t.sends.sends} sends spread over the window "
        "(no effect: median excess <= without + "
        f"{NO_EFFECT_MS:g} ms)\n\n"
    )
    without = SendRun("without", 0.0, [*res.sends[0].excess_ms, *res.sends[1].excess_ms])
    out.write(telemetry_table(t, without) + "\n")
    if t.errors:
        out.write("\nfirst errors: " + "; ".join(t.errors[:3]) + "\n")
    for s in [*res.sends, t.sends]:
        if s.failures:
            out.write(f"\n{s.label}: not acknowledged: " + "; ".join(s.failures[:3]) + "\n")
    return 0
