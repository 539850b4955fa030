"""``nemesys bench planner`` prints every pattern's row with its targets and the memory
comparison (figures are not asserted: timings belong to the benchmark, not the tests)."""

from __future__ import annotations

import io

from bench import planner as bench_planner
from codec import DICTIONARY, decode_frame, frame_of


def test_quick_run_prints_every_pattern_and_the_memory_rows() -> None:
    out = io.StringIO()
    assert bench_planner.run(out, quick=True) == 0
    text = out.getvalue()
    lines = text.splitlines()
    for name in DICTIONARY:
        row = next(ln for ln in lines if ln.startswith(name + " "))
        cells = row.split()
        assert int(cells[1]) >= 1  # waypoints
        assert float(cells[2]) > 0 and float(cells[3]) > 0  # total and per-waypoint us
        assert row.count("met") + row.count("MISSED") == 2
    assert "1620 ms" in text and "26 ms" in text and "15 ms/wp" in text
    bare = next(ln for ln in lines if ln.startswith("plain interpreter (python -I -S"))
    onboard = next(ln for ln in lines if ln.startswith("import codec + planner"))
    bare_mib = float(bare.split(" MiB")[0].split()[-1])
    onboard_mib = float(onboard.split(" MiB")[0].split()[-1])
    assert 1.0 < bare_mib < onboard_mib  # the onboard process does load something
    assert 'paper 13.2 "MB"' in onboard
    assert " MB" not in text.replace('13.2 "MB"', "")  # our figures are MiB, named so
    added = next(ln for ln in lines if ln.startswith("added by the onboard path"))
    assert "<= 1.00 MiB" in added and ("met" in added or "MISSED" in added)
    assert "corrected: 0 1 2 0 1 2 0 1 2" in text  # the frames fed carried bit errors


def test_memory_frames_carry_errors_the_onboard_process_corrects() -> None:
    frames, errors = bench_planner.onboard_frames()
    assert len(frames) == len(DICTIONARY) and set(errors) == {0, 1, 2}
    for text, n in zip(frames, errors, strict=True):
        decoded = decode_frame(text)
        assert decoded.corrected == n  # the decode's own count: errors were really corrected
        assert (int(text, 16) ^ frame_of(decoded.command).value).bit_count() == n
    bare, onboard, corrected = bench_planner.memory_kb(1)
    assert corrected == errors  # reported by the measured process itself
    assert 1024 < bare < onboard


def test_running_square_state_is_on_the_square() -> None:
    current, state = bench_planner.running_square()
    assert current.pattern == "square"
    # 30 s in at 0.5 m/s: on the square's body, at its depth
    assert abs(state.z_m - 5.0) < 1e-9
    assert abs(max(abs(state.x_m), abs(state.y_m)) - 5.0) < 1e-6
