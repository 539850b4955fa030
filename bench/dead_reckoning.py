"""``nemesys bench dead_reckoning``: the believed position against the simulator's own, for a
minute without telemetry.

The simulated vehicle (:class:`sim.simulation.Simulation`, ber 0) flies a circle and a
lawnmower (the belief tests' commands); at a fix time its telemetry "stops": from then on the
console's belief (:func:`backend.belief.estimate.estimate`, on a two-way link, the mirror being
the plan the simulated vehicle flies, as the console replays it from the acknowledgement) is
compared with where the simulated vehicle really is, every 5 s for 60 s: the horizontal
error, the belief's ``sigma_m``, and their ratio (the target: below 1 throughout). Without and
with a water current (0.05 m/s north, 0.02 m/s east, which the belief knows, as the console
knows the simulator's). The worst ratio over fix times every 23 s from 30 s to 400 s is given
beside each, and the cost: a belief's dead reckoning against stepping the simulated twin.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from dataclasses import replace
from datetime import UTC, datetime
from typing import Any, TextIO

from backend.belief.commands import Echo
from backend.belief.estimate import Evidence, estimate
from backend.belief.position import Fix, Start
from backend.belief.reckoning import Current
from bench._timing import table, verdict
from codec import encode_frame
from onboard.agent import command_json
from planner import VehicleState
from sim.channel import ChannelConfig
from sim.environment import CurrentConfig
from sim.simulation import SimConfig, Simulation

#: The commands of tests/backend/belief/test_dead_reckoning.py, and when their telemetry
#: stops there (s).
CASES: dict[str, tuple[str, dict[str, Any], float]] = {
    "circle": ("circle", {"speed": 0.18, "depth": 3, "radius": 5, "direction": "cw"}, 150.0),
    "lawnmower": (
        "lawnmower",
        {"speed": 0.18, "depth": 3, "sweep_length": 20, "lane_spacing": 3, "laps": 4},
        90.0,
    ),
}
CURRENTS = {"no current": (0.0, 0.0), "current 0.05 N 0.02 E": (0.05, 0.02)}
WINDOW_S = 60.0
STEP_S = 5.0
EPOCH = 1_700_000_000.0  # the console's clock at the simulator's 0 s


def _iso(t: float) -> str:
    return datetime.fromtimestamp(t, UTC).isoformat(timespec="milliseconds")


def _flying(pattern: str, params: dict[str, Any], current: tuple[float, float]) -> Simulation:
    cfg = SimConfig(
        seed=1,
        channel=ChannelConfig(ber=0.0, loss=0.0),
        current=CurrentConfig(north_mps=current[0], east_mps=current[1]),
    )
    sim = Simulation(cfg)
    sim.submit_frame(encode_frame(pattern, params).frame.to_bytes())
    return sim


def _evidence(sim: Simulation, fix: Fix, now_s: float) -> Evidence:
    """The console's evidence after the fix: two-way, the plan mirrored, the current known."""
    plan = sim.guidance.plan
    assert plan is not None
    command = command_json(plan.command)
    record = {
        "id": 1,
        "kind": "command",
        **command,
        "state": "acknowledged",
        "copies_sent": 1,
        "first_sent_at": _iso(EPOCH),
        "updated_at": _iso(EPOCH),
    }
    v = sim.vehicle
    return Evidence(
        vehicle="nemesys",
        now_s=now_s,
        time_scale=1.0,
        two_way=True,
        records=[record],
        last_sent=record,
        accepted=record,
        echo=Echo(command, fix.at_s, "status"),
        mirror=plan,
        fix=fix,
        start=Start(VehicleState(0.0, 0.0, 2.0), "the simulator's start"),
        current=Current(v.current_n, v.current_e, 0.0, "the simulator's current"),
        datum=None,
        top_speed_mps=0.19,
        vehicle_now_s=sim.t_s,
    )


def run_case(
    pattern: str, params: dict[str, Any], current: tuple[float, float], fix_t_s: float
) -> list[tuple[float, float, float]]:
    """(seconds since the fix, error m, sigma m) every :data:`STEP_S` over the window."""
    sim = _flying(pattern, params, current)
    sim.run_until(fix_t_s)
    s = sim.state()
    state = VehicleState(s.x_m, s.y_m, s.z_m, s.heading_deg, s.speed_mps, s.t_s)
    fix = Fix(state, EPOCH + fix_t_s, "pose")
    rows = []
    for k in range(int(WINDOW_S / STEP_S) + 1):
        dt = k * STEP_S
        sim.run_until(fix_t_s + dt)
        p = estimate(_evidence(sim, fix, EPOCH + fix_t_s + dt)).position
        error = math.hypot(p.x_m - sim.vehicle.x, p.y_m - sim.vehicle.y)
        rows.append((dt, error, p.sigma_m if p.sigma_m is not None else math.nan))
    return rows


def worst_ratio(
    pattern: str, params: dict[str, Any], current: tuple[float, float], fix_times: Iterable[float]
) -> float:
    """The largest error / sigma over the window, over fix times."""
    return max(
        e / s for t in fix_times for _, e, s in run_case(pattern, params, current, t) if s > 0
    )


def costs() -> tuple[float, float]:
    """(ms for one belief 60 s after the fix, ms per simulated second of the twin)."""
    pattern, params, fix_t_s = CASES["circle"]
    sim = _flying(pattern, params, (0.0, 0.0))
    sim.run_until(fix_t_s)
    s = sim.state()
    fix = Fix(VehicleState(s.x_m, s.y_m, s.z_m, s.heading_deg, s.speed_mps, s.t_s), EPOCH, "pose")
    ev = replace(_evidence(sim, fix, EPOCH + WINDOW_S), vehicle_now_s=s.t_s + WINDOW_S)
    n = 50
    t0 = time.perf_counter()
    for _ in range(n):
        estimate(ev)
    belief_ms = (time.perf_counter() - t0) / n * 1e3
    t0 = time.perf_counter()
    sim.run_until(sim.t_s + 20.0)
    twin_ms = (time.perf_counter() - t0) / 20.0 * 1e3
    return belief_ms, twin_ms


def run(out: TextIO, quick: bool = False) -> int:
    fix_times = range(30, 400, 23 if not quick else 115)
    ok = True
    for name, (pattern, params, fix_t_s) in CASES.items():
        for label, current in CURRENTS.items():
            rows = run_case(pattern, params, current, fix_t_s)
            worst = worst_ratio(pattern, params, current, fix_times)
            ok = ok and worst < 1.0 and all(e <= s for _, e, s in rows)
            print(f"\n{name}, {label}: telemetry stops at {fix_t_s:g} s", file=out)
            cells = [[f"{t:g}", f"{e:.2f}", f"{s:.2f}", f"{e / s:.2f}"] for t, e, s in rows]
            print(table(["s since fix", "error m", "sigma m", "error/sigma"], cells), file=out)
            print(
                f"worst error/sigma over fix times 30..400 s: {worst:.2f} "
                f"(target < 1: {verdict(worst < 1.0)})",
                file=out,
            )
    belief_ms, twin_ms = costs()
    print(
        f"\ncost: one belief 60 s after the fix {belief_ms:.2f} ms; the simulated twin "
        f"{twin_ms:.2f} ms per simulated second (x60 = {60 * twin_ms:.0f} ms for the same minute)",
        file=out,
    )
    return 0 if ok else 1


if __name__ == "__main__":
    import sys

    raise SystemExit(run(sys.stdout, quick="--quick" in sys.argv))
