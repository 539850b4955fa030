"""The addressing comparison (analysis.addressing, analysis.addressing_mc): the counting behind
the analytic figure, the Monte Carlo against it, the choice, and the chosen design through the
codec: a vehicle never executes another's frame in 10^7 corrupted frames at BER 1e-2 (slow
tier; tests/codec/test_batch_addressed.py runs 10^5 through the real receiver in the fast
tier)."""

from __future__ import annotations

import io
import itertools
import random

import numpy as np
import pytest

from analysis.addressing import (
    BERS,
    CODEC_DESIGN,
    DESIGNS,
    REQUIRED,
    Figures,
    chosen,
    count_keys,
    design,
    enumerate_design,
    figures,
    pairs,
    vectors_of,
)
from analysis.addressing_mc import Counts, Engine, run_codec, run_design
from analysis.addressing_report import format_report, run
from analysis.ber_analytic import wilson
from analysis.ber_montecarlo import CommandTables
from cli.main import main
from codec import (
    AddressedFrame,
    DecodeError,
    RejectReason,
    addressed_frame_of,
    decode_frame,
    encode_frame,
    payload_of,
)
from codec.batch_addressed import addressed_messages, encode_addressed

#: Weights counted exactly in the fast tests (the command counts to 8).
W_FAST = 6
#: The dictionary's reasons: a frame that passed the address check, refused after it.
DICTIONARY_REASONS = {
    RejectReason.UNKNOWN_PATTERN,
    RejectReason.FIELD_OUT_OF_RANGE,
    RejectReason.UNUSED_FIELD_SET,
}


def agrees(count: int, frames: int, expected: float) -> bool:
    """``expected`` inside the Wilson 99.9 % interval of ``count / frames``."""
    low, high = wilson(count, frames, z=3.29)
    return low <= expected <= high


# --- the counting ----------------------------------------------------------------------------


def test_meeting_in_the_middle_counts_what_brute_force_counts() -> None:
    rng = random.Random(4)
    keys = np.array([rng.getrandbits(9) for _ in range(18)], dtype=np.int64)
    targets = [0, 5, 300, 511]
    for weight in range(5):
        expected = dict.fromkeys(targets, 0)
        for subset in itertools.combinations(range(18), weight):
            key = 0
            for i in subset:
                key ^= int(keys[i])
            if key in expected:
                expected[key] += 1
        assert count_keys(keys, weight, targets) == expected, weight
        if weight:
            assert len(vectors_of(keys, weight, 5)) == expected[5]


def test_no_light_codeword_moves_one_address_to_another() -> None:
    """The chosen layout (fast: to weight 6; the slow test below: to 8)."""
    d = design(CODEC_DESIGN)
    counts = enumerate_design(d, W_FAST).counts
    targets = {t for b, a in pairs() for t in d.targets(b, a)}
    assert all(counts[w][t] == 0 for w in range(W_FAST + 1) for t in targets)


@pytest.mark.slow  # the weight-8 count (~5 s)
def test_no_codeword_lighter_than_8_bits_moves_one_address_to_another() -> None:
    """The chosen layout's exact counts: nothing below weight 8, and every weight-8 vector is
    real: a frame to vehicle 3 with 6 of its bits flipped is taken by vehicle 5's decoder as
    its own or as to all (the dictionary's checks may still refuse its command)."""
    d = design(CODEC_DESIGN)
    counts = enumerate_design(d, 8).counts
    targets = {t for b, a in pairs() for t in d.targets(b, a)}
    assert all(counts[w][t] == 0 for w in range(8) for t in targets)
    assert sum(counts[8][t] for t in targets) > 0
    frame = addressed_frame_of(payload_of(encode_frame("surface").command), 3)
    keys = d.position_keys()
    seen = set()
    for target in d.targets(3, 5):
        for vector in vectors_of(keys, 8, target):
            for kept in itertools.combinations(vector, 6):
                value = frame.value ^ sum(1 << (4 + i) for i in kept)
                try:
                    dec = decode_frame(AddressedFrame(value), vehicle=5)
                    seen.add(dec.address)  # type: ignore[attr-defined]
                except DecodeError as err:
                    assert err.reason in DICTIONARY_REASONS, err
                    seen.add(err.reason)
    assert seen  # the vectors exist, and none was refused before the dictionary


def test_the_engine_makes_the_codecs_frames() -> None:
    rng = np.random.default_rng(8)
    senders = rng.integers(0, 16, 500)
    payloads = CommandTables().draw(rng, 500)
    frames = Engine(design(CODEC_DESIGN)).encode(senders, payloads)
    assert np.array_equal(frames, encode_addressed(addressed_messages(senders, payloads)))
    for i in range(20):
        ours = addressed_frame_of(int(payloads[i]), int(senders[i]))
        assert frames[i].tobytes() == ours.to_bytes()


# --- the Monte Carlo against the analytic figure -------------------------------------------


@pytest.mark.parametrize(("key", "ber"), [("a", 1e-2), ("ccoset", 1e-2), ("cseed", 3e-2)])
def test_monte_carlo_reproduces_the_analytic_figure(key: str, ber: float) -> None:
    d = design(key)
    counts = run_design(d, 60_000, "independent", ber, np.random.default_rng(11))
    exact = figures(d, ber, W_FAST)
    assert counts.misaddressed > 20
    assert agrees(counts.misaddressed, counts.frames, exact.misaddressed_mean)
    assert agrees(counts.lost, counts.frames, exact.lost)


@pytest.mark.slow  # every design and BER, 300 000 frames each: ~90 s in all
@pytest.mark.parametrize("d", DESIGNS, ids=[d.key for d in DESIGNS])
def test_monte_carlo_reproduces_every_design(d: object) -> None:
    for ber in BERS:
        counts = run_design(d, 300_000, "independent", ber, np.random.default_rng(12))  # type: ignore[arg-type]
        exact = figures(d, ber)  # type: ignore[arg-type]
        assert agrees(counts.misaddressed, counts.frames, exact.misaddressed_mean), ber
        assert agrees(counts.lost, counts.frames, exact.lost), ber


def test_the_codecs_numpy_path_loses_what_the_figure_says() -> None:
    d = design(CODEC_DESIGN)
    for ber in (1e-2, 3e-2):
        counts = run_codec(50_000, "independent", ber, np.random.default_rng(13))
        assert counts.misaddressed == counts.executed == 0
        assert agrees(counts.lost, counts.frames, figures(d, ber, W_FAST).lost)


# --- the choice ------------------------------------------------------------------------------


def test_only_the_codecs_design_meets_the_requirement() -> None:
    rows = {d.key: figures(d, 1e-2, W_FAST) for d in DESIGNS}
    assert chosen(rows) == CODEC_DESIGN
    assert pytest.approx(2.45e-6 / 400) == REQUIRED
    for d in DESIGNS:
        worst = rows[d.key].misaddressed_max
        assert (worst <= REQUIRED) == (d.key == CODEC_DESIGN), (d.key, worst)
    assert rows[CODEC_DESIGN].misaddressed_max < REQUIRED / 10  # a wide margin
    with pytest.raises(ValueError, match=r"at BER 0\.01"):
        chosen({d.key: Figures(3e-2, 0.0, 0.0, 0.0) for d in DESIGNS})


@pytest.mark.slow  # 10^7 frames through the codec's numpy path: ~10 s
def test_a_vehicle_never_executes_another_vehicles_frame_in_ten_million() -> None:
    counts = Counts()
    for seed in range(10):
        counts.add(run_codec(1_000_000, "independent", 1e-2, np.random.default_rng([99, seed])))
    assert counts.frames == 10_000_000
    assert counts.misaddressed == counts.executed == 0
    assert agrees(counts.lost, counts.frames, figures(design(CODEC_DESIGN), 1e-2).lost)


@pytest.mark.slow  # the whole report at smoke size: ~15 s
def test_the_report_and_the_command() -> None:
    report = run(frames=2_000, seed=1, w_exact=7)
    text = format_report(report)
    assert "(chosen)" in text and f"(`{CODEC_DESIGN}`)" in text
    assert text.count("| codec |") == 7  # the codec's own path, every condition
    out = io.StringIO()
    assert main(["analyze", "addressing", "--quick", "--trials", "1000"], out=out) == 0
    assert "[8,4,4] address word in BCH(80,64) (chosen)" in out.getvalue()
    assert main(["analyze", "addressing", "--trials", "0"], out=io.StringIO()) == 2
