"""``nemesys bench sim``: simulation speed and the onboard switch latency.

* One vehicle, 50 Hz physics, 10 Hz guidance, flying the pod patrol's square: simulated
  seconds per wall second on one core (target >= 100x real time).
* A fleet on one shared ME link (:class:`sim.fleet.FleetSimulation`, every vehicle stepped in
  one loop in one process, as ``nemesys sim --vehicles N`` runs it) of 1, 5 and 10 vehicles,
  each flying its square (one square sent to all): simulated seconds per wall second (target
  >= 100x real time with 10).
* 20 vehicles together, split over 2 worker processes (this machine has 2 cores), each
  flying its own square: the slower worker's simulated seconds per wall second (target >=
  1x, i.e. real time); the same 20 on one core is shown beside it.
* Frame received -> first new setpoint: the onboard agent's whole path (frame sync, decode,
  checks, replan with the join, guidance switch and first reference) for every pattern at
  its defaults and the scenarios' retask frames, against a vehicle mid-pattern (target <=
  1 ms; median and worst of 30 trials each, as the paper averages 30 decodes).

Medians over repeated runs: the machine is shared.
"""

from __future__ import annotations

import multiprocessing
import statistics
import time
from typing import TextIO

from bench._timing import table, verdict
from bench.reconfig import receive_afresh, retask_cases
from codec import DICTIONARY, encode_frame
from sim.fleet import FleetSimulation
from sim.scenarios import SCENARIOS
from sim.simulation import SimConfig, Simulation
from vehicle_contract.fleet import parse_vehicles

TARGET_SPEEDUP = 100.0
TARGET_FLEET = 20
TARGET_SETPOINT_MS = 1.0
#: Fleets on one link measured, and the real-time factor each must reach.
FLEET_SIZES = (1, 5, 10)
TARGET_FLEET_SPEEDUP = 100.0
#: Simulated seconds per advance of the fleet: what the bridge's 20 ms tick asks at 100x.
FLEET_SLICE_S = 2.0
WORKERS = 2
TRIALS = 30


def _square_vehicle(seed: int) -> Simulation:
    sim = Simulation(SimConfig(seed=seed))
    frame = encode_frame("square", speed=0.18, depth=2, side_span=8, direction="cw")
    sim.submit_frame(frame.frame.to_bytes())
    sim.run_until(1.0)
    return sim


def speedup(sim_s: float) -> float:
    """Simulated seconds per wall second for one vehicle."""
    sim = _square_vehicle(0)
    t0 = time.perf_counter()
    sim.run_until(sim.t_s + sim_s)
    return sim_s / (time.perf_counter() - t0)


def one_link_factor(n: int, sim_s: float) -> float:
    """Simulated seconds per wall second of a fleet of ``n`` on one link, each vehicle flying
    the square sent to all (address 0), advanced in :data:`FLEET_SLICE_S` slices."""
    fleet = FleetSimulation(parse_vehicles(str(n)))
    square = encode_frame("square", speed=0.18, depth=2, side_span=8, direction="cw", address=0)
    fleet.submit_frame(square.frame.to_bytes())
    fleet.run_until(1.0)
    end = fleet.t_s + sim_s
    t0 = time.perf_counter()
    while fleet.t_s < end - 1e-9:
        fleet.advance(FLEET_SLICE_S)
    return sim_s / (time.perf_counter() - t0)


def _fleet_worker(args: tuple[int, int, float]) -> float:
    first, count, sim_s = args
    fleet = [_square_vehicle(first + k) for k in range(count)]
    t0 = time.perf_counter()
    end = fleet[0].t_s + sim_s
    tick = 0.1
    t = fleet[0].t_s
    while t < end - 1e-9:  # lock-step in 0.1 s slices, as a real-time scheduler would
        t += tick
        for sim in fleet:
            sim.run_until(t)
    return time.perf_counter() - t0


def fleet_shares(n: int, workers: int) -> list[int]:
    """How many of ``n`` vehicles each worker flies: as even as can be, ``n`` in all."""
    return [n // workers + (1 if k < n % workers else 0) for k in range(workers)]


def fleet_factor(n: int, sim_s: float, workers: int) -> float:
    """Real-time factor of ``n`` vehicles over ``workers`` processes (slowest worker)."""
    shares = fleet_shares(n, workers)
    jobs = [(sum(shares[:k]), shares[k], sim_s) for k in range(workers)]
    if workers == 1:
        walls = [_fleet_worker(jobs[0])]
    else:
        with multiprocessing.get_context("spawn").Pool(workers) as pool:
            walls = pool.map(_fleet_worker, jobs)
    return sim_s / max(walls)


def setpoint_latencies(trials: int) -> dict[str, list[float]]:
    """Wall ms of ``agent.receive`` (frame in -> first new setpoint), ``trials`` per case."""
    base = _square_vehicle(0)
    base.run_until(60.0)
    cases: dict[str, tuple[Simulation, int]] = {}
    for name, pattern in DICTIONARY.items():
        bits = int(encode_frame(name, pattern.defaults).frame.bits, 2)
        cases[f"{name} (defaults)"] = (base, bits)
    for name, case in retask_cases().items():
        sc = SCENARIOS[name]
        cases[f"{name} retask ({sc.commands[sc.retask].pattern})"] = (case.sim, case.bits)
    return {
        label: [receive_afresh(sim, bits, label)[1] for _ in range(trials)]
        for label, (sim, bits) in cases.items()
    }


def run(out: TextIO, quick: bool = False) -> int:
    rounds = 3 if quick else 5
    sim_s = 60.0 if quick else 300.0
    speeds = [speedup(sim_s) for _ in range(rounds)]
    fleet_s = 20.0 if quick else 60.0
    fleet2 = [fleet_factor(TARGET_FLEET, fleet_s, WORKERS) for _ in range(rounds)]
    fleet1 = [fleet_factor(TARGET_FLEET, fleet_s, 1) for _ in range(rounds)]
    sp, f2, f1 = statistics.median(speeds), statistics.median(fleet2), statistics.median(fleet1)
    link_s = 30.0 if quick else 120.0
    one_link = {
        n: statistics.median(one_link_factor(n, link_s) for _ in range(rounds)) for n in FLEET_SIZES
    }
    out.write(f"Simulation speed (median of {rounds} runs; 50 Hz physics, 10 Hz guidance)\n\n")
    rows = [
        [
            "1 vehicle, one core",
            f"{sp:,.0f}x real time",
            f">= {TARGET_SPEEDUP:.0f}x",
            verdict(sp >= TARGET_SPEEDUP),
        ],
        [
            f"{TARGET_FLEET} vehicles, {WORKERS} processes",
            f"{f2:,.1f}x real time",
            ">= 1x",
            verdict(f2 >= 1.0),
        ],
        [f"{TARGET_FLEET} vehicles, one process", f"{f1:,.1f}x real time", "(for comparison)", ""],
    ]
    rows += [
        [
            f"fleet of {n} on one link, one loop",
            f"{factor:,.0f}x real time",
            f">= {TARGET_FLEET_SPEEDUP:.0f}x",
            verdict(factor >= TARGET_FLEET_SPEEDUP),
        ]
        for n, factor in one_link.items()
    ]
    out.write(table(["case", "measured", "target", ""], rows) + "\n\n")
    lat = setpoint_latencies(10 if quick else TRIALS)
    out.write(
        "Frame received -> first new setpoint (sync, decode, checks, replan with join, "
        "guidance switch), vehicle mid-pattern\n\n"
    )
    lrows = []
    for label, samples in lat.items():
        med, worst = statistics.median(samples), max(samples)
        lrows.append(
            [
                label,
                f"{med:.3f}",
                f"{worst:.3f}",
                f"<= {TARGET_SETPOINT_MS:g}",
                verdict(med <= TARGET_SETPOINT_MS),
            ]
        )
    out.write(table(["frame", "median ms", "max ms", "target ms", ""], lrows) + "\n")
    return 0
