"""``nemesys sim`` and ``nemesys scenario``: the simulated vehicle from the command line.

Registered by :mod:`cli.main` (:func:`add_parsers`); the handlers return the exit status.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
from collections.abc import Callable
from typing import TextIO

from codec import DEFAULT_BITRATE_BPS, int_from_text, number_from_text

# Scenario names, for the help text (checked against sim.scenarios by the tests; the
# CLI does not import the simulator until a simulator subcommand runs).
SCENARIO_NAMES = ("wreck", "panel", "pod", "tank")


class SimUsageError(ValueError):
    """Bad option values; the CLI reports them with exit status 2."""


def _number(lo: float, hi: float, what: str) -> Callable[[str], float]:
    def parse(text: str) -> float:
        try:
            value = number_from_text(text)  # ASCII digits only
        except ValueError as err:
            raise argparse.ArgumentTypeError(f"{what} must be a number: {err}") from None
        if math.isnan(value) or not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"{what} must be in [{lo:g}, {hi:g}], got {text}")
        return value

    return parse


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "sim",
        help="run the simulated vehicle and its rosbridge websocket (headless)",
        description="Run a simulated NemeSys behind an emulated ME channel, exposed as a "
        "rosbridge v2 websocket (topics /nemesys/frame, /nemesys/pose, /nemesys/mission, "
        "/nemesys/status; see docs/bridge.md). Ctrl-C stops it.",
    )
    p.add_argument("--host", default="127.0.0.1", help="interface to bind (default 127.0.0.1)")
    p.add_argument(
        "--port", type=int_from_text, default=9090, help="TCP port (default 9090; 0 = any)"
    )
    p.add_argument(
        "--seed", type=int_from_text, default=0, help="random seed of the run (default 0)"
    )
    p.add_argument(
        "--ber", type=_number(0, 0.5, "--ber"), default=0.0, help="bit error rate, 0..0.5"
    )
    p.add_argument(
        "--bursts",
        type=_number(0, 1, "--bursts"),
        default=0.0,
        metavar="P",
        help="probability per frame of an error burst, 0..1",
    )
    p.add_argument(
        "--loss", type=_number(0, 1, "--loss"), default=0.0, help="frame loss probability, 0..1"
    )
    p.add_argument(
        "--delay",
        type=_number(0, 3600, "--delay"),
        default=0.0,
        help="link delay (s) on top of the airtime",
    )
    p.add_argument(
        "--range", type=_number(0, math.inf, "--range"), default=730.0, help="link range (m)"
    )
    p.add_argument(
        "--bitrate",
        type=_number(1, 1e9, "--bitrate"),
        default=float(DEFAULT_BITRATE_BPS),
        help="bit rate (b/s)",
    )
    p.add_argument(
        "--current",
        type=number_from_text,
        nargs=2,
        default=(0.0, 0.0),
        metavar=("NORTH", "EAST"),
        help="water current (m/s, NED)",
    )
    p.add_argument(
        "--time-scale",
        type=_number(0, 1000, "--time-scale"),
        default=1.0,
        help="simulated seconds per wall second (default 1: real time)",
    )
    p.add_argument(
        "--vehicles",
        default="",
        metavar="N|JSON",
        help="a fleet on one shared ME link: a count (auv1, auv2, ... with addresses 1, 2, ...) "
        'or a JSON list such as \'[{"name": "alpha", "address": 4}]\'; each vehicle\'s topics '
        "under its namespace (/auv1/nemesys/pose), a frame on any frame topic or on "
        "/nemesys/frame heard by all (default: one vehicle, no address)",
    )
    p.add_argument(
        "--spacing",
        type=_number(0.1, 1000, "--spacing"),
        default=30.0,
        metavar="M",
        help="with --vehicles: metres between neighbouring vehicles at the start (default 30)",
    )
    p.add_argument("--quiet", action="store_true", help="log warnings only")

    p = sub.add_parser(
        "scenario",
        help="run one of the paper's retasking scenarios and print its metrics",
        description="Run a scenario end to end in the simulator (faster than real time), "
        "print its metrics and write a PNG plot of the track and the depth over time.",
    )
    p.add_argument("name", metavar="NAME", help=", ".join(SCENARIO_NAMES))
    p.add_argument("--seed", type=int_from_text, default=0, help="random seed (default 0)")
    p.add_argument(
        "--out", default=".", metavar="DIR", help="where to write scenario-NAME.png (default .)"
    )
    p.add_argument("--no-plot", action="store_true", help="metrics only")
    p.add_argument("--json", action="store_true", help="metrics as JSON")


def cmd_scenario(args: argparse.Namespace, out: TextIO) -> int:
    from dataclasses import asdict

    from sim.scenarios import SCENARIOS, format_result, run_scenario

    if args.name not in SCENARIOS:
        raise SimUsageError(f"unknown scenario {args.name!r}; choose from {', '.join(SCENARIOS)}")
    result = run_scenario(args.name, seed=args.seed)
    png: pathlib.Path | None = None
    if not args.no_plot:
        from sim.plot import plot_scenario

        png = plot_scenario(result, pathlib.Path(args.out) / f"scenario-{args.name}.png")
    if args.json:
        doc = {
            "scenario": args.name,
            "seed": args.seed,
            "metrics": result.metrics,
            "depth_steps": [asdict(st) for st in result.steps],
            "plot": str(png) if png else None,
        }
        json.dump(doc, out, indent=1)
        out.write("\n")
        return 0
    out.write(format_result(result) + "\n")
    if png is not None:
        out.write(f"plot: {png}\n")
    return 0


def cmd_sim(args: argparse.Namespace, out: TextIO) -> int:
    import asyncio
    import logging
    import signal

    from rosbridge.server import BridgeServer
    from sim.channel import ChannelConfig
    from sim.environment import CurrentConfig
    from sim.fleet import FleetSimulation
    from sim.simulation import SimConfig, Simulation
    from vehicle_contract.fleet import FleetError, parse_vehicles

    try:
        vehicles = parse_vehicles(args.vehicles)
    except FleetError as err:
        raise SimUsageError(f"--vehicles: {err}") from None
    try:
        channel = ChannelConfig(
            bitrate_bps=args.bitrate,
            range_m=args.range,
            ber=args.ber,
            burst_rate=args.bursts,
            loss=args.loss,
            delay_s=args.delay,
        )
        current = CurrentConfig(north_mps=args.current[0], east_mps=args.current[1])
        config = SimConfig(seed=args.seed, channel=channel, current=current)
        sim: Simulation | FleetSimulation = (
            FleetSimulation(vehicles, config, spacing_m=args.spacing)
            if vehicles
            else Simulation(config)
        )
    except ValueError as err:
        raise SimUsageError(str(err)) from None
    logging.basicConfig(
        level=logging.WARNING if args.quiet else logging.INFO,
        format="%(asctime)s %(name)s %(levelname)s %(message)s",
    )
    server = BridgeServer(sim, args.host, args.port, time_scale=args.time_scale)
    fleet = (
        " fleet of " + ", ".join(f"{v.name} (address {v.address})" for v in vehicles) + ";"
        if vehicles
        else ""
    )

    async def main() -> None:
        await server.start()
        out.write(
            f"NemeSys simulator: rosbridge at ws://{args.host}:{server.port} "
            f"(seed {args.seed}, BER {args.ber:g}, bursts {args.bursts:g}, loss {args.loss:g}, "
            f"range {args.range:g} m, delay {args.delay:g} s, time x{args.time_scale:g});"
            f"{fleet} Ctrl-C stops\n"
        )
        out.flush()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, lambda: asyncio.ensure_future(server.stop()))
        await server.serve_forever()

    try:
        asyncio.run(main())
    except OSError as err:  # e.g. the port is taken
        raise SimUsageError(f"cannot serve on {args.host}:{args.port}: {err.strerror}") from None
    return 0
