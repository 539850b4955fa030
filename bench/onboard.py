"""``nemesys bench onboard``: the onboard table, per Python a vehicle runs.

Three figures, each the median of :data:`RUNS` runs, for this interpreter (the console's) and
for every vehicle-side venv that ``make test-vehicle`` built beside the checkout
(``.venv-vehicle310/``: ROS 2 Humble's Python 3.10; ``.venv-vehicle312/``: Jazzy's 3.12, a
non-editable install of ``vehicle/`` with bchlib from its test extra):

* the codeword decoder against bchlib: :meth:`codec.TableDecoder.decode_bytes` on the 9
  codeword bytes against bchlib's decode of the same bytes (7 data + 2 ECC), mean over
  random codewords with 0, 1, 2 and 3 (rejected) bit errors
  (:func:`bench._onboard.time_codeword`);
* the whole onboard decode against bchlib: 13 received bytes through
  :func:`codec.receive_frame` (the agent's call) to the checked command against bchlib's bare
  BCH decode of the codeword, mean over the retask scenarios' frames with 0, 1 and 2 errors
  (:func:`bench._onboard.time_decode`, as ``nemesys bench reconfig`` times it);
* the onboard memory increment: peak RSS of the onboard decode + replan of the retask
  scenarios (:mod:`bench._reconfig_memory`) over a plain interpreter, ``python -I -S`` with the
  checkout's root alone on ``sys.path`` (:data:`bench._timing.PLAIN_BASELINE`), bytecode
  compiled for the interpreter measured.

A run is one fresh process per interpreter for the timings (both ratios are taken within it,
bchlib being the peer on the same machine at the same moment: the machine is shared) and one
pair of fresh processes for the memory; the interpreters alternate within a run.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

from bench._onboard import TARGET_BCHLIB_RATIO, TARGET_CODEWORD_RATIO
from bench._reconfig_memory import TARGET_INCREMENT_KB, measure_memory, onboard_arguments
from bench._timing import PLAIN_BASELINE, ROOT, machine, mib, table, verdict
from bench.reconfig import retask_frames

#: Runs per interpreter; each figure is the median over them.
RUNS = 5
#: The vehicle-side venvs ``make test-vehicle`` builds (scripts/test_vehicle.sh).
VEHICLE_VENVS = (".venv-vehicle310", ".venv-vehicle312")
_PROBE = (
    f"import sys; sys.path.insert(0, {ROOT!r})\nfrom bench._onboard import probe_main\nprobe_main()"
)


def interpreters() -> list[str]:
    """This interpreter, then the vehicle-side venvs' that exist."""
    found = [sys.executable]
    for venv in VEHICLE_VENVS:
        python = Path(ROOT) / venv / "bin" / "python"
        if python.exists():
            found.append(str(python))
    return found


def probe(python: str, rounds: int, loops: int, frames: list[int]) -> dict[str, Any]:
    """One timing run in a fresh ``python`` (``-I``: its own site-packages, no PYTHONPATH)."""
    done = subprocess.run(
        [python, "-I", "-c", _PROBE, str(rounds), str(loops), *(f"{f:025x}" for f in frames)],
        capture_output=True,
        text=True,
        check=True,
    )
    result: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    if not str(result["codec"]).startswith(ROOT):
        raise RuntimeError(f"{python} timed {result['codec']}, not this checkout's codec")
    return result


@dataclass(frozen=True, slots=True)
class OnboardRow:
    """One interpreter's runs: the two ratios (``None``: no bchlib there) and the increment
    (KiB), one entry per run."""

    python: str
    version: str
    codeword: tuple[float | None, ...]
    whole: tuple[float | None, ...]
    increment_kb: tuple[int, ...]
    codeword_us: tuple[float, float] | None  # ours, bchlib: means over 0-3 errors, last run
    whole_us: tuple[float, float] | None  # ours, bchlib: means over 0-2 errors, last run

    @staticmethod
    def _median(values: tuple[float | None, ...]) -> float | None:
        known = [v for v in values if v is not None]
        return statistics.median(known) if len(known) == len(values) and known else None

    @property
    def codeword_ratio(self) -> float | None:
        return self._median(self.codeword)

    @property
    def whole_ratio(self) -> float | None:
        return self._median(self.whole)

    @property
    def increment(self) -> float:
        return statistics.median(self.increment_kb)


def measure(quick: bool = False, runs: int | None = None) -> list[OnboardRow]:
    """Every interpreter's row, the interpreters alternating within each run."""
    runs = runs or (2 if quick else RUNS)
    rounds, loops = (5, 2) if quick else (31, 20)
    frames = retask_frames()
    args = onboard_arguments()
    pythons = interpreters()
    samples: dict[str, list[tuple[dict[str, Any], int]]] = {p: [] for p in pythons}
    for _ in range(runs):
        for python in pythons:
            timing = probe(python, rounds, loops, frames)
            bare, peak, _ = measure_memory(1, python, args)
            samples[python].append((timing, peak - bare))
    rows = []
    for python, got in sorted(samples.items(), key=lambda item: _version_key(item[1])):
        last = got[-1][0]

        def means(ours: str, peer: str, last: dict[str, Any] = last) -> tuple[float, float] | None:
            if last[peer] is None:
                return None
            return statistics.fmean(last[ours]), statistics.fmean(last[peer])

        rows.append(
            OnboardRow(
                python=python,
                version=str(last["python"]),
                codeword=tuple(t["codeword_ratio"] for t, _ in got),
                whole=tuple(t["whole_ratio"] for t, _ in got),
                increment_kb=tuple(kb for _, kb in got),
                codeword_us=means("codeword_us", "codeword_bchlib_us"),
                whole_us=means("receiver_us", "bchlib_us"),
            )
        )
    return rows


def _version_key(got: list[tuple[dict[str, Any], int]]) -> tuple[int, ...]:
    return tuple(int(part) for part in str(got[-1][0]["python"]).split(".")[:2])


def _ratio_cell(value: float | None, target: float) -> str:
    if value is None:
        return "n/a (no bchlib)"
    return f"{value:.2f}x ({verdict(value <= target)})"


def _spread(values: tuple[float | None, ...], fmt: str) -> str:
    known = [v for v in values if v is not None]
    return "-" if not known else f"{format(min(known), fmt)}-{format(max(known), fmt)}"


def format_table(rows: list[OnboardRow]) -> str:
    """The onboard table and how it was measured."""
    runs = len(rows[0].increment_kb) if rows else 0
    body = [
        [
            r.version,
            _ratio_cell(r.codeword_ratio, TARGET_CODEWORD_RATIO),
            _ratio_cell(r.whole_ratio, TARGET_BCHLIB_RATIO),
            f"{mib(r.increment)} ({verdict(r.increment <= TARGET_INCREMENT_KB)})",
        ]
        for r in rows
    ]
    detail = [
        [
            r.version,
            _spread(r.codeword, ".2f"),
            "-" if r.codeword_us is None else "{:.2f} / {:.2f}".format(*r.codeword_us),
            _spread(r.whole, ".2f"),
            "-" if r.whole_us is None else "{:.2f} / {:.2f}".format(*r.whole_us),
            _spread(tuple(kb / 1024 for kb in r.increment_kb), ".2f"),
            r.python,
        ]
        for r in rows
    ]
    versions = {r.version[:4] for r in rows}
    missing = [
        f"Python {v}: not measured (no {venv}/: `make test-vehicle` builds it)."
        for v, venv in (("3.10", ".venv-vehicle310"),)
        if v not in versions
    ]
    return "\n".join(
        [
            f"Onboard speed and memory, per Python; medians of {runs} runs (each run: fresh "
            "processes; both ratios taken within one process against bchlib, the peer).",
            "",
            table(
                [
                    "python",
                    f"codeword decode / bchlib (<= {TARGET_CODEWORD_RATIO:g}x)",
                    f"whole decode / bchlib (<= {TARGET_BCHLIB_RATIO:g}x)",
                    f"memory increment (<= {mib(TARGET_INCREMENT_KB)})",
                ],
                body,
            ),
            "",
            "Per run (min-max over the runs), and the last run's mean us (ours / bchlib):",
            "",
            table(
                [
                    "python",
                    "codeword ratio",
                    "codeword us",
                    "whole ratio",
                    "whole us",
                    "increment MiB",
                    "interpreter",
                ],
                detail,
            ),
            "",
            "Codeword: TableDecoder.decode_bytes on 9 bytes vs bchlib.BCH(2, m=8) decode (+ "
            "correct) of the same 7 + 2 bytes, 256 random codewords per error count, mean over "
            "0-3 errors (3: rejected). Whole: 13 bytes -> receive_frame -> checked command vs "
            "bchlib's decode of the codeword, the retask scenarios' frames, mean over 0-2 errors.",
            "Memory increment: peak RSS (VmHWM) of the onboard decode + replan of the retask "
            f"scenarios over that of the baseline, {PLAIN_BASELINE}; both with the checkout's "
            "root alone on sys.path and the vehicle packages' bytecode compiled for that "
            "interpreter.",
            *missing,
            f"Machine: {machine()}.",
        ]
    )


def run(out: TextIO, quick: bool = False) -> int:
    out.write(format_table(measure(quick)) + "\n")
    return 0
