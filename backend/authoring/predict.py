"""The predicted track: what the vehicle will actually do with a command (``POST /api/predict``).

The preview is the planner's path on the planner's clock. The prediction runs the training
twin (:class:`sim.simulation.Simulation`, a fresh one each time) from the vehicle's current
state, with the command's encoded frame submitted the way the console sends it (so it goes
through the onboard decode, checks and replan), faster than real time over a bounded horizon
(at most :data:`MAX_HORIZON_S` of simulated time, or until a finite pattern completes plus
:data:`~backend.authoring.twin.COMPLETION_MARGIN_S`; the run itself:
:mod:`backend.authoring.twin`). It shows what the plan's clock does not: the vehicle's top
speed, its turns and depth transients, the current, the battery.

Its duration is timed by the twin's completion rule (:mod:`sim.completion`: at the path's end
*and* depth; a repeating pattern after the join and one lap), the estimate's too; beside it the
estimate (:mod:`backend.authoring.durations`) and, where they differ by more than 20 %, why.

The twin starts where the console last saw the vehicle: position, depth, heading, speed
through the water (taken along the heading), the mission clock and the plan it runs (the
console's mirror, so the retask join and anchor are the vehicle's), its battery's charge. In
training it gets the simulator's vehicle, gains, limits, its channel and its water current
as they are now (the current drifting on from its present state, as it does there); the
frame arrives intact (the channel's delay and range kept, no errors or loss).
For a real vehicle there is no simulator: the twin's own dynamics, from the last pose, with
no current; ``assumptions`` says so.

Cost: a pure-Python simulation of up to 600 s at ~1000x, about 0.6 s of one core. The request
waits in the threadpool (never on the event loop), one prediction at a time (:class:`Gate`),
and the twin runs in a worker process (one, started on the first prediction, ~1 s): in this
process it would hold the GIL and slow the previews on the event loop threefold; in its own it
uses the machine's other core. Should the worker die, the next prediction starts another.
"""

from __future__ import annotations

import contextlib
import copy
import math
import multiprocessing
import multiprocessing.connection
import os
import threading
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from dataclasses import replace
from functools import partial
from typing import Any

import numpy as np

from backend.authoring.durations import flown, prediction_notes
from backend.authoring.twin import Start, Track, run_twin
from backend.chart.geo import Datum, ned_to_geodetic
from codec import decode_frame, encode_frame
from planner import Plan, VehicleState, plan
from sim.environment import Current
from sim.simulation import SimConfig

#: Longest simulated time a prediction covers (s), and the default.
MAX_HORIZON_S = 600.0
#: Most points returned (the track is decimated evenly, first and last kept).
MAX_POINTS = 600
#: Requests that may wait while one prediction runs; more get 503.
QUEUE = 2
#: Retry-After of a 503 (s): about one prediction's time.
RETRY_AFTER_S = 2


class PredictorBusy(RuntimeError):
    """A prediction runs and the queue is full: try again after ``retry_after_s``."""

    def __init__(self, reason: str | None = None, retry_after_s: int = RETRY_AFTER_S) -> None:
        self.retry_after_s = retry_after_s
        why = reason or f"a prediction is running and {QUEUE} more are waiting"
        super().__init__(f"{why}: retry in {retry_after_s} s")


class Gate:
    """At most one prediction at a time, ``queue`` more waiting; beyond that
    :class:`PredictorBusy` at once."""

    def __init__(self, queue: int = QUEUE) -> None:
        self.queue = queue
        #: Held by the prediction running now.
        self.running = threading.Lock()
        self._count_lock = threading.Lock()
        self._count = 0

    @property
    def admitted(self) -> int:
        """Predictions running or waiting."""
        return self._count

    @contextmanager
    def slot(self) -> Iterator[None]:
        with self._count_lock:
            if self._count >= 1 + self.queue:
                raise PredictorBusy()
            self._count += 1
        try:
            with self.running:
                yield
        finally:
            with self._count_lock:
                self._count -= 1


#: How much the twin's worker yields the CPU (``nice`` increment): a prediction is background
#: work, the console's requests, telemetry and the simulated vehicle come first on a busy
#: machine (on 2 cores a 600 s prediction otherwise took a whole core from the page's previews).
WORKER_NICE = 10


def _worker_init() -> None:
    """In the worker: lower its priority, and exit when the console's process is gone."""
    with contextlib.suppress(OSError):  # a platform without nice: the same work, unyielding
        os.nice(WORKER_NICE)
    _watch_parent()


def _watch_parent() -> None:
    """In the worker: exit when the console's process is gone, however it ended (SIGKILL
    included), so no orphaned twin outlives it."""
    parent = multiprocessing.parent_process()
    if parent is None:
        return

    def watch() -> None:
        multiprocessing.connection.wait([parent.sentinel])
        os._exit(0)

    threading.Thread(target=watch, name="parent watch", daemon=True).start()


class TwinWorker:
    """The worker process a console's twins run in (spawned: no copy of this process's
    threads), started on first use, replaced if it dies, shut down with the console."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._pool: ProcessPoolExecutor | None = None
        self._closed = False

    def _get(self, *, fresh: bool = False) -> ProcessPoolExecutor:
        with self._lock:
            if self._closed:
                raise PredictorBusy("the console is shutting down")
            if self._pool is None or fresh:
                self._pool = ProcessPoolExecutor(
                    1, mp_context=multiprocessing.get_context("spawn"), initializer=_worker_init
                )
            return self._pool

    def run(
        self,
        base: SimConfig,
        start: Start,
        frame: bytes,
        horizon_s: float,
        *,
        finite: bool,
        current: Current | None = None,
    ) -> Track:
        """:func:`run_twin` in the worker process; a new worker if the last one died."""
        job = partial(run_twin, base, start, frame, horizon_s, finite=finite, current=current)
        try:
            return self._get().submit(job).result()
        except BrokenProcessPool:
            return self._get(fresh=True).submit(job).result()

    def close(self) -> None:
        """Stop the worker process (a prediction still running is abandoned)."""
        with self._lock:
            self._closed = True
            pool, self._pool = self._pool, None
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)


def max_deviation_m(path: Plan, xs: list[float], ys: list[float], zs: list[float]) -> float:
    """Largest 3D distance (m) from any track point to the planned path's polyline."""
    p = path.path
    a = np.column_stack((p.xs, p.ys, p.zs))
    pts = np.column_stack((xs, ys, zs))
    if len(a) == 1:
        return float(np.max(np.linalg.norm(pts - a[0], axis=1)))
    seg_a, d = a[:-1], a[1:] - a[:-1]
    den = np.einsum("ij,ij->i", d, d)
    den[den == 0.0] = np.inf  # a point segment: the nearest is its start
    worst = 0.0
    for chunk in np.array_split(pts, max(1, len(pts) // 64)):
        rel = chunk[:, None, :] - seg_a[None, :, :]
        f = np.clip(np.einsum("ijk,jk->ij", rel, d) / den[None, :], 0.0, 1.0)
        near = rel - f[:, :, None] * d[None, :, :]
        dist = np.sqrt(np.einsum("ijk,ijk->ij", near, near)).min(axis=1)
        worst = max(worst, float(dist.max()))
    return worst


def decimate(n: int, most: int = MAX_POINTS) -> list[int]:
    """Indices of at most ``most`` of ``n`` points, evenly spread, first and last kept."""
    if n <= most:
        return list(range(n))
    step = (n - 1) / (most - 1)
    return sorted({round(i * step) for i in range(most)})


def predict(
    console: Any,
    pattern: str,
    params: dict[str, Any],
    horizon_s: float = MAX_HORIZON_S,
    vehicle: str | None = None,
) -> dict[str, Any]:
    """The predicted track of ``pattern``/``params`` from the vehicle's state now (a fleet's
    ``vehicle``: its state, path and battery; the twin takes the frame unaddressed, as the
    one vehicle it is).

    Raises:
        codec.EncodeError / planner.PlanError: naming the parameter at fault (422).
    """
    enc = encode_frame(pattern, params)
    cmd = decode_frame(enc.frame.bits).command  # what the vehicle will decode
    state: VehicleState = console.vehicle_state(vehicle)
    mirror: Plan | None = None
    if console.commands is not None:
        mirror = console.commands.addressee(vehicle).mirror.plan
    planned = plan(cmd, state, mirror)
    status = console.fleet.get(vehicle).hub.status or {}
    soc = status.get("battery_pct")
    soc_pct = float(soc) if isinstance(soc, int | float) and math.isfinite(soc) else None
    mode = status.get("mode") if isinstance(status.get("mode"), str) else None
    base, current, assumptions = _base_config(console)
    if soc_pct is None:
        assumptions.append("battery charge unknown: a full battery")
    start = Start(state, mode, mirror, soc_pct)
    repeats = planned.path.loop_start is not None
    worker: TwinWorker = console.twin_worker
    track = worker.run(
        base, start, enc.frame.to_bytes(), horizon_s, finite=not repeats, current=current
    )
    est = flown(planned, console.profile)[0]
    water = current.velocity if current is not None else (0.0, 0.0)
    keep = decimate(len(track.t_s))
    xs = [track.x_m[i] for i in keep]
    ys = [track.y_m[i] for i in keep]
    lat: list[float] | None = None
    lon: list[float] | None = None
    datum: Datum | None = console.datum
    if datum is not None:
        la, lo = ned_to_geodetic(datum, xs, ys)
        lat, lon = [float(v) for v in la], [float(v) for v in lo]
    return {
        "x_m": xs,
        "y_m": ys,
        "z_m": [track.z_m[i] for i in keep],
        "t_s": [track.t_s[i] for i in keep],
        "lat_deg": lat,
        "lon_deg": lon,
        "duration_s": track.duration_s,
        "planned_duration_s": planned.path.duration_s,
        "estimate_duration_s": est.duration_s,
        "repeats": repeats,
        "duration_notes": prediction_notes(track.duration_s, est.duration_s, water),
        "max_deviation_m": max_deviation_m(planned, track.x_m, track.y_m, track.z_m),
        "horizon_s": track.horizon_s,
        "completes": track.duration_s is not None,
        "outcome": track.outcome,
        "reason": track.reason,
        "assumptions": assumptions,
    }


def _base_config(console: Any) -> tuple[SimConfig, Current | None, list[str]]:
    """The twin's configuration, the water current's process to run (None: the config's) and
    what the prediction assumes. In training, the simulator's channel and current *now* (the
    training controls set ``sim.channel`` and ``sim.current``, not its config): a copy of the
    current, which drifts on from its state, generator included, as the simulator's will."""
    sim = console.sim
    if sim is None:
        no_sim = "no simulator: the training twin's dynamics from the last reported pose"
        return SimConfig(limits=console.limits), None, [no_sim, "no water current"]
    current: Current = copy.deepcopy(sim.current)
    channel = replace(sim.channel.config, ber=0.0, loss=0.0, burst_rate=0.0)
    base = replace(sim.config, channel=channel, current=current.config)
    north, east = current.velocity
    drifts = " (and drifts as it does there)" if current.config.drift else ""
    water = f"the water current runs on from its present {north:.3f} m/s north, {east:.3f} m/s east"
    return base, current, [water + drifts, "the frame arrives intact (no bit errors or loss)"]
