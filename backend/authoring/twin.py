"""The twin's run: a fresh training twin placed where the vehicle was last seen, a command's
frame submitted at once, and its track followed over a bounded horizon.

This is the part of the prediction (:mod:`backend.authoring.predict`) that runs in the twin's
worker process: pure simulation, no console, so it pickles by name and imports only the
simulator, the planner and the vehicle profile. Its duration is timed by the twin's
completion rule (:mod:`sim.completion`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

from backend.authoring.profile import hours_run
from planner import Plan, VehicleState
from sim.environment import Current
from sim.simulation import SimConfig, Simulation
from vehicle_contract.codes import Mode

#: Simulated time kept after a finite pattern completes (s): the vehicle settling.
COMPLETION_MARGIN_S = 10.0
#: Track samples per simulated second (before decimation).
RECORD_HZ = 1.0
#: Simulated seconds between checks of the twin (its guidance tick).
TICK_S = 0.1
#: Ticks between two yields of the GIL (~0.1 ms of work each), for a twin run in a thread of
#: a busy process (the worker process has no other thread to yield to).
YIELD_EVERY = 20


@dataclass(frozen=True, slots=True)
class Start:
    """Where the twin starts: the vehicle as last reported (NED m, deg, m/s, s)."""

    state: VehicleState
    #: The vehicle's mode as last reported (``holding``, ``running``...; None: unknown).
    mode: str | None
    #: The plan it flies (the console's mirror), or None.
    active: Plan | None
    #: Battery charge (%), None: unknown (full is assumed).
    soc_pct: float | None


@dataclass(frozen=True, slots=True)
class Track:
    """The twin's run: samples (t from the submission, s; NED m) and what happened."""

    t_s: list[float]
    x_m: list[float]
    y_m: list[float]
    z_m: list[float]
    #: The onboard agent's answer: accepted, duplicate, rejected (its sentence), or lost.
    outcome: str
    reason: str | None
    #: Simulated seconds from the frame's arrival to the pattern's completion (a repeating
    #: one: the join and one lap; :mod:`sim.completion`), None: not within the horizon.
    duration_s: float | None
    horizon_s: float


def _place(sim: Simulation, start: Start) -> None:
    """Put the fresh twin in the reported state: pose, speed, clock and the active plan."""
    st = start.state
    veh = sim.vehicle
    veh.u = st.speed_mps
    sim.steps = round(st.t_s / sim.dt_s)
    sim.t_s = sim.steps * sim.dt_s
    active = start.active
    if active is None:
        return
    g = sim.guidance
    sim.agent.active = active
    g.set_plan(active, active.t0_s)
    path = active.path
    if len(path) > 1 and active.pattern not in ("hover", "surface"):
        where = path.locate(st.x_m, st.y_m, st.z_m, None, st.t_s - active.t0_s)
        g.segment = min(int(where), len(path) - 2)
    if start.mode == Mode.HOLDING.value and active.pattern != "hover":
        g.hold_here(path.xs[-1], path.ys[-1], path.zs[-1], st.heading_deg)
        g.mode = Mode.HOLDING


def run_twin(
    base: SimConfig,
    start: Start,
    frame: bytes,
    horizon_s: float,
    *,
    finite: bool,
    current: Current | None = None,
) -> Track:
    """Run a fresh twin configured like ``base`` from ``start``, submit ``frame`` at once and
    follow it for ``horizon_s`` simulated seconds (less once a ``finite`` pattern completes:
    the margin after it). ``current``: the water current's process to run (its drift and
    its generator's state, the training simulator's), instead of ``base``'s."""
    st = start.state
    soc_h = 0.0 if start.soc_pct is None else hours_run(start.soc_pct)
    cfg = replace(
        base,
        start_x_m=st.x_m,
        start_y_m=st.y_m,
        start_z_m=max(0.0, st.z_m),
        start_heading_deg=st.heading_deg,
        battery_start_h=soc_h,
        record_hz=0.0,
    )
    sim = Simulation(cfg)
    if current is not None:
        sim.current = current
    _place(sim, start)
    t0 = sim.t_s
    veh = sim.vehicle
    ts, xs, ys, zs = [0.0], [veh.x], [veh.y], [veh.z]
    sim.submit_frame(frame)
    end = t0 + horizon_s
    every = max(1, round(1.0 / (RECORD_HZ * TICK_S)))
    outcome, reason = "lost", None
    arrived: float | None = None
    completed: float | None = None
    k = 0
    half_step = sim.dt_s / 2
    while sim.t_s + half_step <= end:  # the last whole step (run_until's own rule)
        k += 1
        sim.run_until(min(end, t0 + k * TICK_S))
        if arrived is None and sim.acks:
            ack = sim.acks[0]
            arrived = sim.t_s
            if ack.get("outcome") != "accepted":
                outcome, reason = "rejected", str(ack.get("message") or ack.get("reason"))
            else:
                outcome = "duplicate" if ack.get("duplicate") else "accepted"
        if (
            completed is None
            and arrived is not None
            and outcome in ("accepted", "duplicate")
            and sim.completion.done_s is not None
        ):
            completed = max(arrived, sim.completion.done_s)
            if finite:
                end = min(end, completed + COMPLETION_MARGIN_S)
        if k % every == 0 or sim.t_s + half_step > end or completed == sim.t_s:
            ts.append(sim.t_s - t0)
            xs.append(veh.x)
            ys.append(veh.y)
            zs.append(veh.z)
        if k % YIELD_EVERY == 0:
            time.sleep(0)  # let the event loop's thread take the GIL between ticks
    duration = None if completed is None or arrived is None else completed - arrived
    return Track(ts, xs, ys, zs, outcome, reason, duration, sim.t_s - t0)
