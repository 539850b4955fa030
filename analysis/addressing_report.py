"""``nemesys analyze addressing``: the comparison table of the ways to address a vehicle on the
shared ME link (:mod:`analysis.addressing`: the analytic figures; :mod:`analysis.addressing_mc`:
the Monte Carlo), and the design chosen from it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Final, TextIO

import numpy as np

from analysis._markdown import num, table
from analysis.addressing import (
    BERS,
    CODEC_DESIGN,
    DESIGNS,
    REQUIRED,
    REQUIRED_AT_BER,
    TODAYS_WRONG_COMMAND,
    W_EXACT,
    Design,
    Figures,
    chosen,
    design,
    figures,
)
from analysis.addressing_mc import Counts, run_codec, run_design
from analysis.ber_analytic import wilson
from analysis.ber_montecarlo import CommandTables
from codec import DEFAULT_BITRATE_BPS

#: Frames per design and error condition of the full run (a few minutes on this machine).
DEFAULT_FRAMES: Final = 1_000_000
QUICK_FRAMES: Final = 20_000
#: The bursts of the Monte Carlo (codeword bits, each flipped with probability 1/2).
BURSTS: Final = (8, 16, 24)


@dataclass(frozen=True)
class MonteCarloRow:
    """One design (``design``; ``codec``: the codec's own numpy path) under one condition."""

    design: str
    errors: str  # "independent" or "burst"
    level: float  # the BER, or the burst's length (bits)
    counts: Counts
    analytic: Figures | None  # independent errors only

    @property
    def condition(self) -> str:
        return (
            f"BER {self.level:g}" if self.errors == "independent" else f"{self.level:g}-bit burst"
        )


@dataclass(frozen=True)
class Report:
    frames: int
    seed: int
    w_exact: int
    analytic: dict[str, list[Figures]]
    monte_carlo: list[MonteCarloRow]
    chosen: str


def run(
    frames: int = DEFAULT_FRAMES,
    seed: int = 0,
    w_exact: int = W_EXACT,
    progress: Callable[[str], None] | None = None,
) -> Report:
    """Every design's analytic figures at :data:`BERS`, and ``frames`` Monte Carlo frames per
    design and condition (independent errors at :data:`BERS`, the :data:`BURSTS`); each
    condition its own seeded stream."""
    analytic = {d.key: [figures(d, ber, w_exact) for ber in BERS] for d in DESIGNS}
    commands = CommandTables()
    rows = []
    conditions = [("independent", ber) for ber in BERS] + [("burst", float(b)) for b in BURSTS]
    for index, d in enumerate((*DESIGNS, None)):
        for c, (errors, level) in enumerate(conditions):
            rng = np.random.default_rng([seed, index, c])
            if d is None:
                counts = run_codec(frames, errors, level, rng, commands)
            else:
                counts = run_design(d, frames, errors, level, rng, commands)
            key = d.key if d is not None else "codec"
            exact = analytic[CODEC_DESIGN if d is None else d.key]
            found = exact[BERS.index(level)] if errors == "independent" else None
            rows.append(MonteCarloRow(key, errors, level, counts, found))
            if progress is not None:
                progress(f"{key} {rows[-1].condition}: {counts}")
    at = BERS.index(REQUIRED_AT_BER)
    return Report(
        frames, seed, w_exact, analytic, rows, chosen({k: v[at] for k, v in analytic.items()})
    )


def _rate(count: int, frames: int) -> str:
    return f"{count:,} ({num(count / frames, 3)}, <= {num(wilson(count, frames)[1], 3)})"


def format_report(report: Report) -> str:
    """The two tables (analytic, Monte Carlo) and the choice, as Markdown."""
    required = num(REQUIRED, 2)
    lines = [
        "Addressed frames on one ME link: how often a vehicle executes a frame addressed to "
        "another (misaddressed, per frame: mean over every pair of vehicles 1-15 / worst "
        "pair), and how often the addressed vehicle loses its frame. Analytic: exact to "
        f"error weight {report.w_exact}, estimated above; BCH, CRC and address checks (the "
        "dictionary's left out: an upper bound).",
        "",
    ]
    headers = [
        "design",
        "frame bits",
        f"airtime at {DEFAULT_BITRATE_BPS / 1000:g} kb/s",
        *(f"misaddressed at {ber:g}" for ber in BERS),
        *(f"lost at {ber:g}" for ber in BERS[:3]),
    ]
    body = []
    for d in DESIGNS:
        rows = report.analytic[d.key]
        mark = " (chosen)" if d.key == report.chosen else ""
        body.append(
            [
                d.label + mark,
                str(d.frame_bits),
                f"{d.airtime_ms():.3f} ms",
                *(f"{num(r.misaddressed_mean, 2)} / {num(r.misaddressed_max, 2)}" for r in rows),
                *(num(r.lost, 3) for r in rows[:3]),
            ]
        )
    lines += [table(headers, body), ""]
    lines.append(
        f"Required: misaddressed <= {required} per frame at BER {REQUIRED_AT_BER:g} for every "
        f"pair (1e-8, and 400x below today's wrong-command rate {TODAYS_WRONG_COMMAND:g}). "
        f"Chosen: {design(report.chosen).label} (`{report.chosen}`), the one that meets it."
    )
    lines += [
        "",
        f"Monte Carlo: {report.frames:,} frames per row (seed {report.seed}); each a random "
        "valid command from a random vehicle, received with the same bit errors by another "
        "(misaddressed: after BCH, CRC and address; executed: after the dictionary's checks "
        "too) and by its own (lost). Counts (rate, Wilson 95 % upper bound); `codec`: the "
        "chosen design through the codec's numpy path (codec.batch_addressed).",
        "",
    ]
    headers = [
        "design",
        "errors",
        "misaddressed",
        "analytic",
        "executed",
        "lost",
        "analytic lost",
    ]
    body = []
    for row in report.monte_carlo:
        c = row.counts
        body.append(
            [
                row.design,
                row.condition,
                _rate(c.misaddressed, c.frames),
                num(row.analytic.misaddressed_mean, 3) if row.analytic else "-",
                _rate(c.executed, c.frames),
                num(c.lost / c.frames, 4),
                num(row.analytic.lost, 4) if row.analytic else "-",
            ]
        )
    lines += [table(headers, body), ""]
    return "\n".join(lines)


def main(
    out: TextIO,
    frames: int | None = None,
    seed: int = 0,
    quick: bool = False,
    progress: TextIO | None = None,
) -> int:
    """Run and print the comparison; 0 when the codec's design is the one chosen (it meets
    the requirement), else 1."""
    frames = frames or (QUICK_FRAMES if quick else DEFAULT_FRAMES)
    say = (lambda text: print(text, file=progress, flush=True)) if progress is not None else None
    report = run(frames, seed, W_EXACT - 1 if quick else W_EXACT, say)
    out.write(format_report(report))
    return 0 if report.chosen == CODEC_DESIGN else 1


__all__ = ["Design", "MonteCarloRow", "Report", "format_report", "main", "run"]
