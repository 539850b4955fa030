"""``nemesys send``: one command to a vehicle from the command line, through the console's own
send policy (:func:`backend.commands.service.decide`), run in this process.

The command line does not know where the vehicle is: the checks plan the command from the
surface at the NED origin (said in the output), with the limits and the vehicle profile of the
settings (``NEMESYS_*``, as the console reads them); a rosbridge vehicle's topics are under the
settings' ``vehicle_namespace``. A hard violation is refused; a soft one
needs ``--override``; either way nothing is transmitted unless the policy allows it. A station
whose consoles share a mission log (``NEMESYS_DATABASE_URL``) refuses: there a command goes
through a console, which checks who is in control of the vehicle and logs it.
"""

from __future__ import annotations

import argparse
import json
import sys
from datetime import UTC, datetime
from typing import TYPE_CHECKING, Any, TextIO

from cli.common import (
    EXIT_OK,
    EXIT_REJECTED,
    EXIT_USAGE,
    UsageError,
    encoded_json,
    parse_assignments,
    positive_rate,
    write_snaps,
)
from codec import (
    DEFAULT_BITRATE_BPS,
    DICTIONARY,
    CodecError,
    airtime_s,
    encode_frame,
    number_from_text,
)
from codec._fields import fmt

if TYPE_CHECKING:
    from backend.commands.service import Assessment
    from station.transmit import SendResult

#: Where ``nemesys send`` transmits by default: the simulator's rosbridge (``nemesys sim``).
#: Equal to ``station.transmit.DEFAULT_ROSBRIDGE_URL`` (not imported: it pulls in asyncio,
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
    from backend.settings import Settings
    from station.transmit import open_transmitter

    settings = Settings()
    if settings.database_url:  # consoles share a log: control of the vehicle is theirs to check
        raise UsageError(
            "NEMESYS_DATABASE_URL is set: this station shares its mission log with other "
            "consoles, and a command goes through a console, where who is in control of the "
            "vehicle is checked and the command is logged (its page, or POST /api/commands); "
            "nothing was transmitted"
        )
    namespace = settings.vehicle_namespace  # the vehicle's topics: /<it>/nemesys/...
    try:
        transmitter = open_transmitter(args.to, bitrate_bps=args.bitrate, namespace=namespace)
    except ValueError as err:
        raise UsageError(f"--to: {err}") from None
    params = parse_assignments(args.params)
    assessment = assess(args.pattern, params)
    refused = _refusal(assessment, args.override)
    if refused is not None:
        print(f"nemesys send: refused, nothing transmitted: {refused}", file=sys.stderr)
        return EXIT_USAGE
    enc = assessment.enc
    cmd, frame = enc.command, enc.frame
    airtime_ms = airtime_s(args.bitrate) * 1e3
    if not args.json:
        out.write(f"send     {cmd.pattern.name} (ID {cmd.pattern.id}) to {args.to}\n")
        write_snaps(out, enc.snaps)
        for line in _check_lines(assessment):
            out.write(line + "\n")
        out.write(f"hex      {frame.hex}\n")
        out.write(f"airtime  {airtime_ms:.3f} ms at {fmt(args.bitrate)} b/s\n")
        out.flush()
    with transmitter:
        result = transmitter.send(frame, wait_ack_s=args.timeout)
    if args.json:
        doc: dict[str, Any] = {
            **encoded_json(enc),
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


def assess(pattern: str, params: dict[str, Any]) -> Assessment:
    """The console's checks of ``pattern``, planned from the surface at the NED origin, with
    the settings' limits and vehicle profile.

    Raises:
        codec.EncodeError / planner.PlanError: a value the frame cannot carry, named.
    """
    from backend.authoring.assess import assess_from
    from backend.authoring.profile import profile_for
    from backend.settings import Settings

    settings = Settings()
    return assess_from(pattern, params, settings, profile_for(settings))


def _refusal(assessment: Assessment, override: bool) -> str | None:
    from backend.commands.service import SendRefused, decide

    try:
        decide(assessment, override)
    except SendRefused as err:
        hint = " (--override accepts it)" if err.status == 409 else ""
        return f"{err}{hint}"
    return None


def _check_lines(assessment: Assessment) -> list[str]:
    """What the checks found, and what they assumed."""
    lines = ["checked  from the surface at the NED origin (the vehicle's position is unknown here)"]
    lines += [f"override {v.message}" for v in assessment.soft]
    return lines


def add_parser(sub: Any) -> None:
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
        type=positive_rate,
        default=float(DEFAULT_BITRATE_BPS),
        metavar="BPS",
        help=f"link bit rate: airtime and the gap between frames (default {DEFAULT_BITRATE_BPS})",
    )
    p.add_argument(
        "--override",
        action="store_true",
        help="accept the limit violations an operator may override (never the depth rating)",
    )
