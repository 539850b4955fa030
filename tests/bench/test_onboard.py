"""``nemesys bench onboard`` prints the onboard table: each Python's two ratios against bchlib
and memory increment, beside their targets, and names its memory baseline (figures are not
asserted: timings belong to the benchmark, not the tests)."""

from __future__ import annotations

import io
import platform
import subprocess
import sys

import pytest

from bench import onboard
from bench._timing import PLAIN_FLAGS, ROOT, plain_command


@pytest.mark.slow  # fresh processes per Python, ~3 s
def test_quick_run_prints_each_python_with_the_targets() -> None:
    out = io.StringIO()
    assert onboard.run(out, quick=True) == 0
    text = out.getvalue()
    lines = text.splitlines()
    header = next(ln for ln in lines if ln.startswith("python "))
    assert "codeword decode / bchlib (<= 1x)" in header
    assert "whole decode / bchlib (<= 3x)" in header
    assert "memory increment (<= 1.00 MiB)" in header
    row = next(ln for ln in lines if ln.startswith(platform.python_version() + " "))
    cells = [c.strip() for c in row.split("  ") if c.strip()]
    for cell in cells[1:3]:  # the ratios, with bchlib (the dev extras) here
        assert cell.split("x ")[1] in ("(met)", "(MISSED)") and float(cell.split("x")[0]) > 0
    assert cells[3].endswith(("MiB (met)", "MiB (MISSED)"))
    assert "the baseline, a plain interpreter (python -I -S" in text
    assert "Machine:" in text


def test_the_baseline_runs_no_site_and_sees_only_the_checkout() -> None:
    """The plain interpreter: no site (so no editable-install hook) and the environment's
    PYTHONPATH ignored; the checkout's root first on sys.path."""
    assert PLAIN_FLAGS == ("-I", "-S")
    code = "import sys; print('site' in sys.modules, sys.path[0], sys.flags.isolated)"
    done = subprocess.run(plain_command(code), capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["False", ROOT, "1"]
    # The probe itself sees site where it is loaded (guards the check above).
    loaded = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.split()
    assert loaded[0] == "True"
