"""``nemesys contract`` and ``nemesys vehicle-check``: the vehicle contract from the command
line.

Registered by :mod:`cli.main` (:func:`add_parsers`); the handlers return the exit status.
Nothing heavy is imported until a handler runs.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from typing import TextIO

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_USAGE = 2


def _positive_seconds(text: str) -> float:
    from codec import number_from_text

    try:
        value = number_from_text(text)  # ASCII digits only
    except ValueError as err:
        raise argparse.ArgumentTypeError(f"must be seconds: {err}") from None
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be more than 0 seconds, got {text}")
    return value


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "contract",
        help="print the vehicle contract: topics, QoS, time base, message schemas",
        description="Print the contract between the console and a NemeSys vehicle as JSON "
        "({version, topics, time_base, schemas: {ack, status}, ...}), or as the Markdown of "
        "docs/vehicle.md.",
    )
    p.add_argument("--markdown", action="store_true", help="the page docs/vehicle.md")

    p = sub.add_parser(
        "vehicle-check",
        help="check a running vehicle against the vehicle contract",
        description="Connect to a vehicle's rosbridge websocket as the console does and check "
        "it against the contract: topics, types and the vehicle's nodes at their ends (rosapi; "
        "rosbridge's own node does not count), whether the onboard agent runs, pose rate and "
        "age, status rate and schema, and the acknowledgement path: a deliberately malformed "
        "frame must come back rejected (harmless, on a fresh vehicle too), and with a command "
        "running, a repeat of it must be a duplicate (the only frames it sends). Exit status 0 "
        "when no check failed, 1 otherwise, 2 for bad usage.",
    )
    p.add_argument("url", metavar="URL", help="ws://host:port or wss://host:port")
    p.add_argument(
        "--modem",
        metavar="TARGET",
        help="send the probe frames through this ME modem (tcp://host:port, "
        "serial:///dev/...), for a vehicle that takes frames over its own ME receiver; the "
        "acknowledgements still come back over rosbridge",
    )
    p.add_argument(
        "--namespace",
        metavar="NS",
        default=os.environ.get("NEMESYS_VEHICLE_NAMESPACE", ""),
        help="the vehicle's ROS namespace: its topics are /NS/nemesys/... (default: "
        "NEMESYS_VEHICLE_NAMESPACE, else none)",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument(
        "--timeout",
        type=_positive_seconds,
        default=3.0,
        metavar="S",
        help="seconds to wait for each answer (rosapi, the acknowledgement; default 3)",
    )
    p.add_argument(
        "--window",
        type=_positive_seconds,
        default=3.0,
        metavar="S",
        help="seconds over which rates are measured (default 3)",
    )


def cmd_contract(args: argparse.Namespace, out: TextIO) -> int:
    if args.markdown:
        from vehicle_contract.doc import render_markdown

        out.write(render_markdown())
        return EXIT_OK
    from vehicle_contract.contract import contract_json

    json.dump(contract_json(), out, indent=2)
    out.write("\n")
    return EXIT_OK


def cmd_vehicle_check(args: argparse.Namespace, out: TextIO) -> int:
    import asyncio

    from station.vehicle_check import check_vehicle, modem_problem, url_problem
    from vehicle_contract.names import check_namespace

    problem = url_problem(args.url)
    if problem is None and args.modem is not None:
        problem = modem_problem(args.modem)
    if problem is None:
        try:
            check_namespace(args.namespace)
        except ValueError as err:
            problem = f"--namespace: {err}"
    if problem is not None:
        print(f"nemesys vehicle-check: {problem}", file=sys.stderr)
        return EXIT_USAGE
    report = asyncio.run(
        check_vehicle(
            args.url,
            timeout_s=args.timeout,
            window_s=args.window,
            modem=args.modem,
            namespace=args.namespace,
        )
    )
    if args.json:
        json.dump(report.as_json(), out, indent=2)
    else:
        out.write(report.table())
    out.write("\n")
    return EXIT_OK if report.ok else EXIT_FAILED
