"""``nemesys bench reconfig`` prints the paper's Table tab:reconfig_metrics beside ours (figures
are not asserted beyond being positive: timings belong to the benchmark, not the tests)."""

from __future__ import annotations

import io
import random

import pytest

from bench import reconfig
from bench._onboard import decode_rows, time_decode, wire
from codec import Accepted, FrameReceiver, frame_of
from tests.codec.helpers import random_command


def _row(lines: list[str], start: str) -> list[str]:
    row = next(ln for ln in lines if ln.startswith(start))
    return [c.strip() for c in row[len(start) :].split("  ") if c.strip()]


@pytest.mark.slow  # a benchmark run, ~2 s
def test_quick_run_prints_paper_ours_and_ratio() -> None:
    out = io.StringIO()
    assert reconfig.run(out, quick=True) == 0
    text = out.getvalue()
    lines = text.splitlines()
    header = next(ln for ln in lines if ln.startswith("metric"))
    assert "paper" in header and "ours" in header and "ratio (paper/ours)" in header
    for name, paper in (("Shipwreck", 42.0), ("BOP", 15.0), ("Pod", 46.0)):
        cells = _row(lines, f"{name}: normalised replan latency (ms/waypoint)")
        assert float(cells[0]) == paper
        assert float(cells[1]) > 0  # ours
        assert "x " in cells[2]  # e.g. "3,461x faster"
    cells = _row(lines, "decode latency (ms, mean of 30 trials)")
    assert float(cells[0]) == 0.027 and float(cells[1]) > 0
    for start in ("memory: peak RSS", "memory: increment"):
        row = next(ln for ln in lines if ln.startswith(start))
        assert "13.2" in row and 'paper "MB", ours MiB' in row
    assert " MB " not in text and " MB," not in text  # ours are MiB, named so
    assert "MiB (+" in text and "target <= 1.00 MiB" in text
    assert "bits the agent corrected per frame: 1 2 2 0 2 1." in text
    # The whole onboard decode beside bchlib, same run, and the bound.
    for start in ("0 errors", "1 errors", "2 errors", "mean over 0-2 errors"):
        cells = _row(lines, start)
        receiver, bit_level, bchlib = (float(c) for c in cells[:3])
        assert receiver > 0 and bit_level > 0 and bchlib > 0
        assert cells[3].endswith("x") and cells[5] == "27"
        judged = start.startswith("mean")  # the bound is on the mean over 0-2 errors
        assert cells[4] == ("<= 3x bchlib" if judged else "(info)")
        assert cells[6] in (("met", "MISSED") if judged else ("-",))
    assert "Whole decode / bchlib over 0-2 errors: " in text
    for name in ("Shipwreck", "BOP", "Pod"):
        detail = next(ln for ln in lines if ln.startswith(name + " "))
        assert int(detail.split()[4]) >= 2  # waypoints, after "name a -> b"
    # The memory's baseline is named: a plain interpreter, no start-up hook.
    assert "the baseline, a plain interpreter (python -I -S" in text and "Machine:" in text


@pytest.mark.slow  # a benchmark run, ~1.5 s
def test_measure_quick_report_is_consistent() -> None:
    report = reconfig.measure(quick=True)
    assert [s.name for s in report.scenarios] == ["wreck", "panel", "pod"]
    assert report.decode_trials == 30 and report.rounds == len(report.round_decode_ms)
    assert report.decode_ms > 0
    for s in report.scenarios:
        assert s.replan_ms > 0 and s.normalised_ms > 0 and s.waypoints >= 2
        assert s.normalised_ms == s.replan_ms / s.waypoints
        assert len(s.round_normalised_ms) == report.rounds
    assert report.scenarios[0].retask == "lawnmower -> lawnmower"
    assert report.scenarios[2].retask == "square -> circle"
    assert 1024 < report.bare_kb < report.peak_kb  # the onboard process loads something
    assert report.increment_kb == report.peak_kb - report.bare_kb
    # The memory run's frames carried errors, and the agent corrected them.
    assert report.memory_corrected == (1, 2, 2, 0, 2, 1)
    timing = report.onboard_decode
    assert timing is not None and timing.bchlib_us is not None  # bchlib: the dev extras
    assert len(timing.receiver_us) == len(timing.bchlib_us) == 3
    assert report.decode_bchlib_ratio == pytest.approx(
        timing.receiver_mean_us / (sum(timing.bchlib_us) / 3)
    )


@pytest.mark.slow  # onboard subprocesses, ~1 s
def test_memory_arguments_carry_the_errors_the_agent_corrects() -> None:
    args = reconfig.onboard_arguments()
    received = [int(item.split(",")[0], 16) for arg in args for item in arg.split(";")]
    corrected = []
    for frame in received:
        (event,) = FrameReceiver().feed_bytes(wire(frame))
        assert isinstance(event, Accepted)
        corrected.append(event.decoded.corrected)
    expected = [e for name in reconfig.RETASK_SCENARIOS for e in reconfig.MEMORY_ERRORS[name]]
    assert corrected == expected and {1, 2} <= set(corrected)


@pytest.mark.slow  # onboard subprocesses, ~1 s
def test_onboard_arguments_carry_both_frames_of_each_scenario() -> None:
    args = reconfig.onboard_arguments()
    assert len(args) == 3
    for arg in args:
        frames = arg.split(";")
        assert len(frames) == 2
        for frame in frames:
            fields = frame.split(",")
            assert len(fields) == 8 and len(fields[0]) == 25  # 100-bit frame as hex


def test_ratio_says_faster_or_slower() -> None:
    assert reconfig.ratio(42.0, 0.01) == "4,200x faster"
    assert reconfig.ratio(0.027, 0.0135) == "2x faster"
    assert reconfig.ratio(13.2, 20.0, "smaller", "larger") == "0.66x (1.52x larger)"


def test_onboard_decode_timing_is_taken_over_frames_with_errors() -> None:
    timing = time_decode([frame_of(random_command(random.Random(1))).value], rounds=1, loops=1)
    assert timing.frames == 4 and timing.rounds == 1
    assert all(t > 0 for t in (*timing.receiver_us, *timing.bit_level_us))
    rows = decode_rows(timing)
    assert [r[0] for r in rows] == ["0 errors", "1 errors", "2 errors", "mean over 0-2 errors"]
