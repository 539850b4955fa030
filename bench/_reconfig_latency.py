"""The latency half of ``nemesys bench reconfig``: each retask scenario's frame through the
onboard agent, mid-scenario, timed the paper's way.

:func:`retask_cases` flies each scenario's first command in the simulator up to its retask
time; :func:`receive_afresh` hands the retask frame to a deep copy of the agent there (so
every trial sees the same vehicle and plan), and the acknowledgment carries the decode and
replan latencies. :func:`measure_latency` runs rounds of the paper's protocol: 10 trials per
scenario, interleaved, so 30 decodes a round; a round's decode figure is the mean of its 30
decodes and a scenario's replan figure the mean of its 10, and the medians over rounds are
reported.
"""

from __future__ import annotations

import copy
import statistics
import time
from dataclasses import dataclass
from typing import Any

from bench._reconfig_memory import RETASK_SCENARIOS
from codec import FRAME_BITS, encode_frame
from onboard.agent import OnboardAgent
from sim.scenarios import SCENARIOS
from sim.simulation import SimConfig, Simulation

#: The paper's normalised replan latencies (ms per waypoint) and its names of the scenarios.
PAPER_NORMALISED_MS = {"wreck": 42.0, "panel": 15.0, "pod": 46.0}
PAPER_NAMES = {"wreck": "Shipwreck", "panel": "BOP", "pod": "Pod"}
PAPER_REPLAN_TRIALS = 10


@dataclass(frozen=True, slots=True)
class RetaskCase:
    """A scenario's retask frame and the simulated vehicle about to receive it."""

    name: str
    retask: str  # e.g. "lawnmower -> lawnmower"
    bits: int
    sim: Simulation


@dataclass(frozen=True, slots=True)
class ScenarioLatency:
    """One scenario's replan figures: medians over rounds of each round's 10-trial mean."""

    name: str
    retask: str
    waypoints: int
    replan_ms: float  # total replanning time
    decode_ms: float  # this scenario's decodes alone
    round_normalised_ms: tuple[float, ...]  # every round's mean, for the spread

    @property
    def normalised_ms(self) -> float:
        """Total replanning time / waypoints (the paper's normalised replan latency)."""
        return self.replan_ms / self.waypoints

    @property
    def paper_normalised_ms(self) -> float:
        return PAPER_NORMALISED_MS[self.name]

    @property
    def paper_name(self) -> str:
        return PAPER_NAMES[self.name]


def retask_cases() -> dict[str, RetaskCase]:
    """Each retask scenario's vehicle at its retask time, flying the first command."""
    cases: dict[str, RetaskCase] = {}
    for name in RETASK_SCENARIOS:
        sc = SCENARIOS[name]
        sim = Simulation(SimConfig(start_z_m=sc.start_z_m))
        first, cmd = sc.commands[0], sc.commands[sc.retask]
        sim.submit_frame(encode_frame(first.pattern, first.params).frame.to_bytes())
        sim.run_until(cmd.t_s)
        bits = int(encode_frame(cmd.pattern, cmd.params).frame.bits, 2)
        cases[name] = RetaskCase(name, f"{first.pattern} -> {cmd.pattern}", bits, sim)
    return cases


def receive_afresh(sim: Simulation, bits: int, label: str) -> tuple[dict[str, Any], float]:
    """A deep copy of ``sim``'s agent (the same vehicle and plan at every call) receives the
    frame ``bits``: its acknowledgment and the wall ms of ``receive`` (frame in -> first new
    setpoint). Raises unless the frame was accepted."""
    agent: OnboardAgent = copy.deepcopy(sim.agent)
    state = sim.state()
    t0 = time.perf_counter()
    ack, ref = agent.receive(bits, FRAME_BITS, state)
    wall_ms = (time.perf_counter() - t0) * 1e3
    if ack["outcome"] != "accepted" or ref is None:
        raise RuntimeError(f"{label}: the frame was not accepted: {ack['detail']}")
    return ack, wall_ms


def measure_latency(
    rounds: int, trials: int = PAPER_REPLAN_TRIALS
) -> tuple[tuple[ScenarioLatency, ...], tuple[float, ...]]:
    """Per-scenario replan figures and every round's mean decode latency (ms)."""
    cases = retask_cases()
    for case in cases.values():  # warm-up, not counted: imports, first-call caches
        receive_afresh(case.sim, case.bits, case.name)
    decode_means: list[float] = []
    replan: dict[str, list[float]] = {n: [] for n in cases}
    decode_by: dict[str, list[float]] = {n: [] for n in cases}
    waypoints: dict[str, int] = {}
    for _ in range(rounds):
        decodes: list[float] = []
        replans: dict[str, list[float]] = {n: [] for n in cases}
        for _ in range(trials):
            for name, case in cases.items():
                ack, _ = receive_afresh(case.sim, case.bits, case.name)
                decodes.append(ack["decode_latency_ms"])
                decode_by[name].append(ack["decode_latency_ms"])
                replans[name].append(ack["replan_latency_ms"])
                waypoints[name] = ack["waypoints"]
        decode_means.append(statistics.fmean(decodes))
        for name in cases:
            replan[name].append(statistics.fmean(replans[name]))
    scenarios = tuple(
        ScenarioLatency(
            name,
            case.retask,
            waypoints[name],
            statistics.median(replan[name]),
            statistics.median(decode_by[name]),
            tuple(r / waypoints[name] for r in replan[name]),
        )
        for name, case in cases.items()
    )
    return scenarios, tuple(decode_means)
