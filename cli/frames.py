"""``nemesys patterns``, ``nemesys encode`` and ``nemesys decode``: the command dictionary, a
command encoded into its frame (100 bits; 108, addressed, with ``--vehicle``), and a received
frame decoded (exit 1 when it is rejected: :func:`cli.main.main`)."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any, TextIO

from cli.common import (
    EXIT_OK,
    EXIT_REJECTED,
    encoded_json,
    parse_assignments,
    positive_rate,
    write_snaps,
)
from cli.fleet import add_vehicle_option, decode_text, to_text
from codec import (
    DEFAULT_BITRATE_BPS,
    DICTIONARY,
    AddressedDecoded,
    Decoded,
    DecodeError,
    airtime_s,
    describe_dictionary,
    encode_frame,
    markdown_tables,
    sections,
)
from codec._fields import fmt
from onboard.agent import command_json


def add_parsers(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """The three subcommands' parsers."""
    p = sub.add_parser("patterns", help="list the command dictionary")
    fmt_group = p.add_mutually_exclusive_group()
    fmt_group.add_argument("--json", action="store_true", help="machine-readable output")
    fmt_group.add_argument("--markdown", action="store_true", help="Markdown tables")

    p = sub.add_parser(
        "encode",
        help="encode a command into a frame (100 bits; 108, addressed, with --vehicle)",
        description="Encode PATTERN with every parameter as name=value (units: m, m/s, s, deg).",
    )
    p.add_argument("pattern", metavar="PATTERN", help=", ".join(DICTIONARY))
    p.add_argument("params", nargs="*", metavar="name=value")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument(
        "--bitrate",
        type=positive_rate,
        default=float(DEFAULT_BITRATE_BPS),
        metavar="BPS",
        help=f"link bit rate for the airtime (default {DEFAULT_BITRATE_BPS})",
    )
    add_vehicle_option(p, encode=True)

    p = sub.add_parser(
        "decode",
        help="decode a received frame",
        description="Decode a frame given as 100 binary digits or 25 hex digits (spaces "
        "between groups are ignored), or '-' to read one frame per line from standard input.",
    )
    p.add_argument("frame", nargs="+", metavar="BITS", help="the frame, or - for stdin")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    add_vehicle_option(p, encode=False)


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


def cmd_encode(args: argparse.Namespace, out: TextIO) -> int:
    address = args.vehicle
    enc = encode_frame(args.pattern, parse_assignments(args.params), address=address)
    cmd, frame = enc.command, enc.frame
    bits = frame.bits
    airtime_ms = airtime_s(args.bitrate, len(bits)) * 1e3
    secs = sections(cmd.pattern, addressed=address is not None)
    if args.json:
        doc: dict[str, Any] = {
            **encoded_json(enc),
            **({"address": address} if address is not None else {}),
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
    if address is not None:
        out.write(f"  to              {to_text(address)}\n")
    write_snaps(out, enc.snaps)
    out.write(f"bits     {frame.grouped(cmd.pattern)}\n")
    for s in secs:
        out.write(f"  {s.name:<15} bits {s.start:>2}-{s.start + s.length - 1:<3} ")
        out.write(f"{bits[s.start : s.start + s.length]}\n")
    out.write(f"hex      {frame.hex}\n")
    out.write(f"airtime  {airtime_ms:.3f} ms at {fmt(args.bitrate)} b/s\n")
    return EXIT_OK


# --- decode -------------------------------------------------------------------------------


def _decoded_json(dec: Decoded) -> dict[str, Any]:
    address = {"address": dec.address} if isinstance(dec, AddressedDecoded) else {}
    return {
        **command_json(dec.command),
        "corrected": dec.corrected,
        "sync_errors": dec.sync_errors,
        **address,
    }


def _decoded_text(dec: Decoded) -> str:
    bits = "bit" if dec.corrected == 1 else "bits"
    to = f", to {to_text(dec.address)}" if isinstance(dec, AddressedDecoded) else ""
    return f"{dec.command.describe()}  (corrected {dec.corrected} {bits}{to})"


def _decode_one(
    text: str, as_json: bool, out: TextIO, line: int | None, vehicle: int | None = None
) -> bool:
    where = {"line": line} if line is not None else {}
    try:
        dec = decode_text(text, vehicle)
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
            all_ok &= _decode_one(text, args.json, out, number, args.vehicle)
        return EXIT_OK if all_ok else EXIT_REJECTED
    decoded = _decode_one("".join(args.frame), args.json, out, None, args.vehicle)
    return EXIT_OK if decoded else EXIT_REJECTED


# --- send ---------------------------------------------------------------------------------
