"""The 100-bit frame: layout, accepted input forms, every rejection, round trips and fuzzing."""

from __future__ import annotations

import random
from collections.abc import Callable
from itertools import pairwise

import bchlib
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from codec import (
    CODE,
    CODEWORD_BITS,
    CRC_BITS,
    CRC_POLY,
    DEFAULT_BITRATE_BPS,
    DEFAULT_SYNC_TOLERANCE,
    DELIMITER,
    DELIMITER_BITS,
    DICTIONARY,
    FRAME_BITS,
    FRAME_BYTES,
    GUARD_BITS,
    MESSAGE_BITS,
    PARITY_BITS,
    PAYLOAD_BITS,
    PREAMBLE,
    PREAMBLE_BITS,
    SYNC_BITS,
    SYNC_WORD,
    UNCORRECTABLE,
    Command,
    Decoded,
    DecodeError,
    Frame,
    ParamValue,
    Pattern,
    RejectReason,
    Section,
    airtime_s,
    command_of_message,
    crc4,
    decode_codeword,
    decode_frame,
    encode_frame,
    frame_of,
    make_command,
    message_of,
    parse_frame,
    payload_of,
    sections,
)
from tests.codec.helpers import (
    crafted_frame,
    flip_frame,
    frame_value,
    mask_of,
    message,
    payload,
    random_command,
    random_error,
    requested_params,
)

PATTERN_LIST = list(DICTIONARY.values())


def bitwise_crc4(value: int, nbits: int = PAYLOAD_BITS) -> int:
    """CRC-4 (x^4 + x + 1, initial 0, no reflection, no final XOR), one bit at a time."""
    reg = 0
    for i in range(nbits - 1, -1, -1):
        feedback = (reg >> 3 & 1) ^ (value >> i & 1)
        reg = (reg << 1) & 0xF
        if feedback:
            reg ^= 0b0011
    return reg


def test_layout_constants() -> None:
    assert (PREAMBLE, PREAMBLE_BITS, DELIMITER, DELIMITER_BITS) == (0xAAAA, 16, 0x7C, 8)
    assert (SYNC_WORD, SYNC_BITS) == (0xAAAA7C, 24)
    assert (PAYLOAD_BITS, CRC_BITS, MESSAGE_BITS) == (52, 4, 56)
    assert (CODEWORD_BITS, PARITY_BITS, GUARD_BITS) == (72, 16, 4)
    assert (FRAME_BITS, FRAME_BYTES) == (100, 13)
    assert CRC_POLY == 0b10011
    assert DEFAULT_SYNC_TOLERANCE == 2


# --- layout -------------------------------------------------------------------------------------

SECTIONS_UNUSED = [
    ("preamble", 0, 16),
    ("delimiter", 16, 8),
    ("pattern", 24, 4),
    ("j1 (unused)", 28, 8),
    ("j2 (unused)", 36, 8),
    ("j3 (unused)", 44, 8),
    ("j4 (unused)", 52, 8),
    ("j5 (unused)", 60, 8),
    ("j6 (unused)", 68, 8),
    ("crc", 76, 4),
    ("parity", 80, 16),
    ("guard", 96, 4),
]


def test_sections_without_a_pattern() -> None:
    assert sections() == tuple(Section(*s) for s in SECTIONS_UNUSED)
    assert sections(DICTIONARY["surface"]) == sections()


@pytest.mark.parametrize("pattern", PATTERN_LIST, ids=[p.name for p in PATTERN_LIST])
def test_sections_tile_the_frame_and_name_the_fields(pattern: Pattern) -> None:
    secs = sections(pattern)
    assert secs[0].start == 0
    for a, b in pairwise(secs):
        assert a.start + a.length == b.start
    assert secs[-1].start + secs[-1].length == FRAME_BITS
    names = [s.name for s in secs[3:9]]
    used = [f.name for f in pattern.fields]
    assert names == used + [f"j{j + 1} (unused)" for j in range(len(used), 6)]


def test_known_frame_bit_by_bit() -> None:
    """square, 0.5 m/s, 2 m, 10 m, ccw: every section checked against independent pieces."""
    enc = encode_frame("square", speed=0.5, depth=2, side_span=10, direction="ccw")
    square = DICTIONARY["square"]
    assert enc.command.codes == (50, 20, 110, 1)
    assert square.field("side_span").value_of(110) == 10.0
    bits = enc.frame.bits
    assert len(bits) == 100
    parts = {s.name: bits[s.start : s.start + s.length] for s in sections(square)}
    assert parts["preamble"] == "1010101010101010"
    assert parts["delimiter"] == "01111100"
    assert parts["pattern"] == "0001"
    assert parts["speed"] == "00110010"
    assert parts["depth"] == "00010100"
    assert parts["side_span"] == "01101110"
    assert parts["direction"] == "00000001"
    assert parts["j5 (unused)"] == parts["j6 (unused)"] == "00000000"
    payload_bits = bits[24:76]
    assert parts["crc"] == format(bitwise_crc4(int(payload_bits, 2)), "04b") == "0100"
    msg = int(bits[24:80], 2)
    ecc = bchlib.BCH(2, m=8).encode(msg.to_bytes(7, "big"))
    assert parts["parity"] == format(int.from_bytes(ecc, "big"), "016b")
    assert parts["guard"] == "0000"
    # The same frame in its other forms.
    assert enc.frame.hex == "aaaa7c132146e0100004d6500"
    assert len(enc.frame.hex) == 25
    assert int(enc.frame.hex, 16) == int(bits, 2) == enc.frame.value
    packed = enc.frame.to_bytes()
    assert len(packed) == 13
    assert packed == int(bits + "0000", 2).to_bytes(13, "big")
    assert packed[-1] & 0x0F == 0
    assert enc.frame.codeword == int(bits[24:96], 2) == CODE.encode(msg)
    assert str(enc.frame) == bits
    assert enc.frame.grouped(square) == " ".join(
        bits[s.start : s.start + s.length] for s in sections(square)
    )
    assert enc.frame.grouped(square).split() == list(parts.values())


@pytest.mark.parametrize("pattern", PATTERN_LIST, ids=[p.name for p in PATTERN_LIST])
def test_payload_message_and_frame_of_every_pattern(pattern: Pattern) -> None:
    command, _ = make_command(pattern, pattern.defaults)
    p = payload_of(command)
    assert p >> 48 == pattern.id
    assert p == payload(pattern.id, command.codes)
    assert message_of(command) == (p << 4) | crc4(p)
    frame = frame_of(command)
    assert frame.value >> 76 == SYNC_WORD
    assert frame.codeword == CODE.encode(message_of(command))
    assert frame.value & 0xF == 0
    assert command_of_message(message_of(command)) == command
    bits = frame.bits
    for s, code in zip(sections(pattern)[3:], command.codes, strict=False):
        assert int(bits[s.start : s.start + s.length], 2) == code


def test_crc4_against_bitwise(rng: random.Random) -> None:
    assert crc4(0) == 0
    assert crc4(1) == 0b0011  # x^4 mod (x^4 + x + 1) = x + 1
    for _ in range(2000):
        p = rng.getrandbits(52)
        assert crc4(p) == bitwise_crc4(p)
        assert crc4(p ^ (1 << rng.randrange(52))) != crc4(p)  # every single error detected


def test_airtime() -> None:
    assert DEFAULT_BITRATE_BPS == 36_000
    assert airtime_s() == pytest.approx(100 / 36_000)
    assert airtime_s(100) == 1.0
    assert airtime_s(1000, bits=50) == 0.05
    for bad in (0, -1.0):
        with pytest.raises(ValueError):
            airtime_s(bad)


@pytest.mark.parametrize("value", [-1, 1 << 100])
def test_frame_holds_100_bits(value: int) -> None:
    with pytest.raises(ValueError):
        Frame(value)


def test_encode_frame_call_forms() -> None:
    params: dict[str, ParamValue] = {"speed": 0.5, "depth": 2, "radius": 5, "direction": "cw"}
    reference = encode_frame("circle", params)
    assert encode_frame("circle", speed=0.5, depth=2, radius=5, direction="cw") == reference
    assert encode_frame("circle", {"speed": 0.5, "depth": 2}, radius=5, direction="cw") == reference
    assert encode_frame(3, params) == reference
    assert encode_frame(DICTIONARY["circle"], params) == reference
    from_command = encode_frame(reference.command)
    assert from_command.frame == reference.frame
    assert from_command.command == reference.command
    assert from_command.snaps == ()  # nothing was requested, nothing snapped
    with pytest.raises(TypeError):
        encode_frame(reference.command, params)
    with pytest.raises(TypeError):
        encode_frame(reference.command, speed=1.0)


# --- accepted input forms --------------------------------------------------------------------

Form = Callable[[Frame], object]

FORMS: list[tuple[str, Form]] = [
    ("bits", lambda f: f.bits),
    ("bits grouped", lambda f: f.grouped()),
    ("bits grouped by pattern", lambda f: f.grouped(DICTIONARY["circle"])),
    ("bits underscores", lambda f: "_".join(f.bits[i : i + 4] for i in range(0, 100, 4))),
    ("bits surrounding whitespace", lambda f: "  " + f.bits + "\n"),
    ("hex", lambda f: f.hex),
    ("HEX", lambda f: f.hex.upper()),
    ("0x hex", lambda f: "0x" + f.hex),
    ("0X HEX", lambda f: "0X" + f.hex.upper()),
    ("hex grouped", lambda f: " ".join(f.hex[i : i + 5] for i in range(0, 25, 5))),
    ("bytes", lambda f: f.to_bytes()),
    ("bytearray", lambda f: bytearray(f.to_bytes())),
    ("memoryview", lambda f: memoryview(f.to_bytes())),
    ("int", lambda f: f.value),
    ("list of ints", lambda f: [int(c) for c in f.bits]),
    ("tuple of ints", lambda f: tuple(int(c) for c in f.bits)),
    ("Frame", lambda f: f),
]


@pytest.mark.parametrize("form", [f for _, f in FORMS], ids=[n for n, _ in FORMS])
def test_every_accepted_form_decodes(form: Form) -> None:
    enc = encode_frame("circle", speed=0.5, depth=2, radius=5, direction="ccw")
    damaged = Frame(flip_frame(enc.frame.value, header=[3], codeword=[0, 70], guard=0b1010))
    assert parse_frame(form(damaged)) == damaged.value
    decoded = decode_frame(form(damaged))
    assert decoded == Decoded(enc.command, corrected=2, sync_errors=1)


MALFORMED: list[tuple[str, object]] = [
    ("None", None),
    ("float", 1.5),
    ("nan", float("nan")),
    ("complex", 1j),
    ("dict", {"bits": "0" * 100}),
    ("set", {0, 1}),
    ("object", object()),
    ("bool", True),
    ("empty str", ""),
    ("spaces", "   "),
    ("99 bits", "0" * 99),
    ("101 bits", "0" * 101),
    ("100 chars with a 2", "0" * 99 + "2"),
    ("100 chars with a letter", "1" * 50 + "a" + "0" * 49),
    ("24 hex", "f" * 24),
    ("26 hex", "f" * 26),
    ("25 non-hex", "g" * 25),
    ("0x + 24", "0x" + "a" * 24),
    ("tab inside", "aaaa7c13214\t6e0100004d6500"),
    ("empty bytes", b""),
    ("12 bytes", bytes(12)),
    ("14 bytes", bytes(14)),
    ("pad bits set", bytes(12) + b"\x01"),
    ("negative int", -1),
    ("2^100", 1 << 100),
    ("99 ints", [0] * 99),
    ("101 ints", [0] * 101),
    ("100 strings", ["0"] * 100),
    ("100 twos", [2] * 100),
    ("100 bools", [True] * 100),
    ("100 floats", [0.0] * 100),
    ("100 Nones", [None] * 100),
    ("range", range(100)),
    ("list of str", ["0" * 100]),
]


@pytest.mark.parametrize("bad", [b for _, b in MALFORMED], ids=[n for n, _ in MALFORMED])
def test_malformed_inputs(bad: object) -> None:
    with pytest.raises(DecodeError) as err:
        decode_frame(bad)
    assert err.value.reason is RejectReason.MALFORMED
    assert str(err.value).startswith("malformed frame")
    with pytest.raises(DecodeError):
        parse_frame(bad)


@pytest.mark.parametrize(
    "text",
    [
        "-" + "f" * 24,  # int() reads a sign ...
        "+" + "a" * 24,
        "0x-" + "f" * 23,
        "0x0x" + "a" * 23,  # ... a second 0x prefix ...
        "\u0663" * 25,  # ... and non-ASCII digits (ARABIC-INDIC DIGIT THREE)
        "\uff11" * 25,  # FULLWIDTH DIGIT ONE
    ],
    ids=["minus", "plus", "0x-minus", "double 0x", "arabic-indic digits", "fullwidth digits"],
)
def test_hex_text_must_be_25_ascii_hex_digits(text: str) -> None:
    with pytest.raises(DecodeError) as err:
        parse_frame(text)
    assert err.value.reason is RejectReason.MALFORMED


def test_signed_hex_is_not_decoded_as_a_frame() -> None:
    """A minus sign makes parse_frame return a negative int (int(text, 16) accepts a sign).
    Python's two's-complement shifts then read a valid codeword out of it, so with a sync
    tolerance of 3 the text ``-d55830ffffffffffffccb420`` decodes to the surface command."""
    codeword = frame_of(make_command("surface", {})[0]).codeword
    top = -873_860  # a negative 20-bit header 3 bits away from the sync word
    assert ((top ^ SYNC_WORD).bit_count()) == 3
    value = top * (1 << 76) + (codeword << 4)
    text = "-" + format(-value, "024x")
    assert len(text) == 25
    with pytest.raises(DecodeError) as err:
        decode_frame(text, sync_tolerance=3)
    assert err.value.reason is RejectReason.MALFORMED


# --- every rejection reason ----------------------------------------------------------------

CIRCLE = (50, 20, 100, 0)
CRAFTED: list[tuple[str, int, RejectReason, str | None]] = [
    (
        "crc off by one bit",
        crafted_frame(3, CIRCLE, crc_xor=0b0001),
        RejectReason.CRC_MISMATCH,
        None,
    ),
    ("crc all flipped", crafted_frame(3, CIRCLE, crc_xor=0b1111), RejectReason.CRC_MISMATCH, None),
    ("crc checked first", crafted_frame(9, (), crc_xor=0b0100), RejectReason.CRC_MISMATCH, None),
    ("unknown ID 9", crafted_frame(9, ()), RejectReason.UNKNOWN_PATTERN, None),
    ("unknown ID 8", crafted_frame(8, CIRCLE), RejectReason.UNKNOWN_PATTERN, None),
    ("unknown ID 14", crafted_frame(14, ()), RejectReason.UNKNOWN_PATTERN, None),
    (
        "heading code 250",
        crafted_frame(0, (50, 20, 60, 250)),
        RejectReason.FIELD_OUT_OF_RANGE,
        "heading",
    ),
    (
        "heading code 240",
        crafted_frame(6, (60, 20, 240)),
        RejectReason.FIELD_OUT_OF_RANGE,
        "heading",
    ),
    (
        "laps code 0",
        crafted_frame(2, (50, 20, 100, 100, 0)),
        RejectReason.FIELD_OUT_OF_RANGE,
        "laps",
    ),
    (
        "turns code 0",
        crafted_frame(5, (50, 20, 80, 100, 0, 0)),
        RejectReason.FIELD_OUT_OF_RANGE,
        "turns",
    ),
    (
        "direction code 2",
        crafted_frame(3, (50, 20, 100, 2)),
        RejectReason.FIELD_OUT_OF_RANGE,
        "direction",
    ),
    (
        "direction code 255",
        crafted_frame(1, (50, 20, 100, 255)),
        RejectReason.FIELD_OUT_OF_RANGE,
        "direction",
    ),
    (
        "invalid field before unused field",
        crafted_frame(3, (50, 20, 100, 2, 1)),
        RejectReason.FIELD_OUT_OF_RANGE,
        "direction",
    ),
    ("circle j5 set", crafted_frame(3, (*CIRCLE, 1)), RejectReason.UNUSED_FIELD_SET, "j5"),
    ("circle j6 set", crafted_frame(3, (*CIRCLE, 0, 0x80)), RejectReason.UNUSED_FIELD_SET, "j6"),
    ("hover j4 set", crafted_frame(6, (60, 20, 0, 7)), RejectReason.UNUSED_FIELD_SET, "j4"),
    ("surface j1 set", crafted_frame(15, (1,)), RejectReason.UNUSED_FIELD_SET, "j1"),
    (
        "surface j6 set",
        crafted_frame(15, (0, 0, 0, 0, 0, 255)),
        RejectReason.UNUSED_FIELD_SET,
        "j6",
    ),
]


@pytest.mark.parametrize(
    ("value", "reason", "field"),
    [c[1:] for c in CRAFTED],
    ids=[c[0] for c in CRAFTED],
)
@pytest.mark.parametrize("errors", [(), (5,), (0, 71)], ids=["clean", "1 error", "2 errors"])
def test_crafted_frames_are_rejected_for_the_right_reason(
    value: int, reason: RejectReason, field: str | None, errors: tuple[int, ...]
) -> None:
    with pytest.raises(DecodeError) as err:
        decode_frame(flip_frame(value, codeword=errors))
    assert err.value.reason is reason
    assert err.value.field == field
    assert reason.value in repr(err.value)
    if field is not None:
        assert field in str(err.value)
    with pytest.raises(DecodeError) as direct:
        command_of_message(CODE.decode(value >> 4 & ((1 << 72) - 1))[0])
    assert direct.value.reason is reason


def test_no_sync_with_three_header_errors() -> None:
    enc = encode_frame("hover", duration=30, depth=1, heading=90)
    for header in ([0, 1, 2], [15, 16, 23], [0, 12, 20], list(range(24))):
        value = flip_frame(enc.frame.value, header=header)
        with pytest.raises(DecodeError) as err:
            decode_frame(value)
        assert err.value.reason is RejectReason.NO_SYNC
        assert f"in {len(header)} bits" in str(err.value)
        tolerant = decode_frame(value, sync_tolerance=len(header))
        assert tolerant == Decoded(enc.command, 0, len(header))


@pytest.mark.parametrize("tolerance", [0, 1, 2, 3, 4])
def test_sync_tolerance_is_a_strict_bound(tolerance: int) -> None:
    enc = encode_frame("surface")
    for n in range(6):
        value = flip_frame(enc.frame.value, header=range(0, 2 * n, 2))
        if n <= tolerance:
            assert decode_frame(value, sync_tolerance=tolerance).sync_errors == n
        else:
            with pytest.raises(DecodeError, match="sync word"):
                decode_frame(value, sync_tolerance=tolerance)


def find_errors(
    rng: random.Random, codeword: int, weight: int, want: Callable[[tuple[int, int]], bool]
) -> int:
    """A ``weight``-bit error pattern for which the BCH decoder's outcome satisfies ``want``."""
    for _ in range(100_000):
        error = random_error(rng, CODEWORD_BITS, weight)
        if want(CODE.decode(codeword ^ error)):
            return error
    raise AssertionError("no such error pattern found")


def test_uncorrectable_with_three_errors(rng: random.Random) -> None:
    for pattern in PATTERN_LIST:
        command = make_command(pattern, pattern.defaults)[0]
        frame = frame_of(command)
        error = find_errors(rng, frame.codeword, 3, lambda out: out[1] == UNCORRECTABLE)
        with pytest.raises(DecodeError) as err:
            decode_frame(frame.value ^ (error << GUARD_BITS))
        assert err.value.reason is RejectReason.UNCORRECTABLE
        with pytest.raises(DecodeError) as direct:
            decode_codeword(frame.codeword ^ error)
        assert direct.value.reason is RejectReason.UNCORRECTABLE


def test_miscorrection_caught_by_the_crc(rng: random.Random) -> None:
    command = make_command("circle", DICTIONARY["circle"].defaults)[0]
    frame = frame_of(command)
    msg = message_of(command)

    def miscorrected_bad_crc(out: tuple[int, int]) -> bool:
        m, n = out
        return n > 0 and m != msg and crc4(m >> 4) != m & 0xF

    error = find_errors(rng, frame.codeword, 3, miscorrected_bad_crc)
    with pytest.raises(DecodeError) as err:
        decode_frame(frame.value ^ (error << GUARD_BITS))
    assert err.value.reason is RejectReason.CRC_MISMATCH


def test_decode_codeword_contract() -> None:
    enc = encode_frame("lawnmower", speed=1, depth=3, sweep_length=50, lane_spacing=4, laps=3)
    cw = enc.frame.codeword
    assert decode_codeword(cw) == Decoded(enc.command, 0, 0)
    assert decode_codeword(cw ^ 0b101) == Decoded(enc.command, 2, 0)
    assert decode_codeword(cw | (1 << 80)) == Decoded(enc.command, 0, 0)  # masked to 72 bits


# --- round trips ------------------------------------------------------------------------------


@pytest.mark.parametrize("pattern", PATTERN_LIST, ids=[p.name for p in PATTERN_LIST])
@settings(max_examples=60, deadline=None)
@given(
    data=st.data(),
    codeword_errors=st.sets(st.integers(0, CODEWORD_BITS - 1), max_size=2),
    header_errors=st.sets(st.integers(0, SYNC_BITS - 1), max_size=2),
    guard=st.integers(0, 15),
    form=st.sampled_from(FORMS),
)
def test_round_trip_every_pattern_with_up_to_two_errors(
    *,
    pattern: Pattern,
    data: st.DataObject,
    codeword_errors: set[int],
    header_errors: set[int],
    guard: int,
    form: tuple[str, Form],
) -> None:
    params = data.draw(requested_params(pattern), label="params")
    enc = encode_frame(pattern.name, params)
    expected, snaps = make_command(pattern.name, params)
    assert enc.command == expected
    assert enc.snaps == snaps
    for f, snap in zip(pattern.fields, snaps, strict=True):
        assert snap.sent == f.snap(params[f.name])[1]
        assert snap.requested == params[f.name]
    value = flip_frame(enc.frame.value, header=header_errors, codeword=codeword_errors, guard=guard)
    decoded = decode_frame(form[1](Frame(value)))
    assert decoded.command == enc.command
    assert decoded.command.params == {s.field: s.sent for s in snaps}
    assert decoded.corrected == len(codeword_errors)
    assert decoded.sync_errors == len(header_errors)


# --- fuzzing: DecodeError or a valid command, never anything else --------------------------------


def decode_or_reject(frame: object) -> Decoded | DecodeError:
    try:
        return decode_frame(frame)
    except DecodeError as err:
        assert isinstance(err.reason, RejectReason)
        return err


def check_accepted(received: int, decoded: Decoded) -> None:
    """An accepted frame carries a valid command whose codeword is within 2 bits of it."""
    command = decoded.command
    assert Command(command.pattern, command.codes) == command  # validates every code
    assert DICTIONARY.by_id(command.pattern.id) is command.pattern
    codeword = (received >> GUARD_BITS) & ((1 << CODEWORD_BITS) - 1)
    distance = (frame_of(command).codeword ^ codeword).bit_count()
    assert distance == decoded.corrected <= 2
    assert decoded.sync_errors == ((received >> 76) ^ SYNC_WORD).bit_count() <= 2


ANYTHING = st.one_of(
    st.none(),
    st.booleans(),
    st.floats(allow_nan=True),
    st.complex_numbers(),
    st.integers(),
    st.text(),
    st.binary(),
    st.lists(st.text(), max_size=110),
    st.lists(st.integers(-2, 3), min_size=98, max_size=102),
    st.lists(
        st.one_of(st.integers(0, 1), st.booleans(), st.floats(0, 1)), min_size=100, max_size=100
    ),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=3),
    st.tuples(st.integers(), st.text()),
    st.frozensets(st.integers(0, 1)),
)


@pytest.mark.slow  # a fuzz run
@settings(max_examples=200, deadline=None)
@given(anything=ANYTHING)
def test_fuzz_any_python_value(anything: object) -> None:
    decode_or_reject(anything)


@settings(max_examples=300, deadline=None)
@given(
    text=st.one_of(
        st.text(max_size=130),
        st.text(alphabet="01 _\t\n", max_size=130),
        st.text(alphabet="0123456789abcdefABCDEFxX +-_", min_size=20, max_size=30),
    )
)
def test_fuzz_text(text: str) -> None:
    result = decode_or_reject(text)
    if isinstance(result, Decoded):
        check_accepted(parse_frame(text), result)


@settings(max_examples=300, deadline=None)
@given(data=st.binary(max_size=20) | st.binary(min_size=13, max_size=13))
def test_fuzz_bytes(data: bytes) -> None:
    result = decode_or_reject(data)
    if isinstance(result, Decoded):
        check_accepted(int.from_bytes(data, "big") >> 4, result)


@settings(max_examples=500, deadline=None)
@given(value=st.integers(0, (1 << 100) - 1))
def test_fuzz_random_100_bit_ints(value: int) -> None:
    result = decode_or_reject(value)
    if isinstance(result, Decoded):
        check_accepted(value, result)
    else:
        assert result.reason is not RejectReason.MALFORMED


@settings(max_examples=500, deadline=None)
@given(
    pattern_id=st.integers(0, 15),
    codes=st.lists(st.integers(0, 255), min_size=6, max_size=6),
    zero_unused=st.booleans(),
    crc_xor=st.sampled_from([0, 0, 0, 1, 8, 15]),
    codeword_errors=st.sets(st.integers(0, 71), max_size=4),
    header_errors=st.sets(st.integers(0, 23), max_size=2),
    guard=st.integers(0, 15),
)
@pytest.mark.slow  # a fuzz run
def test_fuzz_near_valid_frames(
    *,
    pattern_id: int,
    codes: list[int],
    zero_unused: bool,
    crc_xor: int,
    codeword_errors: set[int],
    header_errors: set[int],
    guard: int,
) -> None:
    """Codewords of arbitrary payloads, damaged: the verdict is the clean payload's verdict
    within 2 errors, and any accepted frame is a valid command within 2 bits."""
    pattern = DICTIONARY.by_id(pattern_id)
    if zero_unused and pattern is not None:
        codes = codes[: len(pattern.fields)] + [0] * (6 - len(pattern.fields))
    msg = message(pattern_id, codes, crc_xor=crc_xor)
    clean = frame_value(CODE.encode(msg), guard=guard)
    received = flip_frame(clean, header=header_errors, codeword=codeword_errors)
    result = decode_or_reject(received)
    if isinstance(result, Decoded):
        check_accepted(received, result)
    else:
        assert result.reason not in (RejectReason.MALFORMED, RejectReason.NO_SYNC)
    if len(codeword_errors) <= 2:
        try:
            expected: Command | RejectReason = command_of_message(msg)
        except DecodeError as err:
            expected = err.reason
        if isinstance(result, Decoded):
            assert result.command == expected
            assert result.corrected == len(codeword_errors)
        else:
            assert result.reason is expected


def test_random_valid_commands_round_trip(rng: random.Random) -> None:
    for _ in range(2000):
        command = random_command(rng)
        frame = frame_of(command)
        errors = rng.sample(range(72), rng.randint(0, 2))
        received = frame.value ^ (mask_of(errors) << GUARD_BITS)
        assert decode_frame(received) == Decoded(command, len(errors), 0)
