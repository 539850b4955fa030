"""``nemesys encode/decode --vehicle N``: a fleet's addressed frames on the command line
(docs/protocol.md, "Addressing")."""

from __future__ import annotations

import argparse

from codec import (
    ADDRESSED_FRAME_BITS,
    BROADCAST_ADDRESS,
    MAX_ADDRESS,
    Decoded,
    decode_addressed_frame,
    decode_frame,
    int_from_text,
)


def _address(text: str, low: int, allowed: str) -> int:
    try:
        value = int_from_text(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"vehicle address {text!r} is not a whole number: {allowed}"
        ) from None
    if not low <= value <= MAX_ADDRESS:
        raise argparse.ArgumentTypeError(f"vehicle address {value} is out of range: {allowed}")
    return value


def frame_address(text: str) -> int:
    """``encode --vehicle N``: whom the addressed frame is for, 0 (all vehicles) to 15."""
    return _address(text, BROADCAST_ADDRESS, f"allowed 0 (all vehicles) or 1 to {MAX_ADDRESS}")


def vehicle_address(text: str) -> int:
    """``decode --vehicle N``: the vehicle deciding, 1 to 15 (0 is every vehicle's)."""
    return _address(text, 1, f"a vehicle's own address is 1 to {MAX_ADDRESS} (0 addresses all)")


def add_vehicle_option(parser: argparse.ArgumentParser, *, encode: bool) -> None:
    if encode:
        parser.add_argument(
            "--vehicle",
            type=frame_address,
            default=None,
            metavar="N",
            help="a fleet's addressed frame (108 bits) for vehicle N, 1-15, or 0 for all "
            "vehicles (default: the single-vehicle 100-bit frame)",
        )
        return
    parser.add_argument(
        "--vehicle",
        type=vehicle_address,
        default=None,
        metavar="N",
        help="decide as vehicle N (1-15) of a fleet: it takes frames addressed to it or to "
        "all, and unaddressed only surface (default: the console's reading; an addressed "
        "frame, 108 binary or 27 hex digits, says whom it is for)",
    )


def to_text(address: int) -> str:
    return "all vehicles" if address == BROADCAST_ADDRESS else f"vehicle {address}"


def _is_addressed(text: str) -> bool:
    """Whether ``text`` has an addressed frame's length (108 binary or 27 hex digits)."""
    compact = text.strip().replace(" ", "").replace("_", "").removeprefix("0x")
    return len(compact) in (ADDRESSED_FRAME_BITS, ADDRESSED_FRAME_BITS // 4)


def decode_text(text: str, vehicle: int | None) -> Decoded:
    """As ``vehicle`` decides (:func:`codec.decode_frame`); without one, a 100-bit frame as
    today and an addressed one as the console reads it (any address, which it says)."""
    if vehicle is None and _is_addressed(text):
        return decode_addressed_frame(text)
    return decode_frame(text, vehicle=vehicle)
