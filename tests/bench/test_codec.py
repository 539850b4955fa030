"""``nemesys bench codec`` runs and prints every row with its target (figures are not
asserted: timings belong to the benchmark, not the tests)."""

from __future__ import annotations

import io

from bench import codec as bench_codec


def test_quick_run_prints_the_full_table() -> None:
    out = io.StringIO()
    assert bench_codec.run(out, quick=True) == 0
    text = out.getvalue()
    for row in (
        "decode, 0 errors",
        "decode, 1 errors",
        "decode, 2 errors",
        "decode, 3 errors (rejected)",
        "encode, 56 -> 72 bits",
        "BER 0.01",
    ):
        line = next(ln for ln in text.splitlines() if row in ln)
        assert "met" in line or "MISSED" in line
    assert "bchlib (C, bytes)" in text and "paper" in text and " 27 " in text
    assert "n/a" not in text  # bchlib (the peer) was measured in the same run
    receiver = next(ln for ln in text.splitlines() if "receive_frame, 13 bytes" in ln)
    cells = [c.strip() for c in receiver.split("  ") if c.strip()]
    assert cells[1] == "-" and float(cells[2]) > 0  # us of the whole onboard decode
    assert cells[5].startswith("0.") or float(cells[5]) > 0  # ratio to bchlib, same run
