"""``nemesys analyze ber``: the Monte Carlo agrees with the analytic curve and the paper's
figure, the T != 2 decoder is the codec's, and the outputs are what they claim to be.

The analysis runs once, in :data:`analysis.ber.TEST` size (a few seconds: 50 000 T = 2
frames per BER, 10 000 for the other T), with a fixed seed, so every figure below is
deterministic; the tolerances are still set so that another seed would pass (4-4.5 binomial
standard deviations, plus 3 frames where the expected count of failures is near zero).
"""

from __future__ import annotations

import csv
import io
import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from numpy.typing import NDArray

from analysis import ber
from analysis.ber import (
    BerConfig,
    BerReport,
    BitFrames,
    CommandTables,
    Simulator,
    SuccessPoint,
    WrongAcceptance,
)
from cli.main import main
from codec import DICTIONARY, BCHCode, DecodeError, command_of_message
from codec.batch import decode_frames, encode_messages, inject_errors, messages_of_payloads
from tests.tiers import slow_fixture

#: Research note (codec.md section 6), n = 56 + 8T: P(<= T errors in n) at BER 1e-2 and 3e-2.
RESEARCH = {
    (1, 1e-2): 0.865376,
    (2, 1e-2): 0.964193,
    (3, 1e-2): 0.991341,
    (4, 1e-2): 0.998030,
    (1, 3e-2): 0.424148,
    (2, 3e-2): 0.632817,
    (3, 3e-2): 0.780667,
    (4, 3e-2): 0.874725,
}


@pytest.fixture(scope="module")
@slow_fixture  # a BER analysis run, ~2.5 s
def run(tmp_path_factory: pytest.TempPathFactory) -> tuple[BerReport, str]:
    progress = io.StringIO()
    out = tmp_path_factory.mktemp("ber")
    report = ber.analyze_config(out, ber.TEST, seed=0, progress=progress)
    return report, progress.getvalue()


@pytest.fixture(scope="module")
def report(run: tuple[BerReport, str]) -> BerReport:
    return run[0]


def _point(report: BerReport, t: int, ber_: float) -> SuccessPoint:
    return next(p for p in report.points if p.t == t and p.ber == ber_)


def _sd(p: SuccessPoint) -> float:
    a = p.analytic_frame
    return math.sqrt(a * (1 - a) / p.frames)


def _consistent(p: SuccessPoint, sigmas: float) -> bool:
    """Successes within ``sigmas`` binomial sd of the exact prediction, give or take 3 frames
    (so a rare failure where almost none is expected, e.g. 1e-8 at BER 1e-4, is no alarm)."""
    mean = p.frames * p.analytic_frame
    return abs(p.successes - mean) <= sigmas * p.frames * _sd(p) + 3


# --- analytic -------------------------------------------------------------------------------


@pytest.mark.parametrize(("t", "p"), [(1, 1e-3), (2, 1e-2), (3, 3e-2), (4, 0.1), (2, 0.5)])
def test_analytic_is_the_binomial_sum(t: int, p: float) -> None:
    n = 56 + 8 * t
    direct = sum(math.comb(n, i) * p**i * (1 - p) ** (n - i) for i in range(t + 1))
    assert ber.analytic_success(t, p) == pytest.approx(direct, rel=1e-12)
    sync = sum(math.comb(24, i) * p**i * (1 - p) ** (24 - i) for i in range(3))
    assert ber.analytic_frame_success(t, p) == pytest.approx(direct * sync, rel=1e-12)


@pytest.mark.parametrize(("key", "value"), sorted(RESEARCH.items()))
def test_analytic_matches_the_research_table(key: tuple[int, float], value: float) -> None:
    assert ber.analytic_success(*key) == pytest.approx(value, abs=5e-7)


def test_wilson_interval() -> None:
    z2 = ber.Z95**2
    low, high = ber.wilson(0, 1000)
    assert low == 0.0 and high == pytest.approx(z2 / (1000 + z2))
    low, high = ber.wilson(50, 100)
    assert 0.5 - low == pytest.approx(high - 0.5) and 0.40 < low < 0.41
    low, high = ber.wilson(1000, 1000)
    assert high == 1.0 and low == pytest.approx(1000 / (1000 + z2))


def test_efficiency_values_are_exact() -> None:
    eff = {e.t: e for e in ber.efficiency_table()}
    assert [(e.n, e.k, e.m) for e in eff.values()] == [
        (64, 56, 8),
        (72, 56, 8),
        (80, 56, 8),
        (88, 56, 8),
    ]
    e2 = eff[2]
    assert e2.code_rate == 56 / 72 and round(e2.code_rate, 4) == 0.7778
    assert e2.paper_efficiency == 56 / (56 + 2 * 8 * 2)  # 0.636 with our field's m = 8
    assert e2.paper_efficiency_m7 == 56 / 84 and round(e2.paper_efficiency_m7, 3) == 0.667
    assert e2.frame_efficiency == 0.52  # the 52-bit payload over the 100-bit frame
    for t, e in eff.items():
        assert e.n == BCHCode(t).n == 56 + 8 * t
        assert e.code_rate == 56 / e.n and e.frame_efficiency == 52 / (e.n + 28)


# --- the vectorised decoder of T != 2 is the codec's ---------------------------------------------


def _codeword_ints(model: BitFrames, frames: NDArray[np.uint8]) -> list[int]:
    shift = 8 * model.frame_bytes - 24 - model.n
    mask = (1 << model.n) - 1
    return [(int.from_bytes(bytes(row), "big") >> shift) & mask for row in frames]


@pytest.mark.parametrize("t", [1, 2, 3, 4])
def test_bitframes_decode_equals_bchcode_decode(t: int) -> None:
    """Word by word against :meth:`codec.BCHCode.decode` (Berlekamp-Massey + Chien), for
    0 .. t + 3 codeword errors: the same accept/reject and the same corrected message."""
    model, code = BitFrames(t), BCHCode(t)
    rng = np.random.default_rng(t)
    payloads = CommandTables().draw(rng, 400)
    messages = messages_of_payloads(payloads)
    clean = model.encode(messages)
    assert _codeword_ints(model, clean) == [code.encode(int(m)) for m in messages]
    for weight in range(t + 4):
        frames = clean.copy()
        for row in range(frames.shape[0]):
            for bit in rng.choice(model.n, size=weight, replace=False) + 24:
                frames[row, bit // 8] ^= 0x80 >> (bit % 8)
        decision = model.decode(frames)
        for i, word in enumerate(_codeword_ints(model, frames)):
            message, corrected = code.decode(word)
            assert bool(decision.bch_ok[i]) == (corrected >= 0), (weight, i)
            if corrected >= 0:
                assert int(decision.message[i]) == message
        if weight <= t:
            assert decision.bch_ok.all() and (decision.message == messages).all()


@pytest.mark.parametrize("ber_", [1e-3, 1e-2, 5e-2, 0.2])
def test_bitframes_at_t2_is_codec_batch(ber_: float) -> None:
    """The generic layout at T = 2 is the real frame byte for byte, and decides like it."""
    rng = np.random.default_rng(7)
    messages = messages_of_payloads(CommandTables().draw(rng, 20_000))
    frames = encode_messages(messages)
    assert (BitFrames(2).encode(messages) == frames).all()
    inject_errors(frames, ber_, rng)
    real = decode_frames(frames)
    mine = BitFrames(2).decode(frames)
    assert (mine.sync_errors == real.sync_errors).all()
    synced = real.sync_errors <= 2
    assert (mine.bch_ok[synced] == (real.corrected[synced] >= 0)).all()
    ok = synced & mine.bch_ok
    assert (mine.message[ok] == real.message[ok]).all()
    # The simulator's own recombination of the checks gives codec.batch's verdict.
    sim = Simulator(2, CommandTables())
    sim.model = BitFrames(2)
    with_crc, without, _ = sim.receive(frames)
    assert (with_crc == real.accepted).all()
    assert (without >= with_crc).all()


def test_random_commands_are_valid_and_checks_match_the_codec() -> None:
    tables = CommandTables()
    rng = np.random.default_rng(3)
    payloads = tables.draw(rng, 3000)
    assert tables.check(payloads).all()
    for m in messages_of_payloads(payloads[:300]):
        command_of_message(int(m))  # raises if not a valid command
    assert len({int(p) >> 48 for p in payloads}) == len(DICTIONARY)  # every pattern
    garbage = rng.integers(0, 1 << 52, 3000, dtype=np.uint64)
    verdict = tables.check(garbage)
    for m, ok in zip(messages_of_payloads(garbage), verdict, strict=True):
        try:
            command_of_message(int(m))
        except DecodeError:
            assert not ok
        else:
            assert ok


@pytest.mark.parametrize(("bits", "ber_"), [(92, 1e-3), (116, 2e-2), (108, 0.3)])
def test_inject_independent_statistics(bits: int, ber_: float) -> None:
    n = 100_000
    frames = np.zeros((n, (bits + 7) // 8), dtype=np.uint8)
    ber.inject_independent(frames, bits, ber_, np.random.default_rng(1))
    flips = np.unpackbits(frames, axis=1)
    assert not flips[:, bits:].any()
    mean = flips.sum() / (n * bits)
    assert abs(mean - ber_) < 5 * math.sqrt(ber_ * (1 - ber_) / (n * bits))


@pytest.mark.parametrize("length", [8, 24])
def test_inject_burst_stays_in_a_codeword_window(length: int) -> None:
    n_cw = 72
    frames = np.zeros((20_000, 13), dtype=np.uint8)
    ber.inject_burst(frames, n_cw, length, np.random.default_rng(2))
    flips = np.unpackbits(frames, axis=1).astype(bool)
    assert not flips[:, :24].any() and not flips[:, 24 + n_cw :].any()
    hit = flips.any(axis=1)
    first = np.argmax(flips, axis=1)
    last = flips.shape[1] - 1 - np.argmax(flips[:, ::-1], axis=1)
    assert (last[hit] - first[hit] < length).all()
    assert flips.sum(axis=1).mean() == pytest.approx(length / 2, rel=0.02)


# --- the analysis run ---------------------------------------------------------------------------


def test_t2_success_at_1e2_is_the_papers_0964(report: BerReport) -> None:
    p = _point(report, 2, 1e-2)
    assert p.frames >= 20_000
    assert abs(p.rate - 0.964) <= 0.005
    assert p.analytic == pytest.approx(0.964193, abs=5e-7)
    # The exact prediction includes the sync word (0.9625): within 4 sigma.
    assert _consistent(p, 4.0)


def test_every_point_agrees_with_the_analytic_frame_success(report: BerReport) -> None:
    assert {p.t for p in report.points} == {1, 2, 3, 4}
    assert len(report.points) == 4 * len(ber.BERS)
    for p in report.points:
        assert p.n == 56 + 8 * p.t
        assert p.ci_low <= p.rate <= p.ci_high
        assert p.rate == p.successes / p.frames
        assert _consistent(p, 4.5), p


def test_success_is_near_one_at_1e4_for_every_t(report: BerReport) -> None:
    for t in (1, 2, 3, 4):
        assert _point(report, t, 1e-4).rate >= 0.999


def test_success_falls_with_ber_and_rises_with_t(report: BerReport) -> None:
    for t in (1, 2, 3, 4):
        rates = [_point(report, t, b).rate for b in ber.BERS]
        for a, b in itertools.pairwise(rates):
            assert b <= a + 2e-3  # non-increasing up to Monte Carlo noise
        assert rates[-1] < _point(report, t, 1e-2).rate < _point(report, t, 1e-3).rate
    at_3e2 = [_point(report, t, 3e-2).rate for t in (1, 2, 3, 4)]
    assert at_3e2 == sorted(at_3e2) and len(set(at_3e2)) == 4


def test_wrong_acceptance_with_crc_never_exceeds_without(report: BerReport) -> None:
    rows: dict[tuple[int, str, float], dict[bool, WrongAcceptance]] = {}
    for w in report.wrong:
        rows.setdefault((w.t, w.errors, w.level), {})[w.crc] = w
    assert len(rows) == len(ber.TS) * (len(ber.TEST.wrong_bers) + len(ber.TEST.burst_lengths))
    for pair in rows.values():
        with_crc, without = pair[True], pair[False]
        assert with_crc.frames == without.frames
        assert with_crc.wrong <= without.wrong
        for w in (with_crc, without):
            assert w.rate == w.wrong / w.frames <= w.ci_high
            if w.wrong == 0:
                assert w.ci_high == pytest.approx(ber.Z95**2 / (w.frames + ber.Z95**2))
    # The real code: BCH + dictionary alone lets through ~3e-4 wrong commands at 1e-2, the
    # CRC-4 removes nearly all of them (research note: 1.2e-3 BCH alone, 1.5e-5 with CRC).
    t2 = rows[(2, "independent", 1e-2)]
    assert 1e-4 < t2[False].rate < 1e-3
    assert t2[True].rate < 2e-5


def test_csv_files_and_png(report: BerReport) -> None:
    with report.csv_path.open() as f:
        rows = list(csv.DictReader(f))
    assert tuple(rows[0]) == ber.SUCCESS_COLUMNS
    assert len(rows) == len(report.points)
    first = report.points[0]
    assert int(rows[0]["t"]) == first.t and int(rows[0]["successes"]) == first.successes
    assert float(rows[0]["analytic"]) == pytest.approx(first.analytic, rel=1e-8)
    with report.wrong_csv_path.open() as f:
        wrong = list(csv.DictReader(f))
    assert tuple(wrong[0]) == ber.WRONG_COLUMNS
    assert len(wrong) == len(report.wrong)
    assert {r["crc"] for r in wrong} == {"0", "1"}
    assert {r["errors"] for r in wrong} == {"independent", "burst"}
    assert report.png_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert report.png_path.parent == report.csv_path.parent == report.wrong_csv_path.parent


def test_progress_bar_and_report_text(run: tuple[BerReport, str]) -> None:
    report, progress = run
    assert progress.startswith("\r[") and progress.endswith("\n")
    assert "100 %" in progress and "done" in progress
    text = ber.format_report(report)
    assert "T=2 at BER 0.01" in text and "0.964193" in text
    assert "0.7778" in text and "0.6667" in text
    assert str(report.png_path) in text and str(report.csv_path) in text


@pytest.mark.slow  # two analysis runs, ~1 s
def test_same_seed_same_figures(tmp_path: Path) -> None:
    tiny = BerConfig("tiny", 3000, 500, 3000, 500, ts=(1, 2), bers=(1e-2,), wrong_ts=(1,),
                     wrong_bers=(0.1,), burst_lengths=())  # fmt: skip
    a = ber.analyze_config(tmp_path / "a", tiny, seed=4)
    b = ber.analyze_config(tmp_path / "b", tiny, seed=4)
    assert a.points == b.points and a.wrong == b.wrong
    c = ber.analyze_config(tmp_path / "c", tiny, seed=5)
    assert c.points != a.points


# --- command line -------------------------------------------------------------------------------


@pytest.mark.slow  # an analysis run through the CLI
def test_cli_analyze_ber(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    tiny = BerConfig("tiny", 2000, 500, 2000, 500, bers=(1e-3, 1e-2), wrong_ts=(2,),
                     wrong_bers=(1e-2,), burst_lengths=(8,))  # fmt: skip
    monkeypatch.setattr(ber, "QUICK", tiny)
    out = io.StringIO()
    assert main(["analyze", "ber", "--quick", "--out", str(tmp_path), "--seed", "3"], out) == 0
    text = out.getvalue()
    assert "Decode success vs BER" in text and "Coding efficiency" in text
    assert "Wrong command accepted" in text and f"wrote {tmp_path / 'ber.png'}" in text
    assert (tmp_path / "ber.csv").exists() and (tmp_path / "ber_wrong.csv").exists()
    assert "100 %" in capsys.readouterr().err
    assert main(["analyze", "nothing"], io.StringIO()) == 2
