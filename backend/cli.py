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
import json
import os
import sys
from collections.abc import Callable, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from backend import contract_cli
from codec import (
    DEFAULT_BITRATE_BPS,
    DICTIONARY,
    CodecError,
    Decoded,
    DecodeError,
    Encoded,
    EncodeError,
    Snap,
    airtime_s,
    decode_frame,
    describe_dictionary,
    encode_frame,
    int_from_text,
    markdown_tables,
    number_from_text,
    sections,
)
from codec._fields import fmt
from sim_bridge import cli as sim_cli
from sim_bridge.agent import command_json

if TYPE_CHECKING:
    from sim_bridge.transmit import SendResult

EXIT_OK = 0
EXIT_REJECTED = 1
EXIT_USAGE = 2
EXIT_INTERNAL = 70  # EX_SOFTWARE


class UsageError(Exception):
    """Bad command-line input; reported on stderr with exit status 2."""


# --- patterns -----------------------------------------------------------------------------


def cmd_patterns(args: argparse.Namespace, out: TextIO) -> int:
    if args.json:
        json.dump(describe_dictionary(), out, indent=1)
        out.write("\n")
        return EXIT_OK
    if args.markdown:
        out.write(markdown_tables() + "\n")
        return EXIT_OK
    for p in describe_dictionary():
        out.write(f"{p['id']:>2} {p['name']:<10} {p['doc']}\n")
        if not p["fields"]:
            out.write("     (no parameters)\n")
        for f in p["fields"]:
            out.write(
                f"     j{f['j']} {f['name']:<14} {f['unit'] or '-':<4} {f['range']:<16} "
                f"steps {f['steps']};  error {f['error']}\n"
            )
    return EXIT_OK


# --- encode -------------------------------------------------------------------------------


def _parse_assignments(items: Sequence[str]) -> dict[str, str]:
    params: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise UsageError(f"parameters are name=value, got {item!r}")
        if name in params:
            raise UsageError(f"parameter {name!r} given twice")
        params[name] = value
    return params


def _positive_rate(text: str) -> float:
    try:
        rate = number_from_text(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(f"bit rate must be a number in b/s: {err}") from None
    if not rate > 0 or rate == float("inf"):
        raise argparse.ArgumentTypeError(f"bit rate must be a positive number in b/s, got {text}")
    return rate


def _number_or_text(value: object) -> object:
    if isinstance(value, str):
        try:
            return number_from_text(value)
        except ValueError:
            return value
    return value


def _write_snaps(out: TextIO, snaps: Sequence[Snap]) -> None:
    """One line per parameter: the value sent, and what was asked for if it was snapped."""
    for snap in snaps:
        sent = snap.sent if isinstance(snap.sent, str) else fmt(snap.sent)
        unit = f" {snap.unit}" if snap.unit else ""
        note = f"   (requested {snap.requested}{unit})" if snap.changed else ""
        out.write(f"  {snap.field:<15} {sent}{unit}{note}\n")


def _command_json(enc: Encoded) -> dict[str, Any]:
    """The encoded command as JSON: pattern, values sent, values requested, what was snapped."""
    return {
        **command_json(enc.command),
        "requested": {s.field: _number_or_text(s.requested) for s in enc.snaps},
        "snapped": [str(s) for s in enc.snaps if s.changed],
    }


def cmd_encode(args: argparse.Namespace, out: TextIO) -> int:
    enc = encode_frame(args.pattern, _parse_assignments(args.params))
    cmd, frame = enc.command, enc.frame
    airtime_ms = airtime_s(args.bitrate) * 1e3
    bits = frame.bits
    secs = sections(cmd.pattern)
    if args.json:
        doc: dict[str, Any] = {
            **_command_json(enc),
            "units": {f.name: f.unit for f in cmd.pattern.fields},
            "bits": bits,
            "hex": frame.hex,
            "sections": [
                {"name": s.name, "start": s.start, "bits": bits[s.start : s.start + s.length]}
                for s in secs
            ],
            "bitrate_bps": args.bitrate,
            "airtime_ms": airtime_ms,
        }
        json.dump(doc, out)
        out.write("\n")
        return EXIT_OK
    out.write(f"{cmd.pattern.name} (ID {cmd.pattern.id})\n")
    _write_snaps(out, enc.snaps)
    out.write(f"bits     {frame.grouped(cmd.pattern)}\n")
    for s in secs:
        out.write(f"  {s.name:<15} bits {s.start:>2}-{s.start + s.length - 1:<3} ")
        out.write(f"{bits[s.start : s.start + s.length]}\n")
    out.write(f"hex      {frame.hex}\n")
    out.write(f"airtime  {airtime_ms:.3f} ms at {fmt(args.bitrate)} b/s\n")
    return EXIT_OK


# --- decode -------------------------------------------------------------------------------


def _decoded_json(dec: Decoded) -> dict[str, Any]:
    return {
        **command_json(dec.command),
        "corrected": dec.corrected,
        "sync_errors": dec.sync_errors,
    }


def _decoded_text(dec: Decoded) -> str:
    bits = "bit" if dec.corrected == 1 else "bits"
    return f"{dec.command.describe()}  (corrected {dec.corrected} {bits})"


def _decode_one(text: str, as_json: bool, out: TextIO, line: int | None) -> bool:
    where = {"line": line} if line is not None else {}
    try:
        dec = decode_frame(text)
    except DecodeError as err:
        if as_json:
            out.write(json.dumps({**where, "error": str(err), "reason": err.reason.value}) + "\n")
        elif line is not None:
            out.write(f"line {line}: rejected: {err}\n")
        else:
            raise
        return False
    if as_json:
        out.write(json.dumps({**where, **_decoded_json(dec)}) + "\n")
    else:
        prefix = f"line {line}: " if line is not None else ""
        out.write(prefix + _decoded_text(dec) + "\n")
    return True


def cmd_decode(args: argparse.Namespace, out: TextIO) -> int:
    if args.frame == ["-"]:
        all_ok = True
        for number, raw in enumerate(sys.stdin, start=1):
            text = raw.strip()
            if not text or text.startswith("#"):
                continue
            all_ok &= _decode_one(text, args.json, out, number)
        return EXIT_OK if all_ok else EXIT_REJECTED
    return EXIT_OK if _decode_one("".join(args.frame), args.json, out, None) else EXIT_REJECTED


# --- send ---------------------------------------------------------------------------------

#: Where ``nemesys send`` transmits by default: the simulator's rosbridge (``nemesys sim``).
#: Equal to ``sim_bridge.transmit.DEFAULT_ROSBRIDGE_URL`` (not imported: it pulls in asyncio,
#: websockets and pyserial, which the other subcommands don't need).
DEFAULT_SEND_TO = "ws://127.0.0.1:9090"
DEFAULT_SEND_TIMEOUT_S = 5.0


def _seconds(text: str) -> float:
    try:
        value = number_from_text(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(f"timeout must be seconds: {err}") from None
    if not 0 <= value < float("inf"):
        raise argparse.ArgumentTypeError(f"timeout must be 0 or more seconds, got {text}")
    return value


def _utc(t: float) -> str:
    return datetime.fromtimestamp(t, UTC).isoformat(timespec="milliseconds")


def _command_text(command: object) -> str:
    """An acknowledgement's ``command`` ({pattern, params}) as ``circle speed=0.5 m/s ...``."""
    if not isinstance(command, dict):
        return str(command)
    try:
        return encode_frame(command["pattern"], command["params"]).command.describe()
    except (CodecError, KeyError, TypeError, ValueError):
        params = command.get("params") or {}
        words = [str(command.get("pattern"))]
        words += [f"{k}={v}" for k, v in params.items()] if isinstance(params, dict) else []
        return " ".join(words)


def _ack_lines(result: SendResult) -> list[str]:
    ack = result.ack or {}
    seq = f"ack #{ack.get('seq')}"
    if result.accepted:
        note = ", already active: not replanned" if ack.get("duplicate") else ""
        lines = [f"accepted {_command_text(ack.get('command'))}  ({seq}{note})"]
        corrected = ack.get("corrected_bits")
        bits = "bit" if corrected == 1 else "bits"
        lines.append(f"         corrected {corrected} {bits}, sync errors {ack.get('sync_errors')}")
        timing = [
            f"{name} {value:.2f} ms"
            for name in ("decode", "replan")
            if isinstance(value := ack.get(f"{name}_latency_ms"), int | float)
        ]
        if isinstance(waypoints := ack.get("waypoints"), int):
            timing.append(f"{waypoints} waypoints")
        if timing:
            lines.append("         " + ", ".join(timing))
    else:
        field = f" (field {ack['field']})" if ack.get("field") else ""
        lines = [f"rejected {ack.get('reason')}{field}: {ack.get('detail')}  ({seq})"]
    if result.ack_match != "exact":
        lines.append(f"         {result.detail}")
    return lines


def cmd_send(args: argparse.Namespace, out: TextIO) -> int:
    from sim_bridge.transmit import open_transmitter

    try:
        transmitter = open_transmitter(args.to, bitrate_bps=args.bitrate)
    except ValueError as err:
        raise UsageError(f"--to: {err}") from None
    enc = encode_frame(args.pattern, _parse_assignments(args.params))
    cmd, frame = enc.command, enc.frame
    airtime_ms = airtime_s(args.bitrate) * 1e3
    if not args.json:
        out.write(f"send     {cmd.pattern.name} (ID {cmd.pattern.id}) to {args.to}\n")
        _write_snaps(out, enc.snaps)
        out.write(f"hex      {frame.hex}\n")
        out.write(f"airtime  {airtime_ms:.3f} ms at {fmt(args.bitrate)} b/s\n")
        out.flush()
    with transmitter:
        result = transmitter.send(frame, wait_ack_s=args.timeout)
    if args.json:
        doc: dict[str, Any] = {
            **_command_json(enc),
            "hex": frame.hex,
            "bitrate_bps": args.bitrate,
            "airtime_ms": airtime_ms,
            "to": args.to,
            **result.to_json(),
        }
        json.dump(doc, out)
        out.write("\n")
    elif result.sent_t is not None:
        out.write(f"sent     {_utc(result.sent_t)} via {result.transport}\n")
        if result.ack is not None:
            out.write("\n".join(_ack_lines(result)) + "\n")
        elif result.ok:
            out.write(f"         {result.detail}\n")
    if not result.ok:
        print(f"nemesys send: failed: {result.reason}: {result.detail}", file=sys.stderr)
        return EXIT_REJECTED
    if result.accepted is False:
        ack = result.ack or {}
        print(f"nemesys send: rejected: {ack.get('reason')}: {ack.get('detail')}", file=sys.stderr)
        return EXIT_REJECTED
    return EXIT_OK


# --- bench --------------------------------------------------------------------------------


#: The benchmarks: each is ``bench.<name>`` with ``run(out, quick=...)``, imported on use.
BENCHMARKS = ("codec", "planner", "sim", "console", "reconfig", "recovery")


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
    raise UsageError(f"unknown analysis {args.target!r}")


def _serve() -> Any:
    """``backend.serve`` (the console command), imported on use."""
    from backend import serve

    return serve


# --- dispatch -----------------------------------------------------------------------------

Handler = Callable[[argparse.Namespace, TextIO], int]
COMMANDS: dict[str, Handler] = {
    "patterns": cmd_patterns,
    "encode": cmd_encode,
    "decode": cmd_decode,
    "send": cmd_send,
    "console": lambda args, out: _serve().cmd_console(args, out),
    "sim": sim_cli.cmd_sim,
    "scenario": sim_cli.cmd_scenario,
    "bench": cmd_bench,
    "results": cmd_results,
    "analyze": cmd_analyze,
    "contract": contract_cli.cmd_contract,
    "vehicle-check": contract_cli.cmd_vehicle_check,
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="nemesys", description="NemeSys mission codec and console tools."
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("patterns", help="list the command dictionary")
    fmt_group = p.add_mutually_exclusive_group()
    fmt_group.add_argument("--json", action="store_true", help="machine-readable output")
    fmt_group.add_argument("--markdown", action="store_true", help="Markdown tables")

    p = sub.add_parser(
        "encode",
        help="encode a command into a 100-bit frame",
        description="Encode PATTERN with every parameter as name=value (units: m, m/s, s, deg).",
    )
    p.add_argument("pattern", metavar="PATTERN", help=", ".join(DICTIONARY))
    p.add_argument("params", nargs="*", metavar="name=value")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument(
        "--bitrate",
        type=_positive_rate,
        default=float(DEFAULT_BITRATE_BPS),
        metavar="BPS",
        help=f"link bit rate for the airtime (default {DEFAULT_BITRATE_BPS})",
    )

    p = sub.add_parser(
        "decode",
        help="decode a received frame",
        description="Decode a frame given as 100 binary digits or 25 hex digits (spaces "
        "between groups are ignored), or '-' to read one frame per line from standard input.",
    )
    p.add_argument("frame", nargs="+", metavar="BITS", help="the frame, or - for stdin")
    p.add_argument("--json", action="store_true", help="machine-readable output")

    p = sub.add_parser(
        "send",
        help="encode a command and transmit it to the vehicle",
        description="Encode PATTERN (parameters as name=value, as for encode), transmit it to "
        "--to and print the vehicle's acknowledgement when the target gives one. Exit status 0 "
        "accepted (or sent, for targets without acknowledgements), 1 rejected, not sent or not "
        "acknowledged in time, 2 bad input.",
    )
    p.add_argument("pattern", metavar="PATTERN", help=", ".join(DICTIONARY))
    p.add_argument("params", nargs="*", metavar="name=value")
    p.add_argument(
        "--to",
        default=DEFAULT_SEND_TO,
        metavar="TARGET",
        help="ws://host:port[/path] (rosbridge), serial:///dev/ttyUSB0[?baud=115200], "
        f"tcp://host:port (modem gateway), loop:// (default {DEFAULT_SEND_TO})",
    )
    p.add_argument(
        "--timeout",
        type=_seconds,
        default=DEFAULT_SEND_TIMEOUT_S,
        metavar="S",
        help="seconds to wait for the acknowledgement; 0 does not wait "
        f"(default {DEFAULT_SEND_TIMEOUT_S:g})",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument(
        "--bitrate",
        type=_positive_rate,
        default=float(DEFAULT_BITRATE_BPS),
        metavar="BPS",
        help=f"link bit rate: airtime and the gap between frames (default {DEFAULT_BITRATE_BPS})",
    )

    sim_cli.add_parsers(sub)
    _serve().add_parser(sub)
    contract_cli.add_parsers(sub)

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
        "sent r = 1..3 times through the training channel, against 1 - (1 - P1)^r.",
    )
    p.add_argument("target", choices=["ber", "delivery"], help="what to analyze")
    p.add_argument("--trials", type=int_from_text, default=None, help="delivery: commands per BER")
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
