"""Timing helpers shared by the benchmarks: interleaved rounds, medians, tables, peak RSS."""

from __future__ import annotations

import math
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any


def per_call_us(func: Callable[[Any], object], inputs: Sequence[Any], loops: int) -> float:
    """Mean microseconds per call of ``func`` over ``loops`` passes through ``inputs``."""
    start = time.perf_counter_ns()
    for _ in range(loops):
        for x in inputs:
            func(x)
    elapsed = time.perf_counter_ns() - start
    return elapsed / 1e3 / (loops * len(inputs))


def interleaved_medians(
    cases: Mapping[str, tuple[Callable[[Any], object], Sequence[Any], int]], rounds: int
) -> dict[str, float]:
    """Median per-call microseconds of every case, measuring all cases once per round.

    Interleaving rounds spreads a noisy neighbour's bursts over every case alike, so
    ratios taken within one run stay meaningful on a shared machine.
    """
    samples: dict[str, list[float]] = {name: [] for name in cases}
    for _ in range(rounds):
        for name, (func, inputs, loops) in cases.items():
            samples[name].append(per_call_us(func, inputs, loops))
    return {name: statistics.median(values) for name, values in samples.items()}


def percentile(values: Sequence[float], q: float) -> float:
    """The ``q``-th percentile (0-100), linear between the closest ranks."""
    if not values:
        return float("nan")
    ordered = sorted(values)
    pos = (len(ordered) - 1) * q / 100.0
    lo = int(pos)
    hi = min(lo + 1, len(ordered) - 1)
    return ordered[lo] + (ordered[hi] - ordered[lo]) * (pos - lo)


def ms_cell(value: float) -> str:
    """A table cell of milliseconds, one decimal; ``-`` for NaN (no sample)."""
    return "-" if math.isnan(value) else f"{value:.1f}"


def table(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """A plain-text table with columns padded to width."""
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(headers)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(headers, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
    return "\n".join(lines)


def verdict(ok: bool) -> str:
    """A target's verdict cell: ``met`` or ``MISSED``."""
    return "met" if ok else "MISSED"


#: How the memory benches start a process, the onboard one and its baseline alike: a plain
#: interpreter. ``-I`` ignores the environment (PYTHONPATH, the user site) and ``-S`` skips
#: ``site``, so no ``.pth`` start-up hook runs (the console's editable install has one, which
#: preloads dozens of modules into any ``python -c`` of its venv and hides their cost) and no
#: site-packages are on the path; the process then puts the checkout's root alone on
#: ``sys.path``, which holds the vehicle's packages.
PLAIN_FLAGS = ("-I", "-S")
#: The checkout's root (the vehicle's packages are folders in it).
ROOT = str(Path(__file__).resolve().parent.parent)
#: The baseline, named as the benches print it.
PLAIN_BASELINE = "a plain interpreter (python -I -S: no site, no .pth start-up hooks)"


def plain_command(code: str, python: str | None = None) -> list[str]:
    """``python -I -S -c code``, the code run with the checkout's root on ``sys.path``."""
    path = f"import sys; sys.path.insert(0, {ROOT!r})\n"
    return [python or sys.executable, *PLAIN_FLAGS, "-c", path + code]


def peak_rss_run(
    code: str, args: Sequence[str], python: str | None = None
) -> tuple[int, list[str]]:
    """Peak RSS (KiB, as the kernel's ``VmHWM`` counts it) of one fresh plain interpreter
    (:func:`plain_command`) running ``code args...``, which prints its own peak on its last
    line; and the lines it printed before that."""
    done = subprocess.run(
        [*plain_command(code, python), *args], capture_output=True, text=True, check=True
    )
    lines = done.stdout.strip().splitlines()
    return int(lines[-1]), lines[:-1]


def peak_rss_kb(code: str, args: Sequence[str], runs: int) -> int:
    """Median peak RSS (KiB) of ``runs`` fresh plain interpreters running ``code args...``;
    the code prints its own peak (``VmHWM``) on its last line of output."""
    return int(statistics.median(peak_rss_run(code, args)[0] for _ in range(runs)))


def compile_packages(names: Sequence[str], python: str | None = None) -> None:
    """Write the bytecode of the checkout's packages ``names`` for ``python`` (default this
    one), as installing them does: compiling source costs a fresh process more than a
    megabyte of peak RSS that an installed vehicle never pays."""
    dirs = [str(Path(ROOT) / name) for name in names]
    subprocess.run(
        [python or sys.executable, *PLAIN_FLAGS, "-m", "compileall", "-q", *dirs],
        check=True,
        capture_output=True,
    )


def mib(kib: float) -> str:
    """KiB (the kernel's "kB") as MiB, unit named: ``1.23 MiB``."""
    return f"{kib / 1024:.2f} MiB"


def machine() -> str:
    """CPU model, core count and Python of this machine, in one line."""
    model = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            model = next(
                (ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")), model
            )
    except OSError:
        pass
    return (
        f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.release()}, "
        f"CPython {platform.python_version()}"
    )
