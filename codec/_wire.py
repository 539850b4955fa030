"""The console's side of the frame: encoding (pattern lookup, snapping, the frame's bits)
and the frame's sections for display. The lookup of a pattern's name is :mod:`codec._lookup`
(still importable from here), which the dictionary calls without importing this module.

:mod:`codec._frame` holds the layout and what the vehicle runs (the codeword's decode and
checks); this module is loaded on first use of one of its names from :mod:`codec`, so the
onboard process never loads it.
"""

from __future__ import annotations

from codec._dictionary import (
    DICTIONARY,
    FIELDS_PER_FRAME,
    Command,
    CommandDictionary,
    Pattern,
)
from codec._errors import EncodeError
from codec._frame import (
    CODE,
    CODEWORD_BITS,
    CRC4_REMAINDER,
    CRC_BITS,
    DEFAULT_BITRATE_BPS,
    FRAME_BITS,
    GUARD_BITS,
    SECTION_BITS,
    SYNC_WORD,
    Frame,
)
from codec._lookup import lookup_pattern
from codec._record import Record, init
from codec._scales import FIELD_BITS, ParamValue
from codec._snap import Snap

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Mapping

__all__ = [
    "Encoded",
    "Section",
    "airtime_s",
    "encode_frame",
    "frame_of",
    "lookup_pattern",
    "make_command",
    "message_of",
    "payload_of",
    "sections",
]


def make_command(
    pattern: str | int | Pattern,
    params: Mapping[str, ParamValue],
    dictionary: CommandDictionary = DICTIONARY,
) -> tuple[Command, tuple[Snap, ...]]:
    """Snap requested values to the dictionary and build the command.

    Every field of the pattern must be given, and nothing else.

    Returns:
        The command and one :class:`Snap` per field, in field order (``snap.changed`` tells
        which values moved).

    Raises:
        EncodeError: unknown pattern, missing or unknown parameter, or a value out of range;
            the message names the parameter, its unit and what is allowed.
    """
    spec = pattern if isinstance(pattern, Pattern) else dictionary.lookup(pattern)
    allowed = [f.name for f in spec.fields]
    unknown = [name for name in params if name not in allowed]
    if unknown:
        takes = ", ".join(allowed) if allowed else "no parameters"
        raise EncodeError(
            f"{spec.name} has no parameter {', '.join(map(repr, unknown))}: it takes {takes}",
            field=unknown[0],
        )
    missing = [f for f in spec.fields if f.name not in params]
    if missing:
        need = ", ".join(f"{f.name} ({f.scale.range_text(f.unit)})" for f in missing)
        raise EncodeError(f"{spec.name} needs {need}", field=missing[0].name)
    codes: list[int] = []
    snaps: list[Snap] = []
    for f in spec.fields:
        code, sent = f.snap(params[f.name])
        codes.append(code)
        snaps.append(Snap(f.name, f.unit, params[f.name], sent))
    return Command(spec, tuple(codes)), tuple(snaps)


class Section(Record):
    """A named bit range of the frame, for display: ``bits[start:start + length]``."""

    __slots__ = ("length", "name", "start")
    name: str
    start: int
    length: int

    def __init__(self, name: str, start: int, length: int) -> None:
        init(self, "name", name)
        init(self, "start", start)
        init(self, "length", length)


def sections(pattern: Pattern | None = None, *, addressed: bool = False) -> tuple[Section, ...]:
    """The frame's sections in order (the widths of :data:`codec._frame.SECTION_BITS`, or of
    :data:`codec._address.ADDRESSED_SECTION_BITS` for an addressed frame); field sections take
    the pattern's field names."""
    fields = pattern.fields if pattern is not None else ()
    widths = SECTION_BITS
    if addressed:
        from codec._address import ADDRESSED_SECTION_BITS

        widths = ADDRESSED_SECTION_BITS
    names = [
        "preamble",
        "delimiter",
        *(("address", "address_check") if addressed else ()),
        "pattern",
        *(f.name for f in fields[:FIELDS_PER_FRAME]),
        *(f"j{j + 1} (unused)" for j in range(len(fields), FIELDS_PER_FRAME)),
        "crc",
        "parity",
        "guard",
    ]
    out = []
    start = 0
    for name, width in zip(names, widths, strict=True):
        out.append(Section(name, start, width))
        start += width
    return tuple(out)


def airtime_s(bitrate_bps: float = DEFAULT_BITRATE_BPS, bits: int = FRAME_BITS) -> float:
    """Time on the link for ``bits`` at ``bitrate_bps`` (s)."""
    if not bitrate_bps > 0:
        raise ValueError(f"bit rate must be positive, got {bitrate_bps} b/s")
    return bits / bitrate_bps


class Encoded(Record):
    """An encoded command: what was asked, what is sent, and the frame.

    ``snaps`` has one entry per field when the command was built from requested values, and
    is empty when a ready :class:`Command` was encoded (nothing was requested or snapped).
    """

    __slots__ = ("command", "frame", "snaps")
    command: Command
    snaps: tuple[Snap, ...]
    frame: Frame

    def __init__(self, command: Command, snaps: tuple[Snap, ...], frame: Frame) -> None:
        init(self, "command", command)
        init(self, "snaps", snaps)
        init(self, "frame", frame)


def payload_of(command: Command) -> int:
    """The 52-bit payload: pattern ID then six 8-bit fields, unused fields zero."""
    payload = command.pattern.id
    codes = command.codes
    for j in range(FIELDS_PER_FRAME):
        payload = (payload << FIELD_BITS) | (codes[j] if j < len(codes) else 0)
    return payload


def message_of(command: Command) -> int:
    """The 56-bit BCH message: payload then its CRC-4."""
    payload = payload_of(command)
    return (payload << CRC_BITS) | CRC4_REMAINDER(payload)


def frame_of(command: Command, address: int | None = None) -> Frame:
    """The frame that carries ``command``: today's 100-bit frame, or with an ``address`` (0:
    all vehicles, 1-15: one) the 108-bit addressed frame (docs/protocol.md, "Addressing").

    Raises:
        ValueError: an address out of range, naming the allowed one.
    """
    if address is not None:
        from codec._address import addressed_frame_of

        return addressed_frame_of(payload_of(command), address)
    codeword = CODE.encode(message_of(command))
    return Frame((SYNC_WORD << (CODEWORD_BITS + GUARD_BITS)) | (codeword << GUARD_BITS))


def encode_frame(
    pattern: str | int | Pattern | Command,
    params: Mapping[str, ParamValue] | None = None,
    /,
    dictionary: CommandDictionary = DICTIONARY,
    address: int | None = None,
    **kwargs: ParamValue,
) -> Encoded:
    """Encode a command: ``encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw")``.

    ``pattern`` is a name or ID (then the parameters come as a mapping and/or keywords), or a
    ready :class:`Command` (then no parameters). ``address``: ``None`` for today's frame (no
    fleet), else the vehicle the addressed frame is for (0: all vehicles).

    Raises:
        EncodeError: unknown pattern, missing/unknown parameter, value out of range, an
            address out of range.
    """
    if address is not None:
        from codec._address import check_address

        try:
            check_address(address)
        except ValueError as err:
            raise EncodeError(str(err)) from None
    if isinstance(pattern, Command):
        if params or kwargs:
            raise TypeError("a Command already holds its parameters")
        command = pattern
        snaps: tuple[Snap, ...] = ()
    else:
        command, snaps = make_command(pattern, {**(params or {}), **kwargs}, dictionary)
    return Encoded(command, snaps, frame_of(command, address))
