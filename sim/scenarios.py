"""The paper's digital-twin retasking runs and its tank test, with their metrics.

Geometry follows ``../shared/research/sim.md`` section 5 (the paper gives none):

* ``wreck``: lawnmower over a 20 x 10 m box (6 lanes 2 m apart) at 3 m, 0.18 m/s; mid-sweep
  the sweep length is extended to 30 m (a parameter-level update: same lanes, same lane).
* ``panel``: helix of radius 2.5 m around the BOP panel from 2 m to 4 m depth in 4 turns;
  then a constant-depth 5 m square at 3 m around the same panel (a pattern-level switch).
* ``pod``: 8 m square patrol at 2 m around the pod; then a 5 m circle at 3 m (pattern and
  depth).
* ``tank``: hover in the tank; the target depth is set to 0.5 m and then changed four times
  over 75 s between 0.5 and 1.0 m (the paper's Fig. ``fig:depth_control`` schedule is not
  given in numbers; this is one consistent with "between 0 and 1.0 m").

Metrics (the paper's, plus the usual path-following ones), for the retask frame:

* decode latency: frame received -> decoded and checked (ms, wall clock);
* replan latency: decoded -> plan and first new setpoint (ms), and normalised per waypoint;
* join time: retask -> on the new pattern's body (past the join) and within 0.3 m cross-track
  and 3 cm of the depth reference, held for 10 s (s);
* cross-track error on the new pattern after the join: RMS and maximum (m);
* depth rise (10-90 %) and settling (into +-3 cm and staying) for the depth change (s);
* peak memory: Python heap peak (tracemalloc) while the agent decodes and replans (KiB),
  and the process's peak RSS (MB).
"""

from __future__ import annotations

import math
import statistics
import tracemalloc
from dataclasses import dataclass, field, replace
from typing import Any

from codec import encode_frame
from sim.simulation import Sample, SimConfig, Simulation

#: Join tolerances (sim.md section 4).
JOIN_CROSS_TRACK_M = 0.3
JOIN_DEPTH_M = 0.03
JOIN_HOLD_S = 10.0
#: Depth settling band (the paper's +-3 cm).
SETTLE_BAND_M = 0.03
RECORD_HZ = 10.0


@dataclass(frozen=True, slots=True)
class TimedCommand:
    """A command sent at ``t_s`` seconds into the run."""

    t_s: float
    pattern: str
    params: dict[str, float | str]


@dataclass(frozen=True, slots=True)
class Scenario:
    name: str
    title: str
    commands: tuple[TimedCommand, ...]
    duration_s: float
    start_z_m: float = 2.0
    #: Index in ``commands`` of the retask being scored (the tank scores every step).
    retask: int = 1


SCENARIOS: dict[str, Scenario] = {
    s.name: s
    for s in (
        Scenario(
            "wreck",
            "Shipwreck mapping: lawnmower sweep length 20 m -> 30 m mid-sweep",
            (
                TimedCommand(
                    0.0,
                    "lawnmower",
                    {"speed": 0.18, "depth": 3, "sweep_length": 20, "lane_spacing": 2, "laps": 3},
                ),
                TimedCommand(
                    180.0,
                    "lawnmower",
                    {"speed": 0.18, "depth": 3, "sweep_length": 30, "lane_spacing": 2, "laps": 3},
                ),
            ),
            duration_s=600.0,
            start_z_m=3.0,
        ),
        Scenario(
            "panel",
            "BOP panel inspection: helix 2 -> 4 m, then a 5 m square at 3 m",
            (
                TimedCommand(
                    0.0,
                    "helix",
                    {
                        "speed": 0.18,
                        "start_depth": 2,
                        "end_depth": 4,
                        "radius": 2.5,
                        "turns": 4,
                        "direction": "ccw",
                    },
                ),
                TimedCommand(
                    200.0, "square", {"speed": 0.18, "depth": 3, "side_span": 5, "direction": "cw"}
                ),
            ),
            duration_s=420.0,
        ),
        Scenario(
            "pod",
            "Subsea pod patrol: 8 m square at 2 m, then a 5 m circle at 3 m",
            (
                TimedCommand(
                    0.0, "square", {"speed": 0.18, "depth": 2, "side_span": 8, "direction": "cw"}
                ),
                TimedCommand(
                    200.0, "circle", {"speed": 0.18, "depth": 3, "radius": 5, "direction": "cw"}
                ),
            ),
            duration_s=420.0,
        ),
        Scenario(
            "tank",
            "Tank test: hover, target depth 0.5 / 1.0 / 0.5 / 1.0 / 0.5 m over 75 s",
            tuple(
                TimedCommand(t, "hover", {"duration": 600, "depth": d, "heading": 0})
                for t, d in ((0.0, 0.5), (15.0, 1.0), (30.0, 0.5), (45.0, 1.0), (60.0, 0.5))
            ),
            duration_s=75.0,
            start_z_m=0.0,
        ),
    )
}


@dataclass(frozen=True, slots=True)
class DepthStep:
    """One depth change: from, to (m); rise 10-90 % and settling into +-3 cm (s, None if
    never); steady-state mean and peak deviation (m) after settling, until the next step."""

    t_s: float
    from_m: float
    to_m: float
    rise_s: float | None
    settle_s: float | None
    steady_mean_m: float | None
    steady_peak_m: float | None


@dataclass
class ScenarioResult:
    scenario: Scenario
    seed: int
    acks: list[dict[str, Any]]
    track: list[Sample]
    plans: list[Any]  # the plan in force after each command (planner.Plan)
    metrics: dict[str, Any] = field(default_factory=dict)
    steps: list[DepthStep] = field(default_factory=list)


def run_scenario(name: str, seed: int = 0, config: SimConfig | None = None) -> ScenarioResult:
    """Run a scenario start to end and compute its metrics.

    Raises:
        KeyError: ``name`` is not one of :data:`SCENARIOS`.
    """
    if name not in SCENARIOS:
        raise KeyError(f"unknown scenario {name!r}; choose from {', '.join(SCENARIOS)}")
    sc = SCENARIOS[name]
    cfg = replace(config or SimConfig(), seed=seed, start_z_m=sc.start_z_m, record_hz=RECORD_HZ)
    sim = Simulation(cfg)
    plans: list[Any] = []
    heap_peak_kib: float | None = None
    for k, cmd in enumerate(sc.commands):
        sim.run_until(cmd.t_s)
        frame = encode_frame(cmd.pattern, cmd.params).frame.to_bytes()
        n_acks = len(sim.acks)
        measure = k == sc.retask
        if measure:
            tracemalloc.start()
        sim.submit_frame(frame)
        while len(sim.acks) == n_acks and sim.t_s < cmd.t_s + 5.0:
            sim.step()
        if measure:
            heap_peak_kib = tracemalloc.get_traced_memory()[1] / 1024
            tracemalloc.stop()
        plans.append(sim.agent.active)
    sim.run_until(sc.duration_s)
    result = ScenarioResult(sc, seed, list(sim.acks), list(sim.track), plans)
    result.metrics = _metrics(result, heap_peak_kib)
    if sc.name == "tank":
        result.steps = depth_steps(
            sim.track, [(c.t_s, float(c.params["depth"])) for c in sc.commands], sc.duration_s
        )
    return result


def _peak_rss_mb() -> float | None:
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        return None
    return None


def _metrics(result: ScenarioResult, heap_peak_kib: float | None) -> dict[str, Any]:
    sc = result.scenario
    acks = result.acks
    ack = acks[sc.retask]
    decode = [a["decode_latency_ms"] for a in acks if a["decode_latency_ms"] is not None]
    m: dict[str, Any] = {
        "frames": len(acks),
        "accepted": sum(a["outcome"] == "accepted" for a in acks),
        "decode_latency_ms": ack["decode_latency_ms"],
        "decode_latency_mean_ms": statistics.fmean(decode) if decode else None,
        "replan_latency_ms": ack["replan_latency_ms"],
        "waypoints": ack["waypoints"],
        "normalised_replan_ms": (
            ack["replan_latency_ms"] / ack["waypoints"] if ack["waypoints"] else None
        ),
        "switch_latency_ms": (ack["decode_latency_ms"] or 0.0) + (ack["replan_latency_ms"] or 0.0),
        "heap_peak_kib": heap_peak_kib,
        "peak_rss_mb": _peak_rss_mb(),
    }
    if sc.name == "tank":
        return m
    t_retask = ack["t_s"]
    new_plan = result.plans[sc.retask]
    body = new_plan.path.body_start
    after = [s for s in result.track if s.t_s > t_retask]
    m["join_time_s"] = _join_time(after, body, t_retask)
    on = [s for s in after if s.segment >= body and s.mode == "running"]
    if m["join_time_s"] is not None:
        on = [s for s in on if s.t_s >= t_retask + m["join_time_s"]]
    xte = [s.cross_track_m for s in on]
    m["cross_track_rms_m"] = math.sqrt(statistics.fmean(x * x for x in xte)) if xte else None
    m["cross_track_max_m"] = max(xte) if xte else None
    m["transition_cross_track_max_m"] = max(
        (s.cross_track_m for s in after if s.segment < body), default=0.0
    )
    z_from = next((s.z_m for s in result.track if s.t_s >= t_retask), after[0].z_m)
    z_to = new_plan.path.zs[-1]  # where the new pattern settles (after any ramp laps)
    step = depth_steps(after, [(t_retask, z_to)], result.scenario.duration_s, z_from)[0]
    m["depth_from_m"] = z_from
    m["depth_to_m"] = z_to
    m["depth_rise_s"] = step.rise_s if abs(z_to - z_from) > 2 * SETTLE_BAND_M else None
    m["depth_settle_s"] = step.settle_s
    return m


def _join_time(after: list[Sample], body: int, t_retask: float) -> float | None:
    """First time after which the vehicle holds the join tolerances for JOIN_HOLD_S."""
    start: float | None = None
    for s in after:
        ok = (
            s.segment >= body
            and s.cross_track_m <= JOIN_CROSS_TRACK_M
            and abs(s.z_m - s.depth_ref_m) <= JOIN_DEPTH_M
        )
        if not ok:
            start = None
            continue
        if start is None:
            start = s.t_s
        if s.t_s - start >= JOIN_HOLD_S:
            return start - t_retask
    return None


def depth_steps(
    track: list[Sample],
    schedule: list[tuple[float, float]],
    end_s: float,
    first_from_m: float | None = None,
) -> list[DepthStep]:
    """Rise, settling and steady-state figures of each depth step in ``schedule``."""
    out: list[DepthStep] = []
    for k, (t0, target) in enumerate(schedule):
        t1 = schedule[k + 1][0] if k + 1 < len(schedule) else end_s
        seg = [s for s in track if t0 < s.t_s <= t1]
        if not seg:
            continue
        z0 = first_from_m if (k == 0 and first_from_m is not None) else seg[0].z_m
        span = target - z0
        rise: float | None = None
        if abs(span) > 1e-9:
            t10 = next((s.t_s for s in seg if (s.z_m - z0) / span >= 0.1), None)
            t90 = next((s.t_s for s in seg if (s.z_m - z0) / span >= 0.9), None)
            rise = t90 - t10 if t10 is not None and t90 is not None else None
        outside = [s.t_s for s in seg if abs(s.z_m - target) > SETTLE_BAND_M]
        settle: float | None
        if not outside:
            settle = 0.0
        elif outside[-1] >= seg[-1].t_s:
            settle = None
        else:
            settle = outside[-1] - t0
        steady = [s.z_m - target for s in seg if settle is not None and s.t_s - t0 > settle]
        out.append(
            DepthStep(
                t0,
                z0,
                target,
                rise,
                settle,
                statistics.fmean(steady) if steady else None,
                max((abs(d) for d in steady), default=None),
            )
        )
    return out


def format_result(result: ScenarioResult) -> str:
    """The metrics as an aligned text table."""
    sc = result.scenario
    lines = [f"scenario {sc.name}: {sc.title} (seed {result.seed})"]
    for key, value in result.metrics.items():
        lines.append(f"  {key:<30} {_fmt(value)}")
    if result.steps:
        lines.append(
            "  depth steps (t, from -> to, rise 10-90 %, settle +-3 cm, steady mean, peak)"
        )
        for st in result.steps:
            lines.append(
                f"    {st.t_s:5.1f} s  {st.from_m:4.2f} -> {st.to_m:4.2f} m"
                f"  rise {_fmt(st.rise_s)} s"
                f"  settle {_fmt(st.settle_s)} s  mean {_fmt(_cm(st.steady_mean_m))} cm"
                f"  peak {_fmt(_cm(st.steady_peak_m))} cm"
            )
    return "\n".join(lines)


def _cm(v: float | None) -> float | None:
    return None if v is None else v * 100


def _fmt(v: object) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)
