"""The command dictionary: patterns, lookup, make_command, and adding a pattern as data."""

from __future__ import annotations

import random

import pytest

from codec import (
    DICTIONARY,
    FIELDS_PER_FRAME,
    PATTERN_ID_BITS,
    PATTERNS,
    Command,
    CommandDictionary,
    DecodeError,
    EncodeError,
    Field,
    FrameReceiver,
    ParamValue,
    Pattern,
    RejectReason,
    decode_frame,
    encode_frame,
    make_command,
    sections,
)
from tests.codec.helpers import random_bits, representable, summary

#: Table tab:command_dict of the paper (IDs 0-7, fields j1.. in order) plus surface on 15.
PAPER = [
    (0, "straight", ("speed", "depth", "duration", "heading")),
    (1, "square", ("speed", "depth", "side_span", "direction")),
    (2, "lawnmower", ("speed", "depth", "sweep_length", "lane_spacing", "laps")),
    (3, "circle", ("speed", "depth", "radius", "direction")),
    (4, "spiral", ("speed", "depth", "initial_radius", "final_radius", "loops", "direction")),
    (5, "helix", ("speed", "start_depth", "end_depth", "radius", "turns", "direction")),
    (6, "hover", ("duration", "depth", "heading")),
    (7, "box_orbit", ("speed", "depth", "radius", "direction", "laps")),
    (15, "surface", ()),
]

UNITS = {
    "speed": "m/s",
    "depth": "m",
    "start_depth": "m",
    "end_depth": "m",
    "duration": "s",
    "heading": "deg",
    "side_span": "m",
    "sweep_length": "m",
    "lane_spacing": "m",
    "radius": "m",
    "initial_radius": "m",
    "final_radius": "m",
    "laps": "",
    "loops": "",
    "turns": "",
    "direction": "",
}


def test_widths() -> None:
    assert PATTERN_ID_BITS == 4
    assert FIELDS_PER_FRAME == 6


@pytest.mark.parametrize(("pattern_id", "name", "fields"), PAPER)
def test_patterns_follow_the_paper(pattern_id: int, name: str, fields: tuple[str, ...]) -> None:
    pattern = DICTIONARY[name]
    assert pattern.id == pattern_id
    assert pattern.name == name
    assert tuple(f.name for f in pattern.fields) == fields
    assert DICTIONARY.by_id(pattern_id) is pattern
    assert DICTIONARY.lookup(pattern_id) is pattern
    assert DICTIONARY.lookup(name) is pattern
    assert pattern.label
    assert pattern.doc
    for f in pattern.fields:
        assert f.unit == UNITS[f.name], f.name
        assert f.label
        assert f.doc


def test_dictionary_holds_exactly_those_patterns() -> None:
    assert list(DICTIONARY) == [name for _, name, _ in PAPER]
    assert len(DICTIONARY) == len(PAPER)
    assert [p.id for p in PATTERNS] == [i for i, _, _ in PAPER]
    assert "circle" in DICTIONARY
    assert "zigzag" not in DICTIONARY


@pytest.mark.parametrize("pattern_id", range(8, 15))
def test_ids_8_to_14_are_free(pattern_id: int) -> None:
    assert DICTIONARY.by_id(pattern_id) is None
    with pytest.raises(EncodeError):
        DICTIONARY.lookup(pattern_id)


def test_surface_has_no_parameters() -> None:
    surface = DICTIONARY.by_id(15)
    assert surface is not None
    assert surface.name == "surface"
    assert surface.fields == ()
    command, snaps = make_command("surface", {})
    assert command.codes == ()
    assert command.params == {}
    assert snaps == ()


@pytest.mark.parametrize(
    "name",
    ["box_orbit", "box-orbit", "Box Orbit", "BOX_ORBIT", " box orbit ", "Box-Orbit", "7", " 7 "],
)
def test_lookup_name_variants(name: str) -> None:
    assert DICTIONARY.lookup(name) is DICTIONARY["box_orbit"]


@pytest.mark.parametrize(("key", "name"), [(0, "straight"), ("0", "straight"), (15, "surface")])
def test_lookup_by_id(key: int | str, name: str) -> None:
    assert DICTIONARY.lookup(key).name == name


@pytest.mark.parametrize(
    "key", ["zigzag", "", "box__orbit", "boxorbit", "8", "16", 8, 16, -1, True, False, 7.0, None]
)
def test_unknown_pattern_lists_the_known_ones(key: object) -> None:
    with pytest.raises(EncodeError) as err:
        DICTIONARY.lookup(key)  # type: ignore[arg-type]
    text = str(err.value)
    assert err.value.field is None
    assert repr(key) in text
    for pattern_id, name, _ in PAPER:
        assert f"{name} ({pattern_id})" in text
    with pytest.raises(EncodeError):
        make_command(key, {})  # type: ignore[arg-type]


@pytest.mark.parametrize(
    "key",
    [
        "\u0663",  # ARABIC-INDIC DIGIT THREE: str.isdigit() and int() accept it
        "\u00b9",  # SUPERSCRIPT ONE: str.isdigit() accepts it, int() raises ValueError
        "\uff13",  # FULLWIDTH DIGIT THREE
        "\u20033",  # an EM SPACE before an ASCII 3: only ASCII spaces are stripped
        "\u212aircle",  # KELVIN SIGN lower-cases to an ASCII k: no look-alike letters
        "\uff43ircle",  # FULLWIDTH c
        "3.0",
        "+3",
        "-0",
        "9" * 5000,  # more digits than int() converts; quoted as 40 characters at most
    ],
)
def test_pattern_text_is_ascii_names_or_ascii_digits(key: str) -> None:
    with pytest.raises(EncodeError) as err:
        DICTIONARY.lookup(key)
    text = str(err.value)
    assert text.startswith("unknown pattern ") and err.value.field is None
    assert "circle (3)" in text and "box_orbit (7)" in text and "surface (15)" in text
    assert len(text) < 250  # quotes at most 40 characters of what was given


@pytest.mark.parametrize(
    ("key", "name"),
    [("3", "circle"), ("3 ", "circle"), ("\t3\n", "circle"), ("03", "circle"), ("015", "surface")],
)
def test_ascii_digits_name_the_id_leading_zeros_included(key: str, name: str) -> None:
    assert DICTIONARY.lookup(key).name == name


def test_mapping_lookup_is_exact() -> None:
    with pytest.raises(KeyError):
        DICTIONARY["box-orbit"]  # the Mapping is by exact name; lookup() is lenient


@pytest.mark.parametrize("pattern", list(DICTIONARY.values()), ids=list(DICTIONARY))
def test_defaults_encode_unchanged(pattern: Pattern) -> None:
    command, snaps = make_command(pattern.name, pattern.defaults)
    assert command.pattern is pattern
    assert command.params == pattern.defaults
    assert [s.field for s in snaps] == [f.name for f in pattern.fields]
    assert not any(s.changed for s in snaps)
    for f, code in zip(pattern.fields, command.codes, strict=True):
        assert f.scale.is_valid_code(code)


def test_make_command_accepts_name_id_or_pattern() -> None:
    params: dict[str, ParamValue] = {"speed": 0.5, "depth": 2, "radius": 5, "direction": "cw"}
    by_name, _ = make_command("circle", params)
    by_id, _ = make_command(3, params)
    by_pattern, _ = make_command(DICTIONARY["circle"], params)
    by_text_id, _ = make_command("3", params)
    assert by_name == by_id == by_pattern == by_text_id
    assert by_name.params == {"speed": 0.5, "depth": 2.0, "radius": 5.0, "direction": "cw"}


@pytest.mark.parametrize(
    ("pattern", "given", "missing"),
    [
        ("circle", {"speed": 0.5, "depth": 2, "direction": "cw"}, ["radius"]),
        ("straight", {}, ["speed", "depth", "duration", "heading"]),
        (
            "helix",
            {"speed": 1, "radius": 5, "turns": 2, "direction": "cw"},
            ["start_depth", "end_depth"],
        ),
        ("hover", {"duration": 10, "depth": 1}, ["heading"]),
    ],
)
def test_missing_parameters(
    pattern: str, given: dict[str, float | str], missing: list[str]
) -> None:
    with pytest.raises(EncodeError) as err:
        make_command(pattern, given)
    text = str(err.value)
    assert err.value.field == missing[0]
    assert pattern in text
    spec = DICTIONARY[pattern]
    for name in missing:
        f = spec.field(name)
        assert f"{name} ({f.scale.range_text(f.unit)})" in text
    for name in given:
        assert f"{name} (" not in text


@pytest.mark.parametrize(
    ("pattern", "extra"),
    [("circle", "radiu"), ("circle", "heading"), ("surface", "speed"), ("square", "laps")],
)
def test_unknown_parameters(pattern: str, extra: str) -> None:
    params: dict[str, float | str] = dict(DICTIONARY[pattern].defaults)
    params[extra] = 1
    with pytest.raises(EncodeError) as err:
        make_command(pattern, params)
    text = str(err.value)
    assert err.value.field == extra
    assert repr(extra) in text
    fields = [f.name for f in DICTIONARY[pattern].fields]
    assert (", ".join(fields) if fields else "no parameters") in text


def test_make_command_reports_one_snap_per_field_in_order() -> None:
    command, snaps = make_command(
        "spiral",
        {
            "direction": "CCW",
            "loops": 4,
            "final_radius": 12.34,
            "initial_radius": 2,
            "depth": 3.33,
            "speed": 1.006,
        },
    )
    assert [s.field for s in snaps] == [f.name for f in command.pattern.fields]
    assert command.params == {
        "speed": 1.01,
        "depth": 3.3,
        "initial_radius": 2.0,
        "final_radius": 12.5,
        "loops": 4,
        "direction": "ccw",
    }
    assert [s.changed for s in snaps] == [True, True, False, True, False, False]


def test_command_describe_and_repr() -> None:
    command, _ = make_command(
        "square", {"speed": 0.5, "depth": 2, "side_span": 10, "direction": "cw"}
    )
    assert command.describe() == "square speed=0.5 m/s depth=2 m side_span=10 m direction=cw"
    assert repr(command) == f"<Command {command.describe()}>"
    laps, _ = make_command("box_orbit", {**DICTIONARY["box_orbit"].defaults, "laps": 3})
    assert laps.describe().endswith("direction=cw laps=3")  # no unit after a count


def test_command_validates_codes() -> None:
    circle = DICTIONARY["circle"]
    Command(circle, (50, 20, 100, 1))
    with pytest.raises(ValueError, match="takes 4 codes"):
        Command(circle, (50, 20, 100))
    with pytest.raises(ValueError, match="direction"):
        Command(circle, (50, 20, 100, 2))
    with pytest.raises(ValueError, match="laps"):
        Command(DICTIONARY["lawnmower"], (50, 20, 100, 100, 0))
    with pytest.raises(ValueError, match="heading"):
        Command(DICTIONARY["straight"], (50, 20, 100, 250))


def test_pattern_helpers() -> None:
    circle = DICTIONARY["circle"]
    assert repr(circle) == "<Pattern 3 circle>"
    assert circle.field("radius").unit == "m"
    with pytest.raises(KeyError):
        circle.field("side_span")
    assert list(circle.defaults) == ["speed", "depth", "radius", "direction"]


SPEED = DICTIONARY["helix"].field("speed")
DEPTH = DICTIONARY["circle"].field("depth")
COUNT = DICTIONARY["helix"].field("turns")


@pytest.mark.parametrize("pattern_id", [-1, 16, 255])
def test_pattern_id_must_fit_in_four_bits(pattern_id: int) -> None:
    with pytest.raises(ValueError, match="4 bits"):
        Pattern(pattern_id, "x", "x", (), "")


def test_pattern_field_limits() -> None:
    depths = tuple(
        Field(f"d{i}", f"d{i}", "m", DEPTH.scale, 1.0, "") for i in range(FIELDS_PER_FRAME + 1)
    )
    Pattern(9, "six", "six", depths[:FIELDS_PER_FRAME], "")
    with pytest.raises(ValueError, match="more than 6 fields"):
        Pattern(9, "seven", "seven", depths, "")
    with pytest.raises(ValueError, match="duplicate"):
        Pattern(9, "dup", "dup", (SPEED, SPEED), "")


def test_dictionary_refuses_duplicate_ids_and_names() -> None:
    with pytest.raises(ValueError, match="pattern ID 3"):
        CommandDictionary((*PATTERNS, Pattern(3, "other", "other", (), "")))
    with pytest.raises(ValueError, match="circle"):
        CommandDictionary((*PATTERNS, Pattern(9, "circle", "circle", (), "")))


# --- adding a pattern is adding data ---------------------------------------------------------

YOYO = Pattern(
    8,
    "yoyo",
    "yo-yo",
    (
        SPEED,
        Field("top_depth", "top depth", "m", DEPTH.scale, 1.0, "Shallow end."),
        Field("bottom_depth", "bottom depth", "m", DEPTH.scale, 10.0, "Deep end."),
        Field("cycles", "cycles", "", COUNT.scale, 3, "Down-and-up cycles."),
    ),
    "Profile the water column between two depths.",
)
EXTENDED = CommandDictionary((*PATTERNS, YOYO))
YOYO_PARAMS = {"speed": 0.8, "top_depth": 1.5, "bottom_depth": 20, "cycles": 4}


def test_extended_dictionary_keeps_the_shared_patterns() -> None:
    assert len(EXTENDED) == len(DICTIONARY) + 1
    assert EXTENDED.by_id(8) is YOYO
    assert EXTENDED.lookup("YoYo") is YOYO
    assert EXTENDED.lookup("8") is YOYO
    for name in DICTIONARY:
        assert EXTENDED[name] is DICTIONARY[name]
    with pytest.raises(EncodeError, match="yoyo"):
        make_command("yoyo", YOYO_PARAMS)  # not in the shared dictionary


def test_added_pattern_round_trips_through_a_frame() -> None:
    encoded = encode_frame("yoyo", YOYO_PARAMS, dictionary=EXTENDED)
    assert encoded.command.pattern is YOYO
    assert encoded.command.params == {
        "speed": 0.8,
        "top_depth": 1.5,
        "bottom_depth": 20.0,
        "cycles": 4,
    }
    assert encoded.frame.bits[24:28] == "1000"  # pattern ID 8
    assert [s.name for s in sections(YOYO)][3:9] == [
        "speed",
        "top_depth",
        "bottom_depth",
        "cycles",
        "j5 (unused)",
        "j6 (unused)",
    ]
    decoded = decode_frame(encoded.frame.bits, dictionary=EXTENDED)
    assert decoded.command == encoded.command
    assert decoded.corrected == 0
    # The shared dictionary does not know ID 8: the same frame is refused, not misread.
    with pytest.raises(DecodeError) as err:
        decode_frame(encoded.frame.bits)
    assert err.value.reason is RejectReason.UNKNOWN_PATTERN


def test_added_pattern_through_the_receiver(rng: random.Random) -> None:
    commands = [
        encode_frame("yoyo", YOYO_PARAMS, dictionary=EXTENDED),
        encode_frame("circle", DICTIONARY["circle"].defaults, dictionary=EXTENDED),
        encode_frame("yoyo", {**YOYO_PARAMS, "cycles": 9}, dictionary=EXTENDED),
    ]
    stream = ""
    offsets = []
    for enc in commands:
        stream += random_bits(rng, 37)
        offsets.append(len(stream))
        stream += enc.frame.bits
    stream += random_bits(rng, 50)
    receiver = FrameReceiver(dictionary=EXTENDED)
    events = [summary(e) for e in receiver.feed_bits(stream)]
    assert events == [
        ("accepted", off, enc.command, 0, 0) for off, enc in zip(offsets, commands, strict=True)
    ]
    # With the shared dictionary the yo-yo frames are rejected and the circle still accepted.
    plain = [summary(e) for e in FrameReceiver().feed_bits(stream)]
    assert [(s[0], s[1]) for s in plain] == [
        ("rejected", offsets[0]),
        ("accepted", offsets[1]),
        ("rejected", offsets[2]),
    ]
    assert plain[0][2] is RejectReason.UNKNOWN_PATTERN


def test_every_field_of_the_added_pattern_round_trips() -> None:
    for f in YOYO.fields:
        for value in representable(f)[::17]:
            params = {**YOYO.defaults, f.name: value}
            enc = encode_frame(YOYO, params, dictionary=EXTENDED)
            assert decode_frame(enc.frame, dictionary=EXTENDED).command.params[f.name] == value
