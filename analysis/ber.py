"""Decode success and wrong-command acceptance against bit error rate (``nemesys analyze ber``).

Redoes the paper's Fig. ``fig:encoding_eval`` (decoding success rate against BER for
T = 1..4, and the coding efficiency that motivates T = 2) by Monte Carlo through the real frame
and decoder, with Wilson 95 % intervals, against the analytic curve; and measures how often a
frame is accepted as a *different* valid command, with and without the CRC-4, for independent
and for burst errors.

Frames and decoders:

* **T = 2 is the real frame**: :mod:`codec.batch` encodes, injects the bit errors into and
  decodes ``(N, 13)`` packed frames with exactly the checks of :func:`codec.decode_frame`
  (sync word within :data:`codec.DEFAULT_SYNC_TOLERANCE` bits, BCH(72, 56) syndrome-table
  decoder, CRC-4, pattern ID, field codes, unused fields zero).
* **T = 1, 3, 4** use the same layout with that code's parity: sync word (24) + the
  ``n = 56 + 8T`` bit codeword of ``BCHCode(T)`` over GF(2^8) + 4 guard bits, the same
  message (pattern ID, six fields, CRC-4) and the same checks in the same order. They are
  decoded by :class:`BitFrames`, a numpy transcription of :meth:`codec.BCHCode.decode`
  (syndromes, Berlekamp-Massey, Chien search over the shortened length, the same acceptance
  rule); the tests check it against the scalar decoder word by word, and at T = 2 against
  :mod:`codec.batch` frame by frame.

Every frame carries a random valid command (uniform pattern, uniform valid code per used
field), seeded. Independent errors flip every transmitted bit (sync, codeword and guard) with
probability ``ber``; a burst of ``L`` bits is a window of ``L`` consecutive codeword bits at a
uniform position in which every bit flips with probability 1/2.

Success means the frame is accepted and carries the command that was sent. With bounded
distance decoding that happens exactly when the sync word has at most 2 wrong bits and the
codeword at most T, so the exact prediction is ``P(sync ok) * P(<= T errors in n bits)``
(:func:`analytic_frame_success`). The paper's curve (and the research note's 0.964 at BER

The parts: :mod:`analysis.ber_analytic` (code sizes, the analytic curves, Wilson intervals,
the efficiency table), :mod:`analysis.ber_frames` (the frame of any T and its numpy decoder),
:mod:`analysis.ber_montecarlo` (random commands, error injection, the counting runs) and
:mod:`analysis.ber_report` (the results, the CSV files, the figure and the printed tables).
This module sizes and runs the analysis; every name of the parts is importable from here.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Final, TextIO

import numpy as np

from analysis.ber_analytic import (
    BERS,
    M_FIELD,
    PAPER_M,
    PAPER_POINT,
    REAL_T,
    TS,
    Z95,
    Efficiency,
    K,
    analytic_frame_success,
    analytic_success,
    analytic_sync,
    code_length,
    efficiency_table,
    frame_bits,
    wilson,
)
from analysis.ber_frames import U8, U64, BitFrames, Bool, Decision
from analysis.ber_montecarlo import (
    CHUNK_OTHER,
    CHUNK_REAL,
    CommandTables,
    Counts,
    ErrorKind,
    Simulator,
    inject_burst,
    inject_independent,
)
from analysis.ber_report import (
    SUCCESS_COLUMNS,
    WRONG_COLUMNS,
    BerReport,
    SuccessPoint,
    WrongAcceptance,
    format_report,
    plot,
    write_csv,
)

__all__ = [
    "BERS",
    "CHUNK_OTHER",
    "CHUNK_REAL",
    "DEFAULT_OUT_DIR",
    "FULL",
    "M_FIELD",
    "PAPER_M",
    "PAPER_POINT",
    "QUICK",
    "REAL_T",
    "SUCCESS_COLUMNS",
    "TEST",
    "TS",
    "U8",
    "U64",
    "WRONG_COLUMNS",
    "Z95",
    "BerConfig",
    "BerReport",
    "BitFrames",
    "Bool",
    "CommandTables",
    "Counts",
    "Decision",
    "Efficiency",
    "ErrorKind",
    "K",
    "ProgressBar",
    "Simulator",
    "SuccessPoint",
    "WrongAcceptance",
    "analytic_frame_success",
    "analytic_success",
    "analytic_sync",
    "analyze",
    "analyze_config",
    "code_length",
    "efficiency_table",
    "format_report",
    "frame_bits",
    "inject_burst",
    "inject_independent",
    "plot",
    "wilson",
    "write_csv",
]

#: Where ``nemesys analyze ber`` writes by default (the results page's image directory).
DEFAULT_OUT_DIR: Final = Path(__file__).resolve().parents[1] / "docs" / "results"


# --- run sizes ----------------------------------------------------------------------------


@dataclass(frozen=True)
class BerConfig:
    """What to simulate, and how many frames.

    T = 2 goes through :mod:`codec.batch` (about 1 s per 10^6 frames); the other codes through
    the numpy Berlekamp-Massey decoder, several times slower, so they get fewer frames.
    """

    name: str
    success_frames_real: int
    success_frames_other: int
    wrong_frames_real: int
    wrong_frames_other: int
    ts: tuple[int, ...] = TS
    bers: tuple[float, ...] = BERS
    wrong_ts: tuple[int, ...] = TS
    wrong_bers: tuple[float, ...] = (3e-3, 1e-2, 3e-2, 1e-1)
    burst_lengths: tuple[int, ...] = (8, 16, 24)

    def success_frames(self, t: int) -> int:
        return self.success_frames_real if t == REAL_T else self.success_frames_other

    def wrong_frames(self, t: int) -> int:
        return self.wrong_frames_real if t == REAL_T else self.wrong_frames_other


FULL: Final = BerConfig("full", 2_000_000, 1_000_000, 20_000_000, 2_000_000)
QUICK: Final = BerConfig("quick", 200_000, 30_000, 2_000_000, 100_000)
#: For the test suite: a few seconds, still 50 000 T = 2 frames per BER (sd 0.0008 at 0.964).
TEST: Final = BerConfig(
    "test", 50_000, 10_000, 200_000, 10_000, wrong_bers=(1e-2, 1e-1), burst_lengths=(8, 24)
)


# --- progress ---------------------------------------------------------------------------------


@dataclass
class ProgressBar:
    """``\\r[#########...........] 45 %  12 s  T=3 BER 2e-02`` on a text stream."""

    stream: TextIO | None
    total: float
    width: int = 30
    done: float = 0.0
    label: str = ""
    _shown: int = -1
    _drawn: float = -math.inf
    _start: float = field(default_factory=time.perf_counter)

    def advance(self, amount: float) -> None:
        self.done += amount
        self._draw()

    def advancer(self, weight: float) -> Callable[[int], None]:
        """``advance(weight * frames)`` as a callback taking the frames done."""

        def advance(frames: int) -> None:
            self.advance(weight * frames)

        return advance

    def describe(self, label: str) -> None:
        self.label = label
        self._draw(force=True)

    def _draw(self, force: bool = False) -> None:
        if self.stream is None:
            return
        pct = min(100, int(100 * self.done / self.total)) if self.total > 0 else 100
        now = time.perf_counter()
        if pct == self._shown and not (force and now - self._drawn >= 0.25):
            return
        self._shown = pct
        self._drawn = now
        filled = self.width * pct // 100
        bar = "#" * filled + "." * (self.width - filled)
        elapsed = now - self._start
        self.stream.write(f"\r[{bar}] {pct:3d} %  {elapsed:4.0f} s  {self.label:<28}")
        self.stream.flush()

    def close(self) -> None:
        if self.stream is None:
            return
        self.done = self.total
        self.label = "done"
        self._drawn = -math.inf
        self._draw(force=True)
        self.stream.write("\n")
        self.stream.flush()


# --- the run ----------------------------------------------------------------------------------


#: Rough time per frame against T = 2 (codec.batch), for the progress bar only.
_COST: Final = {1: 1.5, 2: 1.0, 3: 3.5, 4: 5.0}


def _seed(seed: int, *key: int) -> np.random.Generator:
    return np.random.default_rng([seed, *key])


def analyze_config(
    out_dir: Path,
    config: BerConfig,
    *,
    seed: int = 0,
    progress: TextIO | None = None,
) -> BerReport:
    """:func:`analyze` with explicit run sizes (the test suite uses :data:`TEST`)."""
    start = time.perf_counter()
    commands = CommandTables()
    sims = {t: Simulator(t, commands) for t in sorted({*config.ts, *config.wrong_ts})}

    def cost(t: int) -> float:
        return _COST.get(t, 6.0)

    wrong_levels: list[tuple[ErrorKind, float]] = [("independent", b) for b in config.wrong_bers]
    wrong_levels += [("burst", float(length)) for length in config.burst_lengths]
    total = sum(cost(t) * config.success_frames(t) * len(config.bers) for t in config.ts)
    total += sum(cost(t) * config.wrong_frames(t) * len(wrong_levels) for t in config.wrong_ts)
    bar = ProgressBar(progress, total)

    points: list[SuccessPoint] = []
    for t in config.ts:
        sim = sims[t]
        for i, ber in enumerate(config.bers):
            bar.describe(f"T={t} BER {ber:.0e}")
            c = sim.run(
                config.success_frames(t),
                "independent",
                ber,
                _seed(seed, 1, t, i),
                bar.advancer(cost(t)),
            )
            low, high = wilson(c.success, c.frames)
            points.append(
                SuccessPoint(
                    t=t,
                    n=sim.n,
                    ber=ber,
                    frames=c.frames,
                    successes=c.success,
                    rate=c.success / c.frames,
                    ci_low=low,
                    ci_high=high,
                    analytic=analytic_success(t, ber),
                    analytic_frame=analytic_frame_success(t, ber),
                )
            )

    wrong: list[WrongAcceptance] = []
    for t in config.wrong_ts:
        sim = sims[t]
        for i, (kind, level) in enumerate(wrong_levels):
            what = f"BER {level:.0e}" if kind == "independent" else f"burst {level:.0f}"
            bar.describe(f"T={t} wrong, {what}")
            c = sim.run(
                config.wrong_frames(t),
                kind,
                level,
                _seed(seed, 2, t, i),
                bar.advancer(cost(t)),
            )
            for crc, count in ((True, c.wrong_crc), (False, c.wrong_nocrc)):
                wrong.append(
                    WrongAcceptance(
                        t=t,
                        errors=kind,
                        level=level,
                        crc=crc,
                        frames=c.frames,
                        wrong=count,
                        rate=count / c.frames,
                        ci_high=wilson(count, c.frames)[1],
                    )
                )
    bar.close()

    out_dir.mkdir(parents=True, exist_ok=True)
    csv_path = out_dir / "ber.csv"
    wrong_csv_path = out_dir / "ber_wrong.csv"
    png_path = out_dir / "ber.png"
    efficiency = efficiency_table(config.ts)
    write_csv(csv_path, SUCCESS_COLUMNS, points)
    write_csv(wrong_csv_path, WRONG_COLUMNS, wrong)
    plot(png_path, points, efficiency, wrong)
    return BerReport(
        points=tuple(points),
        efficiency=efficiency,
        wrong=tuple(wrong),
        csv_path=csv_path,
        png_path=png_path,
        wrong_csv_path=wrong_csv_path,
        seconds=time.perf_counter() - start,
    )


def analyze(
    out_dir: Path, *, quick: bool = False, seed: int = 0, progress: TextIO | None = None
) -> BerReport:
    """Run the BER analysis, write ``ber.csv``, ``ber_wrong.csv`` and ``ber.png`` into
    ``out_dir`` and return the figures. ``quick``: about 10x fewer frames (under a minute)."""
    return analyze_config(out_dir, QUICK if quick else FULL, seed=seed, progress=progress)
