"""Field quantizations: ranges, steps, exact values, snapping and its errors (codec._fields)."""

from __future__ import annotations

import math
import random
from decimal import Decimal
from itertools import pairwise

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from codec import (
    DICTIONARY,
    FIELD_BITS,
    ChoiceScale,
    EncodeError,
    Field,
    NumericScale,
    ParamValue,
    Segment,
    Snap,
    make_command,
)
from codec._fields import exact_decimal
from tests.codec.helpers import in_range, representable, valid_codes


def field(pattern: str, name: str) -> Field:
    return DICTIONARY[pattern].field(name)


def numeric(f: Field) -> NumericScale:
    assert isinstance(f.scale, NumericScale), f.name
    return f.scale


SPEED = field("straight", "speed")
DEPTH = field("straight", "depth")
DURATION = field("straight", "duration")
HEADING = field("straight", "heading")
LENGTH = field("square", "side_span")
COUNT = field("lawnmower", "laps")
DIRECTION = field("square", "direction")

#: Every (pattern, field) of the dictionary, with a readable id.
ALL_FIELDS = [(p.name, f) for p in DICTIONARY.values() for f in p.fields]
ALL_IDS = [f"{p}.{f.name}" for p, f in ALL_FIELDS]
NUMERIC_FIELDS = [(p, f) for p, f in ALL_FIELDS if isinstance(f.scale, NumericScale)]
NUMERIC_IDS = [f"{p}.{f.name}" for p, f in NUMERIC_FIELDS]

#: Fields that share a quantization: the paper's lengths, radii and spacings; depths; counts.
LENGTH_FIELDS = [
    ("square", "side_span"),
    ("lawnmower", "sweep_length"),
    ("lawnmower", "lane_spacing"),
    ("circle", "radius"),
    ("spiral", "initial_radius"),
    ("spiral", "final_radius"),
    ("helix", "radius"),
    ("box_orbit", "radius"),
]
DEPTH_FIELDS = [
    ("straight", "depth"),
    ("square", "depth"),
    ("lawnmower", "depth"),
    ("circle", "depth"),
    ("spiral", "depth"),
    ("helix", "start_depth"),
    ("helix", "end_depth"),
    ("hover", "depth"),
    ("box_orbit", "depth"),
]
COUNT_FIELDS = [
    ("lawnmower", "laps"),
    ("spiral", "loops"),
    ("helix", "turns"),
    ("box_orbit", "laps"),
]


def steps(scale: NumericScale) -> list[float]:
    return [b - a for a, b in pairwise(scale.values)]


def fmt(x: float) -> str:
    return format(x, ".10g")


# --- required coverage ----------------------------------------------------------------------


def test_speed_covers_0_to_2_m_s_in_steps_of_at_most_1_cm_s() -> None:
    scale = numeric(SPEED)
    assert SPEED.unit == "m/s"
    assert scale.minimum == 0
    assert scale.maximum >= 2
    assert max(steps(scale)) <= 0.01 + 1e-12
    assert SPEED.snap(1.234) == (123 + scale.first_code, 1.23)
    assert SPEED.snap(2) == (200 + scale.first_code, 2.0)


def test_depth_covers_0_to_100_m_with_half_and_whole_metres_exact() -> None:
    scale = numeric(DEPTH)
    assert DEPTH.unit == "m"
    assert scale.minimum == 0
    assert scale.maximum >= 100
    for exact in (0.5, 1.0, 2.0, 10.0, 50.5, 100.0):
        assert exact in scale.values
        code, sent = DEPTH.snap(exact)
        assert sent == exact
        assert DEPTH.value_of(code) == exact


def test_lengths_cover_half_a_metre_to_200_m() -> None:
    scale = numeric(LENGTH)
    assert LENGTH.unit == "m"
    assert scale.minimum <= 0.5
    assert scale.maximum >= 200
    for exact in (0.5, 1.0, 5.0, 10.0, 12.5, 50.0, 100.0, 200.0):
        assert LENGTH.snap(exact)[1] == exact
    rel = scale.max_rel_error
    assert rel is not None
    assert scale.rel_error_from is not None
    assert scale.rel_error_from <= 0.5
    assert rel < 0.025  # the documented bound: below 2.5 % from 0.5 m up


def test_durations_reach_half_an_hour() -> None:
    scale = numeric(DURATION)
    assert DURATION.unit == "s"
    assert scale.minimum == 0
    assert scale.maximum >= 1800
    assert DURATION.snap(1800)[1] == 1800
    assert DURATION.snap(60)[1] == 60


@pytest.mark.parametrize(
    ("requested", "sent"),
    [
        (0, 0.0),
        (90, 90.0),
        (359.4, 0.0),  # closer to 360 than to 358.5: wraps to north
        (-90, 270.0),
        (-0.4, 0.0),
        (360, 0.0),
        (-360, 0.0),
        (359.0, 358.5),
        (-1.5, 358.5),
        (180.7, 180.0),
        (7.5, 7.5),
        (359.25, 0.0),  # the tie across north goes to the larger value, 360 = 0
        (0.75, 1.5),  # ties go to the larger value
    ],
)
def test_heading_wraps_around_the_full_circle(requested: float, sent: float) -> None:
    assert HEADING.unit == "deg"
    code, value = HEADING.snap(requested)
    assert value == sent
    assert HEADING.value_of(code) == sent


def test_heading_covers_the_circle_evenly() -> None:
    scale = numeric(HEADING)
    assert scale.period == 360
    assert scale.minimum == 0
    gaps = steps(scale)
    assert len(set(gaps)) == 1  # one step size ...
    assert scale.maximum + gaps[0] == 360  # ... that also closes the circle
    for code in range(1 << FIELD_BITS):  # the codes past the circle are invalid
        assert scale.is_valid_code(code) == (code < len(scale.values))
    assert not scale.is_valid_code(250)


def test_counts_are_their_own_code() -> None:
    scale = numeric(COUNT)
    assert COUNT.unit == ""
    assert not scale.is_valid_code(0)
    assert valid_codes(COUNT) == list(range(1, 256))
    for n in range(1, 256):
        code, sent = COUNT.snap(n)
        assert code == n
        assert sent == n
        assert type(sent) is int
        assert type(COUNT.value_of(n)) is int
    assert COUNT.snap(3.0) == (3, 3)
    assert COUNT.snap("7") == (7, 7)


@pytest.mark.parametrize("value", [0, -1, 256, 2.5, 0.5, 254.999, "3.5"])
def test_counts_refuse_zero_out_of_range_and_non_integers(value: ParamValue) -> None:
    with pytest.raises(EncodeError) as err:
        COUNT.snap(value)
    assert err.value.field == "laps"
    assert "laps" in str(err.value)
    assert "1 to 255" in str(err.value)


@pytest.mark.parametrize(
    ("requested", "code", "sent"),
    [("cw", 0, "cw"), ("ccw", 1, "ccw"), ("CW", 0, "cw"), (" Ccw ", 1, "ccw")],
)
def test_direction_choices(requested: str, code: int, sent: str) -> None:
    assert DIRECTION.snap(requested) == (code, sent)
    assert DIRECTION.value_of(code) == sent


@pytest.mark.parametrize("value", ["left", "", "c w", "clockwise", 0, 1, None, 0.0])
def test_direction_refuses_anything_else(value: object) -> None:
    with pytest.raises(EncodeError) as err:
        DIRECTION.snap(value)  # type: ignore[arg-type]
    assert err.value.field == "direction"
    assert "cw" in str(err.value)
    assert "ccw" in str(err.value)


def test_direction_codes() -> None:
    assert isinstance(DIRECTION.scale, ChoiceScale)
    assert DIRECTION.scale.choices == ("cw", "ccw")
    assert valid_codes(DIRECTION) == [0, 1]
    assert not DIRECTION.scale.is_valid_code(2)


@pytest.mark.parametrize(("pattern", "name"), LENGTH_FIELDS + DEPTH_FIELDS + COUNT_FIELDS)
def test_shared_quantizations(pattern: str, name: str) -> None:
    f = field(pattern, name)
    if (pattern, name) in LENGTH_FIELDS:
        assert f.scale == LENGTH.scale
        assert f.unit == "m"
    elif (pattern, name) in DEPTH_FIELDS:
        assert f.scale == DEPTH.scale
        assert f.unit == "m"
    else:
        assert f.scale == COUNT.scale
        assert f.unit == ""


# --- tables: exact values, codes, idempotent snapping ---------------------------------------


@pytest.mark.parametrize(("pattern", "f"), ALL_FIELDS, ids=ALL_IDS)
def test_every_representable_value_snaps_to_itself_and_its_code(pattern: str, f: Field) -> None:
    codes = valid_codes(f)
    assert codes == list(range(codes[0], codes[-1] + 1))  # contiguous
    for code in codes:
        value = f.value_of(code)
        assert f.snap(value) == (code, value)
        if isinstance(value, float):
            assert f.snap(str(value)) == (code, value)
    assert f.snap(f.default)[1] == f.default  # defaults are representable


@pytest.mark.parametrize(("pattern", "f"), NUMERIC_FIELDS, ids=NUMERIC_IDS)
def test_numeric_values_are_exact_decimals_in_increasing_order(pattern: str, f: Field) -> None:
    scale = numeric(f)
    values = scale.values
    assert all(a < b for a, b in pairwise(values))
    assert scale.first_code + len(values) <= 1 << FIELD_BITS
    for v in values:
        assert float(fmt(v)) == v  # 0.07, not 0.07000000000000001
    assert scale.max_abs_error == pytest.approx(max(steps(scale)) / 2)


def nearest_distance(scale: NumericScale, x: float) -> float:
    if scale.period is None:
        return min(abs(v - x) for v in scale.values)
    x %= scale.period
    return min(min(abs(v - x), scale.period - abs(v - x)) for v in scale.values)


@settings(max_examples=300, deadline=None)
@given(data=st.data(), which=st.integers(0, len(NUMERIC_FIELDS) - 1))
def test_snap_is_nearest_and_idempotent(data: st.DataObject, which: int) -> None:
    _, f = NUMERIC_FIELDS[which]
    scale = numeric(f)
    x = data.draw(in_range(f), label=f.name)
    assert not isinstance(x, str)
    code, sent = f.snap(x)
    assert isinstance(sent, int | float)
    assert f.value_of(code) == sent
    assert f.snap(sent) == (code, sent)  # snap(snap(x)) == snap(x)
    assert nearest_distance(scale, sent) == 0
    error = nearest_distance(scale, x) if scale.period is None else None
    if error is not None:
        assert abs(sent - x) <= error + 1e-9
        assert abs(sent - x) <= scale.max_abs_error + 1e-9
    else:  # circular: compare distances around the circle
        d = abs(sent - x % 360)
        assert min(d, 360 - d) <= nearest_distance(scale, x) + 1e-9


@pytest.mark.parametrize(
    ("f", "x", "sent"),
    [
        (LENGTH, 5.125, 5.25),  # midpoint of 5 and 5.25: ties go up
        (LENGTH, 5.124999, 5.0),
        (DURATION, 62.5, 65.0),
        (DURATION, 62.4, 60.0),
        (SPEED, 0.004, 0.0),
        (DEPTH, 4.95, 5.0),
        (DEPTH, 4.94, 4.9),
    ],
)
def test_snap_rounds_to_nearest_ties_up(f: Field, x: float, sent: float) -> None:
    assert f.snap(x)[1] == sent


def brute_force_max_rel_error(f: Field) -> tuple[float, float]:
    """Largest |snap(x) - x| / x over inputs x >= rel_error_from, by scanning the table.

    In each gap a < b the worst inputs sit on either side of the midpoint (ties go up), so
    they are probed there, and at a few points in between as a sanity check.
    """
    scale = numeric(f)
    assert scale.rel_error_from is not None
    lo = scale.rel_error_from
    worst = 0.0
    worst_at = lo
    for a, b in pairwise(scale.values):
        if b <= lo:
            continue
        mid = (a + b) / 2
        probes = [math.nextafter(mid, -math.inf), mid, a + (b - a) / 4, b - (b - a) / 4, a, b]
        for x in probes:
            if x < lo:
                continue
            err = abs(f.snap(x)[1] - x) / x  # type: ignore[operator]
            if err > worst:
                worst, worst_at = err, x
    return worst, worst_at


@pytest.mark.parametrize(("pattern", "f"), NUMERIC_FIELDS, ids=NUMERIC_IDS)
def test_max_rel_error_matches_a_scan_of_the_table(pattern: str, f: Field) -> None:
    scale = numeric(f)
    if scale.rel_error_from is None:
        assert scale.max_rel_error is None
        return
    stated = scale.max_rel_error
    worst, _ = brute_force_max_rel_error(f)
    assert stated is not None
    assert worst <= stated + 1e-12  # a true bound ...
    assert worst == pytest.approx(stated, rel=1e-9)  # ... and attained


def test_length_relative_error_uniform_scan(rng: random.Random) -> None:
    scale = numeric(LENGTH)
    stated = scale.max_rel_error
    assert stated is not None and scale.rel_error_from is not None
    lo, hi = scale.rel_error_from, scale.maximum
    for _ in range(20_000):
        x: float = lo * (hi / lo) ** rng.random()  # log-uniform over the range
        sent = LENGTH.snap(x)[1]
        assert isinstance(sent, float)
        assert abs(sent - x) / x <= stated + 1e-12


# --- strict encoding: errors, never a clamp ---------------------------------------------------


def out_of_range_values(f: Field) -> list[float]:
    scale = numeric(f)
    if scale.period is not None:
        p = scale.period
        return [math.nextafter(p, math.inf), p + 0.5, -math.nextafter(p, math.inf), -p - 0.5, 1e9]
    lo, hi = scale.minimum, scale.maximum
    return [math.nextafter(hi, math.inf), hi + 1, hi * 10 + 1, math.nextafter(lo, -math.inf), -1e9]


OUT_OF_RANGE = [(p, f, x) for p, f in NUMERIC_FIELDS for x in out_of_range_values(f)]


@pytest.mark.parametrize(
    ("pattern", "f", "value"),
    OUT_OF_RANGE,
    ids=[f"{p}.{f.name}={v!r}" for p, f, v in OUT_OF_RANGE],
)
def test_out_of_range_is_an_error_naming_field_unit_and_range(
    pattern: str, f: Field, value: float
) -> None:
    scale = numeric(f)
    params = dict(DICTIONARY[pattern].defaults)
    params[f.name] = value
    with pytest.raises(EncodeError) as err:
        make_command(pattern, params)
    text = str(err.value)
    assert err.value.field == f.name
    assert f.name in text
    assert f.unit in text
    if scale.period is not None:
        assert f"{fmt(-scale.period)} to {fmt(scale.period)}" in text
    else:
        assert f"{fmt(scale.minimum)} to {fmt(scale.maximum)}" in text
    assert "out of range" in text


@pytest.mark.parametrize(
    ("f", "value", "expected"),
    [
        (SPEED, 2.56, ("speed", "m/s", "0 to 2.55")),
        (SPEED, -0.01, ("speed", "m/s", "0 to 2.55")),
        (DEPTH, 108, ("depth", "m", "0 to 107.5")),
        (LENGTH, 751, ("side_span", "m", "0 to 750")),
        (DURATION, 3300, ("duration", "s", "0 to 3210")),
        (HEADING, 361, ("heading", "deg", "-360 to 360")),
    ],
)
def test_out_of_range_messages_spot_checks(
    f: Field, value: float, expected: tuple[str, str, str]
) -> None:
    with pytest.raises(EncodeError) as err:
        f.snap(value)
    for part in expected:
        assert part in str(err.value)
    assert str(err.value).startswith(f"{f.name} = {fmt(value)} {f.unit} is out of range")


@pytest.mark.parametrize(
    ("f", "bad"),
    [
        (SPEED, True),
        (SPEED, None),
        (SPEED, "fast"),
        (SPEED, ""),
        (SPEED, [1.0]),
        (SPEED, {"v": 1}),
        (SPEED, float("nan")),
        (SPEED, float("inf")),
        (DEPTH, "nan"),
        (DEPTH, "-inf"),
        (HEADING, float("inf")),
        (HEADING, "1e400"),
        (COUNT, False),
        (COUNT, "two"),
        (LENGTH, b"5"),
    ],
)
def test_non_numbers_are_encode_errors_naming_the_field(f: Field, bad: object) -> None:
    with pytest.raises(EncodeError) as err:
        f.snap(bad)  # type: ignore[arg-type]
    assert err.value.field == f.name
    assert f.name in str(err.value)


@pytest.mark.parametrize(
    ("f", "huge"),
    [(SPEED, 10**400), (HEADING, -(10**400)), (COUNT, 10**309)],
    ids=["speed=10**400", "heading=-10**400", "laps=10**309"],
)
def test_huge_integers_are_encode_errors_not_overflow(f: Field, huge: int) -> None:
    """An int too large for a float is out of range like any other: EncodeError, not the
    OverflowError of float(huge)."""
    with pytest.raises(EncodeError) as err:
        f.snap(huge)
    assert err.value.field == f.name


@pytest.mark.parametrize(
    ("f", "value"),
    [(COUNT, 0), (COUNT, 300), (COUNT, "x"), (COUNT, 1.5)],
    ids=["laps=0", "laps=300", "laps='x'", "laps=1.5"],
)
def test_messages_of_unitless_fields_are_well_formed(f: Field, value: ParamValue) -> None:
    """No doubled space or dangling "in ," where a unit would go."""
    with pytest.raises(EncodeError) as err:
        f.snap(value)
    text = str(err.value)
    assert "  " not in text, text
    assert " in ," not in text, text


# --- Snap -----------------------------------------------------------------------------------


def test_snap_report_format() -> None:
    _, snaps = make_command(
        "square", {"speed": 0.5, "depth": "2", "side_span": 12.34, "direction": "CW"}
    )
    assert [str(s) for s in snaps] == [
        "speed: requested 0.5 m/s, sent 0.5 m/s",
        "depth: requested 2 m, sent 2 m",
        "side_span: requested 12.34 m, sent 12.5 m",
        "direction: requested CW, sent cw",
    ]
    assert [s.changed for s in snaps] == [False, False, True, False]
    assert snaps[2] == Snap("side_span", "m", 12.34, 12.5)


@pytest.mark.parametrize(
    ("snap", "text", "changed"),
    [
        (Snap("laps", "", 3, 3), "laps: requested 3, sent 3", False),
        (Snap("laps", "", 3.0, 3), "laps: requested 3, sent 3", False),
        (Snap("heading", "deg", -90, 270.0), "heading: requested -90 deg, sent 270 deg", True),
        (Snap("radius", "m", "5", 5.0), "radius: requested 5 m, sent 5 m", False),
        (Snap("speed", "m/s", 0.123, 0.12), "speed: requested 0.123 m/s, sent 0.12 m/s", True),
        (Snap("direction", "", "ccw", "ccw"), "direction: requested ccw, sent ccw", False),
        (Snap("direction", "", " CCW", "ccw"), "direction: requested  CCW, sent ccw", False),
    ],
)
def test_snap_str_and_changed(snap: Snap, text: str, changed: bool) -> None:
    assert str(snap) == text
    assert snap.changed is changed


# --- building quantizations ------------------------------------------------------------------


def test_numeric_scale_from_segments() -> None:
    scale = NumericScale(segments=(Segment("0", "0.1", 3), Segment("1", "0.5", 3)))
    assert scale.values == (0.0, 0.1, 0.2, 1.0, 1.5, 2.0)
    assert (scale.minimum, scale.maximum) == (0.0, 2.0)
    assert not scale.is_linear
    assert scale.max_abs_error == pytest.approx(0.4)
    assert scale.snap("x", "m", 0.7) == (3, 1.0)  # 0.7 is nearer 1.0 than 0.2
    assert scale.snap("x", "m", 0.5) == (2, 0.2)


def test_numeric_scale_refuses_overlap_and_too_many_values() -> None:
    with pytest.raises(ValueError, match="overlaps"):
        NumericScale(segments=(Segment("0", "1", 10), Segment("5", "1", 3)))
    with pytest.raises(ValueError, match="8 bits"):
        NumericScale(segments=(Segment("0", "1", 257),))
    with pytest.raises(ValueError, match="8 bits"):
        NumericScale(segments=(Segment("1", "1", 256),), first_code=1)
    NumericScale(segments=(Segment("1", "1", 255),), first_code=1)  # exactly fits


def decimal_values(scale: NumericScale) -> tuple[float, ...]:
    """The table as the codec built it before it dropped :mod:`decimal` (the reference)."""
    values: list[float] = []
    for seg in scale.segments:
        start, step = Decimal(seg.start), Decimal(seg.step)
        values.extend(float(start + i * step) for i in range(seg.count))
    return tuple(values)


@pytest.mark.parametrize(("pattern", "f"), NUMERIC_FIELDS, ids=NUMERIC_IDS)
def test_values_are_bit_identical_to_decimal_arithmetic(pattern: str, f: Field) -> None:
    scale = numeric(f)
    reference = decimal_values(scale)
    assert [v.hex() for v in scale.values] == [v.hex() for v in reference]
    codes = valid_codes(f)
    assert [float(f.value_of(c)) for c in codes] == list(reference)  # computed without the table
    for seg in scale.segments:
        a, b, d = seg.exact()
        assert Decimal(a) / Decimal(d) == Decimal(seg.start)
        assert Decimal(b) / Decimal(d) == Decimal(seg.step)


@pytest.mark.parametrize(
    "text",
    ["0", "1", "0.025", "2.5", "107.5", "-1.5", "+3", "0.1", "1e3", "1.5E-3", "12.", ".5"],
)
def test_exact_decimal_matches_decimal(text: str) -> None:
    numerator, denominator = exact_decimal(text)
    assert Decimal(numerator) / Decimal(denominator) == Decimal(text)
    assert (numerator / denominator).hex() == float(Decimal(text)).hex()


@pytest.mark.parametrize(
    "text", ["", ".", "1.2.3", "abc", "1e", "1e-", "1e1.5", "0x10", "1_0", "٣", "nan", "inf", "--1"]
)
def test_exact_decimal_refuses_non_decimals(text: str) -> None:
    with pytest.raises(ValueError, match="not a decimal number"):
        exact_decimal(text)


def test_random_segments_match_decimal() -> None:
    rng = random.Random(7)
    for _ in range(300):
        start = f"{rng.randrange(10**6)}e-{rng.randrange(8)}"
        step = f"{rng.randrange(1, 10**6)}e-{rng.randrange(8)}"
        scale = NumericScale(segments=(Segment(start, step, 200),))
        assert scale.values == decimal_values(scale), (start, step)


@pytest.mark.parametrize(("pattern", "f"), ALL_FIELDS, ids=ALL_IDS)
def test_represents_agrees_with_snap(pattern: str, f: Field) -> None:
    candidates: list[ParamValue] = [*representable(f), f.default, -1, 0.123, 1e300, "cw", " CW"]
    if isinstance(f.scale, NumericScale):
        scale = f.scale
        candidates += [scale.maximum + 1, math.nan, math.inf, 360.0, -0.0, 2**80]
        candidates += [math.nextafter(v, math.inf) for v in scale.values[::7]]
        candidates += [str(v) for v in scale.values[::31]]
    for value in candidates:
        try:
            unchanged = f.snap(value)[1] == value
        except EncodeError:
            unchanged = False
        assert f.scale.represents(value) == unchanged, value


def test_numeric_scale_builds_its_table_on_first_use() -> None:
    scale = NumericScale(segments=(Segment("0", "0.5", 10),), name="x")
    assert scale._table is None
    assert scale.is_valid_code(9) and not scale.is_valid_code(10)
    assert scale.value_of(3) == 1.5
    assert (scale.minimum, scale.maximum) == (0.0, 4.5)
    assert scale._table is None  # none of the above needed it
    assert scale.snap("x", "m", 1.4) == (3, 1.5)
    assert scale._table == (0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5)
    with pytest.raises(IndexError):
        scale.value_of(10)
    with pytest.raises(IndexError):
        scale.value_of(-1)


def test_numeric_scale_needs_a_value() -> None:
    with pytest.raises(ValueError, match="at least one value"):
        NumericScale(segments=())
    with pytest.raises(ValueError, match="at least one value"):
        NumericScale(segments=(Segment("0", "1", 0),))


def test_choice_scale_size_limits() -> None:
    with pytest.raises(ValueError):
        ChoiceScale(choices=())
    with pytest.raises(ValueError):
        ChoiceScale(choices=tuple(f"c{i}" for i in range(257)))


def test_field_default_must_be_representable() -> None:
    with pytest.raises(ValueError, match="not representable"):
        Field("speed", "speed", "m/s", SPEED.scale, 0.123, "")


def test_representable_lists_match_codes() -> None:
    assert representable(DIRECTION) == ["cw", "ccw"]
    assert representable(COUNT) == list(range(1, 256))
    assert representable(SPEED)[:3] == [0.0, 0.01, 0.02]
