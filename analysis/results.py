"""``nemesys results``: regenerate ``docs/results.md``, the paper's tables and figures beside ours.

:func:`generate` runs every reproduction and writes one Markdown page plus its images:

* the encoding evaluation (Fig. ``fig:encoding_eval``): :func:`analysis.ber.analyze`, which
  writes its own PNG and CSVs into the image directory;
* the mission adaptation table (Table ``tab:reconfig_metrics``): :func:`bench.reconfig.measure`,
  rerun :data:`analysis.decode_spread.RERUNS` times for the decode figure's spread;
* the twin's vehicle figures (Tables ``tab:design_comparison`` and
  ``tab:battery_power_consumption_table``, Figs. ``fig:depth_control`` and
  ``fig:sim_reconfig``): :func:`analysis.twin.reproduce`, with the tank steps measured by
  :mod:`analysis.tank`;
* the passive-stability comparison (Fig. ``fig:stability_comparison``):
  :mod:`analysis.stability`; the controllability rank: :mod:`analysis.controllability`;
* every figure and table of the paper with its status, and the differences:
  :mod:`analysis.results_paper`.

The sections are written by :mod:`analysis.results_vehicle`, :mod:`analysis.results_onboard`
and :mod:`analysis.results_paper`; this module numbers them and writes the page. Each
expensive part can be passed in already computed (``ber=``, ``reconfig=``, ``twin_report=``,
``spread=``), so tests and callers that hold one need not rerun it. ``quick`` asks each part
for its smoke-run size (fewer frames, rounds and processes); the page says which mode made it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import TextIO, TypeVar

import numpy as np

from analysis import results_onboard, results_paper, results_vehicle
from analysis._markdown import slug
from analysis.ber import BerReport, analyze
from analysis.controllability import analyse, model_matrix
from analysis.decode_spread import RERUNS, DecodeSpread, reruns
from analysis.stability import compare, plot_stability, push_impulse_nms, roll_mode
from analysis.tank import tank_result_steps
from analysis.twin import PAPER_DESIGNS, TwinReport, reproduce
from bench.reconfig import ReconfigReport, measure

DOCS = Path(__file__).resolve().parents[1] / "docs"
DEFAULT_MD = DOCS / "results.md"
DEFAULT_IMG_DIR = DOCS / "results"
STABILITY_PNG = "stability_comparison.png"

_T = TypeVar("_T")
Section = tuple[str, list[str]]


@dataclass(frozen=True, slots=True)
class RunInfo:
    """How this copy of the page was made."""

    quick: bool
    command: str
    seconds: dict[str, float]
    started: datetime
    machine: str
    paper_labels: int | None  # labels checked against the paper's source, None if absent


def _header(info: RunInfo, titles: list[str]) -> list[str]:
    parts = ", ".join(f"{k} {v:.1f} s" for k, v in info.seconds.items())
    mode = (
        "quick mode (smoke-run sizes: fewer frames, rounds and processes)"
        if info.quick
        else "full mode"
    )
    checked = (
        f"The list of the paper's figures and tables was checked against its LaTeX source "
        f"({info.paper_labels} labels)."
        if info.paper_labels is not None
        else "The paper's LaTeX source was not at hand to recheck the list of its labels."
    )
    toc = [f"{k}. [{title}](#{slug(f'{k}. {title}')})" for k, title in enumerate(titles, 1)]
    return [
        "# Reproducing the paper's results",
        "",
        "The NemeSys paper's tables and figures beside what this repository measures: the "
        "codec's error correction, the onboard decode-and-replan path, and the simulated "
        "vehicle (the twin). Section 1 lists every figure and table of the paper with its "
        "status here; each later section says how its figure was measured and where and why "
        "we differ; the last collects the differences, including the paper's own "
        "inconsistencies.",
        "",
        f"Regenerate the whole page and its images with `{info.command}` (or `make results`). "
        f"This copy: {mode}, {info.started:%Y-%m-%d %H:%M} UTC, on {info.machine}; {parts}. "
        "Timings vary from run to run: they are medians from one run on a shared 2-core "
        f"machine, and the decode figure's spread over reruns is stated. {checked}",
        "",
        *toc,
        "",
    ]


@dataclass(frozen=True, slots=True)
class Parts:
    """Everything the page shows, computed."""

    ber: BerReport
    reconfig: ReconfigReport
    spread: DecodeSpread
    twin: TwinReport
    stability_png: Path


def sections(parts: Parts, base: Path) -> list[Section]:
    """The page's sections in order, untitled by number."""
    twin = parts.twin
    runs = compare()
    modes = [roll_mode(gm) for gm, _, _ in PAPER_DESIGNS.values()]
    c = analyse()
    return [
        results_paper.items_section(),
        results_vehicle.design(twin),
        results_vehicle.stability(runs, modes, push_impulse_nms(), parts.stability_png, base),
        results_vehicle.controllability(c, float(np.abs(model_matrix() - c.matrix).max())),
        results_vehicle.battery(twin),
        results_vehicle.tank(twin, tank_result_steps(twin.tank), base),
        results_vehicle.scenarios(twin, base),
        results_onboard.reconfig(parts.reconfig, parts.spread),
        results_onboard.encoding(parts.ber, base),
        results_paper.differences(parts.reconfig, twin),
    ]


def render(parts: Parts, base: Path, info: RunInfo) -> str:
    """The page, with image and data links relative to ``base`` (the page's directory)."""
    secs = sections(parts, base)
    lines = _header(info, [title for title, _ in secs])
    for k, (title, body) in enumerate(secs, 1):
        lines += [f"## {k}. {title}", "", *body, ""]
    return "\n".join(lines).rstrip("\n") + "\n"


def generate(
    out_md: Path = DEFAULT_MD,
    img_dir: Path = DEFAULT_IMG_DIR,
    *,
    quick: bool = False,
    progress: TextIO | None = None,
    seed: int = 0,
    ber: BerReport | None = None,
    reconfig: ReconfigReport | None = None,
    twin_report: TwinReport | None = None,
    spread: DecodeSpread | None = None,
    command: str | None = None,
) -> Path:
    """Run every reproduction (or use the parts given) and write the page; returns its path."""
    started = datetime.now(UTC)
    paper_labels = results_paper.check_against_paper()
    img_dir.mkdir(parents=True, exist_ok=True)
    out_md.parent.mkdir(parents=True, exist_ok=True)
    seconds: dict[str, float] = {}

    def say(text: str) -> None:
        if progress is not None:
            progress.write(f"results: {text}\n")
            progress.flush()

    def timed(label: str, given: _T | None, run: Callable[[], _T]) -> _T:
        if given is not None:
            return given
        say(f"{label} ...")
        t0 = time.perf_counter()
        value = run()
        seconds[label] = time.perf_counter() - t0
        say(f"{label} done in {seconds[label]:.1f} s")
        return value

    ber_report = timed(
        "BER analysis", ber, lambda: analyze(img_dir, quick=quick, seed=seed, progress=progress)
    )
    twin = timed("twin", twin_report, lambda: reproduce(img_dir, seed=seed, progress=progress))
    stab_png = timed("stability", None, lambda: plot_stability(compare(), img_dir / STABILITY_PNG))
    rec = timed("reconfig bench", reconfig, lambda: measure(quick))
    spr = timed(
        f"reconfig bench reruns (x{RERUNS - 1})",
        spread,
        lambda: reruns(RERUNS, quick=quick, first=rec),
    )
    info = RunInfo(
        quick=quick,
        command=command or ("nemesys results --quick" if quick else "nemesys results"),
        seconds=seconds or {"all parts given": 0.0},
        started=started,
        machine=rec.machine,
        paper_labels=paper_labels,
    )
    text = render(Parts(ber_report, rec, spr, twin, stab_png), out_md.parent, info)
    out_md.write_text(text, encoding="utf-8")
    say(f"wrote {out_md}")
    return out_md


__all__ = ["DEFAULT_IMG_DIR", "DEFAULT_MD", "Parts", "RunInfo", "generate", "render", "sections"]
