"""The ``nemesys`` command line.

Subcommands are dispatched through :data:`COMMANDS`; each handler returns the exit status.
Exit status: 0 success, 1 a frame was rejected (or, for ``send``, not sent or not
acknowledged), 2 bad input (usage, out-of-range value, bad target),
70 an internal error (a bug: reported in one line; ``NEMESYS_DEBUG=1`` shows the traceback).
Errors are one line on standard error, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from cli import contract as contract_cli
from cli import export as export_cli
from cli import frames as frames_cli
from cli import send as send_cli
from cli import sim as sim_cli
from cli.common import (
    EXIT_INTERNAL,
    EXIT_OK,
    EXIT_REJECTED,
    EXIT_USAGE,
    UsageError,
)
from cli.send import cmd_send
from codec import (
    CodecError,
    DecodeError,
    EncodeError,
    int_from_text,
)

if TYPE_CHECKING:
    pass

# --- bench --------------------------------------------------------------------------------


#: The benchmarks: each is ``bench.<name>`` with ``run(out, quick=...)``, imported on use.
BENCHMARKS = (
    "codec",
    "planner",
    "sim",
    "console",
    "reconfig",
    "onboard",
    "recovery",
    "channel_estimate",
    "durations",
    "dead_reckoning",
    "export",
    "control_sync",
    "relay",
    "fleet_cost",
)


def cmd_bench(args: argparse.Namespace, out: TextIO) -> int:
    if args.target not in BENCHMARKS:
        raise UsageError(f"unknown benchmark {args.target!r}")
    options = {k: v for k in ("kills", "seed") if (v := getattr(args, k, None)) is not None}
    if options and args.target != "recovery":
        raise UsageError("--kills and --seed are options of the recovery benchmark")
    if options.get("kills", 1) < 1:
        raise UsageError(f"--kills must be at least 1, got {options['kills']}")
    bench = importlib.import_module(f"bench.{args.target}")
    status: int = bench.run(out, quick=args.quick, **options)
    return status


def cmd_results(args: argparse.Namespace, out: TextIO) -> int:
    from analysis import results

    path = results.generate(
        args.out or results.DEFAULT_MD,
        args.img_dir or results.DEFAULT_IMG_DIR,
        quick=args.quick,
        progress=sys.stderr,
    )
    out.write(f"{path}\n")
    return EXIT_OK


def cmd_analyze(args: argparse.Namespace, out: TextIO) -> int:
    if args.target == "ber":
        from analysis import ber

        report = ber.analyze(
            args.out or ber.DEFAULT_OUT_DIR, quick=args.quick, seed=args.seed, progress=sys.stderr
        )
        out.write(ber.format_report(report))
        return EXIT_OK
    if args.target == "delivery":
        from analysis import delivery

        if args.trials is not None and args.trials < 1:
            raise UsageError(f"--trials must be at least 1, got {args.trials}")
        return delivery.main(out, args.trials or delivery.DEFAULT_TRIALS, args.seed)
    if args.target == "addressing":
        from analysis import addressing_report

        if args.trials is not None and args.trials < 1:
            raise UsageError(f"--trials must be at least 1, got {args.trials}")
        return addressing_report.main(out, args.trials, args.seed, args.quick, sys.stderr)
    if args.target == "surface-all":
        from analysis import surface_all

        if args.trials is not None and args.trials < 1:
            raise UsageError(f"--trials must be at least 1, got {args.trials}")
        return surface_all.main(out, args.trials, args.seed, args.quick)
    raise UsageError(f"unknown analysis {args.target!r}")


def _serve() -> Any:
    """``backend.serve`` (the console command), imported on use."""
    from backend import serve

    return serve


# --- dispatch -----------------------------------------------------------------------------

Handler = Callable[[argparse.Namespace, TextIO], int]
COMMANDS: dict[str, Handler] = {
    "patterns": frames_cli.cmd_patterns,
    "encode": frames_cli.cmd_encode,
    "decode": frames_cli.cmd_decode,
    "send": cmd_send,
    "console": lambda args, out: _serve().cmd_console(args, out),
    "sim": sim_cli.cmd_sim,
    "scenario": sim_cli.cmd_scenario,
    "bench": cmd_bench,
    "results": cmd_results,
    "analyze": cmd_analyze,
    "contract": contract_cli.cmd_contract,
    "vehicle-check": contract_cli.cmd_vehicle_check,
    "export": export_cli.cmd_export,
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="nemesys", description="NemeSys mission codec and console tools."
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    frames_cli.add_parsers(sub)
    send_cli.add_parser(sub)

    sim_cli.add_parsers(sub)
    _serve().add_parser(sub)
    contract_cli.add_parsers(sub)
    export_cli.add_parser(sub)

    p = sub.add_parser("bench", help="run a benchmark and print its table")
    p.add_argument("target", choices=BENCHMARKS, help="what to benchmark")
    p.add_argument("--quick", action="store_true", help="fewer repetitions (smoke run)")
    p.add_argument("--kills", type=int_from_text, help="recovery: console kills (default 20)")
    p.add_argument("--seed", type=int_from_text, help="recovery: random seed (default 0)")

    p = sub.add_parser(
        "results",
        help="regenerate docs/results.md: the paper's tables and figures beside ours",
        description="Run the BER analysis, the reconfiguration benchmark and the twin's "
        "reproductions, and write the Markdown page and its images.",
    )
    p.add_argument("--quick", action="store_true", help="smoke-run sizes (under a minute)")
    p.add_argument("--out", type=Path, default=None, help="the page (default docs/results.md)")
    p.add_argument(
        "--img-dir", type=Path, default=None, help="images and data (default docs/results/)"
    )

    p = sub.add_parser(
        "analyze",
        help="reproduce a figure of the paper by simulation (CSV + PNG)",
        description="ber: decoding success vs bit error rate for T = 1..4 (Monte Carlo through "
        "the real frame and decoder, against the analytic curve), coding efficiency, and the "
        "rate of wrong commands accepted with and without the CRC-4. delivery: one command "
        "sent r = 1..3 times through the training channel, against 1 - (1 - P1)^r. "
        "addressing: the ways to address vehicles on one link compared (misaddressed "
        "acceptance and lost frames, analytic and Monte Carlo), and the one chosen. "
        "surface-all: copies and time to get Surface to all of N = 1, 5, 10 vehicles at "
        "p >= 0.999 on a one-way link at BER 1e-2, against a Surface per vehicle.",
    )
    p.add_argument(
        "target",
        choices=["ber", "delivery", "addressing", "surface-all"],
        help="what to analyze",
    )
    p.add_argument(
        "--trials",
        type=int_from_text,
        default=None,
        help="delivery: commands per BER; addressing: frames per design and condition; "
        "surface-all: Monte Carlo trials per fleet size",
    )
    p.add_argument("--quick", action="store_true", help="fewer frames (under a minute)")
    p.add_argument(
        "--out",
        type=Path,
        default=None,
        metavar="DIR",
        help="output directory (default docs/results)",
    )
    p.add_argument("--seed", type=int_from_text, default=0, help="random seed (default 0)")
    return parser


def main(argv: Sequence[str] | None = None, out: TextIO | None = None) -> int:
    """Entry point of the ``nemesys`` console script; returns the exit status."""
    stream = out if out is not None else sys.stdout
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse already printed its message
        return int(exc.code) if isinstance(exc.code, int) else EXIT_USAGE
    try:
        return COMMANDS[args.command](args, stream)
    except DecodeError as err:
        print(f"nemesys {args.command}: rejected: {err}", file=sys.stderr)
        return EXIT_REJECTED
    except (EncodeError, UsageError, CodecError, sim_cli.SimUsageError) as err:
        print(f"nemesys {args.command}: {err}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:  # e.g. piped into head
        return EXIT_OK
    except KeyboardInterrupt:
        return 130
    except Exception as err:  # a bug of ours: one line for the user, details on request
        if os.environ.get("NEMESYS_DEBUG"):
            raise
        print(
            f"nemesys {args.command}: internal error: {type(err).__name__}: {err} "
            "(set NEMESYS_DEBUG=1 for the traceback, and please report it)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
