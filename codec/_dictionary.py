"""The command dictionary: pattern IDs and their fields, declared as data.

Table ``tab:command_dict`` of the NemeSys paper gives eight patterns (IDs 0-7) with up to six
parameters j1..j6; we add ``surface`` (ID 15), the safety abort. IDs 8-14 are free: adding a
pattern is adding a :class:`Pattern` to :data:`PATTERNS`, nothing else.
"""

from __future__ import annotations

from codec._fields import (
    COUNT,
    DEPTH,
    DIRECTION,
    DURATION,
    HEADING,
    LENGTH,
    SPEED,
    Field,
    ParamValue,
)
from codec._record import Record, init

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import ItemsView, Iterator, KeysView, Mapping, ValuesView

    from codec._fastpath import StraightLine

    _MappingBase = Mapping[str, "Pattern"]
else:
    # A Mapping to the type checker and to every caller, without collections.abc at run time:
    # importing it loads the collections package, 0.45-0.6 MiB of the vehicle's 1 MiB
    # (``nemesys bench onboard``); CommandDictionary writes the mixin methods out instead.
    _MappingBase = object

#: Width of the pattern ID (bits) and the number of parameter fields in every frame.
PATTERN_ID_BITS = 4
FIELDS_PER_FRAME = 6


class Pattern(Record):
    """One entry of the command dictionary.

    Attributes:
        id: the 4-bit pattern ID.
        name: identifier used by the API and the CLI (``box_orbit``).
        label: the paper's wording (``box orbit``).
        fields: parameters j1.. in wire order; fields after the last are sent as zero.
        doc: what the vehicle does.
    """

    __slots__ = ("doc", "fields", "id", "label", "name")
    id: int
    name: str
    label: str
    fields: tuple[Field, ...]
    doc: str

    def __init__(self, id: int, name: str, label: str, fields: tuple[Field, ...], doc: str) -> None:
        if not 0 <= id < 1 << PATTERN_ID_BITS:
            raise ValueError(f"pattern ID {id} does not fit in {PATTERN_ID_BITS} bits")
        if len(fields) > FIELDS_PER_FRAME:
            raise ValueError(f"{name}: more than {FIELDS_PER_FRAME} fields")
        names = [f.name for f in fields]
        if len(set(names)) != len(names):
            raise ValueError(f"{name}: duplicate field names {names}")
        init(self, "id", id)
        init(self, "name", name)
        init(self, "label", label)
        init(self, "fields", fields)
        init(self, "doc", doc)

    def __repr__(self) -> str:
        return f"<Pattern {self.id} {self.name}>"

    def field(self, name: str) -> Field:
        for f in self.fields:
            if f.name == name:
                return f
        raise KeyError(name)

    @property
    def defaults(self) -> dict[str, ParamValue]:
        return {f.name: f.default for f in self.fields}


# Shared field declarations (each pattern lists them in its own j1..j6 order).
SPEED_F = Field("speed", "cruise speed", "m/s", SPEED, 0.5, "Speed through the water.")
DEPTH_F = Field("depth", "target depth", "m", DEPTH, 5.0, "Depth held by the pattern (z, down).")
DIR_F = Field("direction", "direction", "", DIRECTION, "cw", "Turning sense seen from above.")


def _radius(doc: str, default: float = 5.0, name: str = "radius", label: str = "radius") -> Field:
    return Field(name, label, "m", LENGTH, default, doc)


def _count(name: str, label: str, default: int, doc: str) -> Field:
    return Field(name, label, "", COUNT, default, doc)


PATTERNS: tuple[Pattern, ...] = (
    Pattern(
        0,
        "straight",
        "straight",
        (
            SPEED_F,
            DEPTH_F,
            Field("duration", "duration", "s", DURATION, 60.0, "How long to run the line."),
            Field("heading", "heading", "deg", HEADING, 0.0, "Course over the line, from north."),
        ),
        "Run a straight line on a heading for a time.",
    ),
    Pattern(
        1,
        "square",
        "square",
        (
            SPEED_F,
            DEPTH_F,
            Field("side_span", "side span", "m", LENGTH, 10.0, "Length of each side."),
            DIR_F,
        ),
        "Fly a closed square at constant depth.",
    ),
    Pattern(
        2,
        "lawnmower",
        "lawnmower",
        (
            SPEED_F,
            DEPTH_F,
            Field("sweep_length", "sweep length", "m", LENGTH, 20.0, "Length of each lane."),
            Field("lane_spacing", "lane spacing", "m", LENGTH, 5.0, "Distance between lanes."),
            _count("laps", "# laps", 2, "Number of out-and-back lane pairs."),
        ),
        "Survey a box in parallel lanes (grid search).",
    ),
    Pattern(
        3,
        "circle",
        "circle",
        (SPEED_F, DEPTH_F, _radius("Radius of the circle."), DIR_F),
        "Circle at constant depth.",
    ),
    Pattern(
        4,
        "spiral",
        "spiral",
        (
            SPEED_F,
            DEPTH_F,
            _radius("Radius at the start.", 2.0, "initial_radius", "initial radius"),
            _radius("Radius at the end.", 10.0, "final_radius", "final radius"),
            _count("loops", "# loops", 3, "Number of loops from initial to final radius."),
            DIR_F,
        ),
        "Planar spiral between two radii at constant depth.",
    ),
    Pattern(
        5,
        "helix",
        "helix",
        (
            SPEED_F,
            Field("start_depth", "start depth", "m", DEPTH, 2.0, "Depth at the first turn."),
            Field("end_depth", "end depth", "m", DEPTH, 8.0, "Depth after the last turn."),
            _radius("Radius of the helix."),
            _count("turns", "turns", 3, "Number of full turns between the two depths."),
            DIR_F,
        ),
        "Helix around a vertical axis between two depths (3D inspection).",
    ),
    Pattern(
        6,
        "hover",
        "hover",
        (
            Field("duration", "duration", "s", DURATION, 60.0, "How long to hold station."),
            DEPTH_F,
            Field("heading", "heading", "deg", HEADING, 0.0, "Heading held, from north."),
        ),
        "Hold position, depth and heading.",
    ),
    Pattern(
        7,
        "box_orbit",
        "box orbit",
        (
            SPEED_F,
            DEPTH_F,
            _radius("Half-width of the square orbit around the anchor."),
            DIR_F,
            _count("laps", "# laps", 2, "Number of orbits."),
        ),
        "Orbit a point on a square path.",
    ),
    Pattern(
        15,
        "surface",
        "surface",
        (),
        "Abort: stop the pattern and rise to the surface.",
    ),
)


class CommandDictionary(_MappingBase):
    """Patterns by name, with lookup by ID; validated once at construction.

    A read-only ``Mapping[str, Pattern]`` (names in dictionary order), equal to another
    mapping with the same items, and unhashable, as a :class:`collections.abc.Mapping` is;
    but not registered as one (that module is not loaded onboard), so ``isinstance(d,
    Mapping)`` is false.
    """

    def __init__(self, patterns: tuple[Pattern, ...]) -> None:
        by_id: dict[int, Pattern] = {}
        by_name: dict[str, Pattern] = {}
        for p in patterns:
            if p.id in by_id:
                raise ValueError(f"pattern ID {p.id} used by {by_id[p.id].name} and {p.name}")
            if p.name in by_name:
                raise ValueError(f"pattern name {p.name} used twice")
            by_id[p.id] = p
            by_name[p.name] = p
        self._by_id = by_id
        self._by_name = by_name
        #: The receiver's straight-line decoder for this dictionary (``codec._fastpath``),
        #: built by the first receiver that uses it.
        self.straight_line: StraightLine | None = None

    def __getstate__(self) -> dict[str, object]:
        """Pickled without the straight-line decoder (a closure; rebuilt on first use)."""
        return {**self.__dict__, "straight_line": None}

    def __getitem__(self, name: str) -> Pattern:
        return self._by_name[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._by_name)

    def __len__(self) -> int:
        return len(self._by_name)

    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    def __eq__(self, other: object) -> bool:
        if isinstance(other, CommandDictionary):
            return self._by_name == other._by_name
        if isinstance(other, dict):
            return self._by_name == other
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]  # as Mapping: equal by value, so unhashable

    def keys(self) -> KeysView[str]:
        return self._by_name.keys()

    def values(self) -> ValuesView[Pattern]:
        return self._by_name.values()

    def items(self) -> ItemsView[str, Pattern]:
        return self._by_name.items()

    if not TYPE_CHECKING:  # Mapping's overloads are what the type checker sees

        def get(self, name, default=None):
            return self._by_name.get(name, default)

    def by_id(self, pattern_id: int) -> Pattern | None:
        return self._by_id.get(pattern_id)

    def lookup(self, pattern: str | int) -> Pattern:
        """Pattern by name (``box_orbit``, ``box-orbit``, ``Box Orbit``) or ID (``7``).

        Text is ASCII only: a name in any case with ``-`` or a space for ``_``, or an ID in
        ASCII digits (``7``, ``07``); surrounding spaces and tabs are ignored. Other digits
        (``٣``, ``¹``) and look-alike letters name no pattern.

        Raises:
            EncodeError: no such pattern; the message quotes (the start of) what was given
                and lists the known ones.
        """
        from codec._lookup import lookup_pattern  # the console's: not loaded onboard

        return lookup_pattern(self, pattern)


#: The dictionary the vehicle and the console share.
DICTIONARY = CommandDictionary(PATTERNS)


class Command(Record):
    """A pattern with one valid code per field: exactly what goes on the wire.

    Build it with :func:`make_command` (from physical values) or ``Command(pattern, codes)``.
    """

    __slots__ = ("codes", "pattern")
    pattern: Pattern
    codes: tuple[int, ...]

    def __init__(self, pattern: Pattern, codes: tuple[int, ...]) -> None:
        fields = pattern.fields
        if len(codes) != len(fields):
            raise ValueError(f"{pattern.name} takes {len(fields)} codes, got {len(codes)}")
        for f, code in zip(fields, codes, strict=True):
            if not f.scale.is_valid_code(code):
                raise ValueError(f"code {code} is not valid for {f.name}")
        init(self, "pattern", pattern)
        init(self, "codes", codes)

    def __repr__(self) -> str:
        return f"<Command {self.describe()}>"

    @property
    def params(self) -> dict[str, ParamValue]:
        """Field name -> the value the vehicle will use (SI units)."""
        return {f.name: f.value_of(c) for f, c in zip(self.pattern.fields, self.codes, strict=True)}

    def describe(self) -> str:
        """``square speed=0.5 m/s depth=2 m side_span=10 m direction=cw``."""
        parts = [self.pattern.name]
        for f, value in zip(self.pattern.fields, self.params.values(), strict=True):
            text = value if isinstance(value, str) else format(value, ".10g")
            parts.append(f"{f.name}={text}{' ' + f.unit if f.unit else ''}")
        return " ".join(parts)
