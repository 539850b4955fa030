"""The results of ``nemesys analyze ber`` and how they are written out: the CSV files, the
figure (the paper's Fig. ``fig:encoding_eval`` redone, then wrong-command acceptance) and the
tables the command prints.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Final

import numpy as np

from analysis.ber_analytic import (
    PAPER_POINT,
    REAL_T,
    Efficiency,
    analytic_frame_success,
    analytic_success,
    code_length,
    wilson,
)
from analysis.ber_montecarlo import ErrorKind

if TYPE_CHECKING:
    from matplotlib.axes import Axes


@dataclass(frozen=True)
class SuccessPoint:
    """Decode success at one BER for one T.

    ``analytic`` is the paper's curve, P(at most T errors among the n codeword bits);
    ``analytic_frame`` multiplies it by P(at most 2 of the 24 sync bits wrong), the exact
    prediction for the Monte Carlo, which flips the sync bits too.
    """

    t: int
    n: int
    ber: float
    frames: int
    successes: int
    rate: float
    ci_low: float
    ci_high: float
    analytic: float
    analytic_frame: float


@dataclass(frozen=True)
class WrongAcceptance:
    """How often a frame is accepted as a different valid command.

    ``errors`` is ``"independent"`` (``level`` = BER over every frame bit) or ``"burst"``
    (``level`` = burst length in codeword bits); ``crc`` says whether the receiver checks the
    CRC-4 (without it every other check stays). ``ci_high`` is the Wilson 95 % upper bound
    (3.84 / frames when nothing was seen).
    """

    t: int
    errors: ErrorKind
    level: float
    crc: bool
    frames: int
    wrong: int
    rate: float
    ci_high: float


@dataclass(frozen=True)
class BerReport:
    points: tuple[SuccessPoint, ...]
    efficiency: tuple[Efficiency, ...]
    wrong: tuple[WrongAcceptance, ...]
    csv_path: Path
    png_path: Path
    wrong_csv_path: Path
    seconds: float


SUCCESS_COLUMNS: Final = (
    "t", "n", "ber", "frames", "successes", "rate", "ci_low", "ci_high", "analytic",
    "analytic_frame",
)  # fmt: skip
WRONG_COLUMNS: Final = ("t", "errors", "level", "crc", "frames", "wrong", "rate", "ci_high")


def _cell(value: object) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return f"{value:.9g}"
    return str(value)


def write_csv(path: Path, columns: Sequence[str], rows: Sequence[object]) -> None:
    """One line per row: its attributes named by ``columns``, under a header of them."""
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(columns)
        for row in rows:
            writer.writerow([_cell(getattr(row, col)) for col in columns])


_COLOURS: Final = {1: "tab:blue", 2: "tab:red", 3: "tab:green", 4: "tab:purple"}


def plot(
    path: Path,
    points: Sequence[SuccessPoint],
    efficiency: Sequence[Efficiency],
    wrong: Sequence[WrongAcceptance],
) -> None:
    """Success vs BER (the paper's figure, redone), then wrong-command acceptance for
    independent and for burst errors when there are any."""
    from matplotlib.figure import Figure  # no pyplot: no global state, no GUI backend

    kinds = [k for k in ("independent", "burst") if any(w.errors == k for w in wrong)]
    panels = 1 + len(kinds)
    fig = Figure(figsize=(6.2 * panels, 4.8), layout="constrained")
    axes = fig.subplots(1, panels, squeeze=False)[0]
    _success_panel(axes[0], points, efficiency)
    for axis, kind in zip(axes[1:], kinds, strict=True):
        _wrong_panel(axis, [w for w in wrong if w.errors == kind])
        if kind == "independent":
            axis.set_xscale("log")
            axis.set_xlabel("bit error rate (independent errors, every frame bit)")
            axis.set_title("Wrong command accepted (v: 95 % bound, none seen)")
        else:
            axis.set_xlabel("burst length in the codeword (bits, each flipped w.p. 1/2)")
            axis.set_title("Wrong command accepted, burst errors")
    fig.savefig(path, dpi=120)


def _success_panel(
    ax: Axes, points: Sequence[SuccessPoint], efficiency: Sequence[Efficiency]
) -> None:
    eff = {e.t: e for e in efficiency}
    bers = [p.ber for p in points]
    lo, hi = math.log10(min(bers)), math.log10(max(bers))
    if hi - lo < 0.5:  # a single BER (or a narrow range): show a decade around it
        lo, hi = (lo + hi) / 2 - 0.5, (lo + hi) / 2 + 0.5
    fine = np.logspace(lo, hi, 200)
    for t in sorted({p.t for p in points}):
        colour = _COLOURS.get(t, "black")
        mine = sorted((p for p in points if p.t == t), key=lambda p: p.ber)
        label = f"T={t}, n={mine[0].n}"
        e = eff.get(t)
        if e is not None:
            label += f" (k/n {e.code_rate:.3f}, paper eff. {e.paper_efficiency_m7:.3f})"
        ax.plot(fine, [analytic_frame_success(t, b) for b in fine], color=colour, lw=1.2)
        ax.plot(fine, [analytic_success(t, b) for b in fine], color=colour, lw=0.8, ls=":")
        err = [
            [max(0.0, p.rate - p.ci_low) for p in mine],
            [max(0.0, p.ci_high - p.rate) for p in mine],
        ]
        ax.errorbar(
            [p.ber for p in mine],
            [p.rate for p in mine],
            yerr=err,
            fmt="o",
            ms=3.5,
            color=colour,
            capsize=2,
            label=label,
        )
    ber0, rate0 = PAPER_POINT
    ax.axvline(ber0, color="grey", lw=0.6, ls="--")
    paper = f"paper / research: T=2, BER {ber0:g}: {rate0}"
    ax.plot([ber0], [rate0], marker="*", ms=12, color="gold", mec="black", ls="", label=paper)
    ax.plot([], [], color="black", lw=1.2, label="analytic, P(sync ok) x P(<= T in n)")
    ax.plot([], [], color="black", lw=0.8, ls=":", label="analytic, P(<= T in n) (paper)")
    ax.set_xscale("log")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("bit error rate")
    ax.set_ylabel("decoding success rate")
    ax.set_title("Decoding success vs BER (Monte Carlo, Wilson 95 %)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="lower left")


def _wrong_panel(ax: Axes, rows: Sequence[WrongAcceptance]) -> None:
    """Measured rates with Wilson bars; a 'v' at the 95 % upper bound where none was seen."""
    for t in sorted({w.t for w in rows}):
        colour = _COLOURS.get(t, "black")
        for crc, style in ((True, "-"), (False, "--")):
            mine = sorted((w for w in rows if w.t == t and w.crc == crc), key=lambda w: w.level)
            label = f"T={t} {'with' if crc else 'without'} CRC-4"
            seen = [w for w in mine if w.wrong]
            xs, ys = [w.level for w in seen], [w.rate for w in seen]
            ax.plot(xs, ys, color=colour, ls=style, lw=1.0, label=label)
            for w in mine:
                if not w.wrong:
                    ax.plot([w.level], [w.ci_high], marker="v", ms=6, color=colour)
                    continue
                low = wilson(w.wrong, w.frames)[0]
                ax.errorbar(
                    [w.level],
                    [w.rate],
                    yerr=[[max(0.0, w.rate - low)], [max(0.0, w.ci_high - w.rate)]],
                    fmt="o" if crc else "s",
                    ms=3.5,
                    color=colour,
                    mfc=colour if crc else "white",
                    capsize=2,
                )
    ax.set_yscale("log")
    ax.set_ylabel("wrong command accepted, per frame")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")


def _rate_ci(p: SuccessPoint) -> str:
    return f"{p.rate:.5f} [{p.ci_low:.5f}, {p.ci_high:.5f}]"


def format_report(report: BerReport) -> str:
    """The tables ``nemesys analyze ber`` prints."""
    lines: list[str] = []
    ts = sorted({p.t for p in report.points})
    bers = sorted({p.ber for p in report.points})
    by_key = {(p.t, p.ber): p for p in report.points}
    lines.append(
        "Decode success vs BER (Monte Carlo through the frame; analytic = "
        "P(sync ok) x P(<= T errors in n))"
    )
    lines.append("        " + "".join(f"  {f'T={t}, n={code_length(t)}':<19}" for t in ts))
    lines.append("BER     " + "  MC       analytic  " * len(ts))
    for ber in bers:
        cells = []
        for t in ts:
            p = by_key.get((t, ber))
            cells.append(f"  {p.rate:.6f} {p.analytic_frame:.6f}  " if p else " " * 21)
        lines.append(f"{ber:<8.0e}" + "".join(cells).rstrip())
    frames = sorted({(p.t, p.frames) for p in report.points})
    lines.append("frames per point: " + ", ".join(f"T={t} {n:,}" for t, n in frames))
    ber0, rate0 = PAPER_POINT
    p0 = by_key.get((REAL_T, ber0))
    if p0 is not None:
        lines.append(
            f"T=2 at BER {ber0:g}: {_rate_ci(p0)} (Wilson 95 %, {p0.frames:,} frames); "
            f"analytic {p0.analytic_frame:.6f} with the sync term, {p0.analytic:.6f} codeword "
            f"only (paper / research: {rate0})"
        )
    lines.append("")
    lines.append("Coding efficiency (k = 56)")
    lines.append("T   n   paper k/(k+2mT) m=8   paper's m=7   code rate k/n   frame 52/(n+28)")
    for e in report.efficiency:
        lines.append(
            f"{e.t}  {e.n:>3}   {e.paper_efficiency:18.4f}   {e.paper_efficiency_m7:11.4f}   "
            f"{e.code_rate:13.4f}   {e.frame_efficiency:14.4f}"
        )
    lines.append(
        "(the paper: k/(k+2mT) with m = 7, but n - k = 16 at T = 2; a binary BCH code over "
        "GF(2^m) has at most mT parity bits, here exactly 8T)"
    )
    if report.wrong:
        lines.append("")
        lines.append("Wrong command accepted (per frame; '<' = none seen, Wilson 95 % upper bound)")
        lines.append("T  errors        level       frames      with CRC-4            without CRC-4")
        keys = sorted({(w.t, w.errors != "independent", w.errors, w.level) for w in report.wrong})
        by_w = {(w.t, w.errors, w.level, w.crc): w for w in report.wrong}
        for t, _, kind, level in keys:
            cells = []
            for crc in (True, False):
                w = by_w[(t, kind, level, crc)]
                if w.wrong:
                    cells.append(f"{w.rate:9.2e} ({w.wrong:>6})")
                else:
                    cells.append(f"< {w.ci_high:7.1e} (     0)")
            lvl = f"{level:.0e}" if kind == "independent" else f"{level:.0f} bits"
            frames_n = by_w[(t, kind, level, True)].frames
            lines.append(f"{t}  {kind:<12}  {lvl:<9} {frames_n:>10,}      {cells[0]}    {cells[1]}")
    lines.append("")
    lines.append(f"wrote {report.csv_path}")
    lines.append(f"wrote {report.wrong_csv_path}")
    lines.append(f"wrote {report.png_path}")
    lines.append(f"{report.seconds:.1f} s")
    return "\n".join(lines) + "\n"
