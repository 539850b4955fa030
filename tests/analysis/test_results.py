"""``nemesys results`` writes the whole page: every section and table, images that exist and
are PNGs, links that resolve, every figure and table of the paper with its status, and the
paper's inconsistencies spelled out. The BER analysis runs at a tiny size here (its own tests
check its figures); the twin and the reconfiguration bench run in quick mode, the bench twice
for the decode spread."""

from __future__ import annotations

import argparse
import io
import re
from pathlib import Path

import pytest

from analysis import ber, results, results_paper
from analysis.ber import BerConfig
from analysis.decode_spread import reruns
from cli import main as cli
from cli.common import EXIT_OK
from tests.tiers import slow_fixture

PNG = b"\x89PNG\r\n\x1a\n"


#: A BER run of a second or two: real outputs (CSVs, PNG, report), figures too noisy to quote.
TINY = BerConfig(
    "tiny",
    2000,
    500,
    2000,
    500,
    bers=(1e-3, 1e-2),
    wrong_ts=(2,),
    wrong_bers=(1e-2,),
    burst_lengths=(16,),
)


@pytest.fixture(scope="module")
@slow_fixture  # builds the whole results page, ~5 s
def page(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    root = tmp_path_factory.mktemp("results")
    img_dir = root / "docs" / "results"
    progress = io.StringIO()
    spread = reruns(2, quick=True)
    path = results.generate(
        root / "docs" / "results.md",
        img_dir,
        quick=True,
        progress=progress,
        ber=ber.analyze_config(img_dir, TINY),
        reconfig=spread.reports[0],
        spread=spread,
    )
    assert "twin" in progress.getvalue() and "stability" in progress.getvalue()
    return path, path.read_text(encoding="utf-8")


def _slug(heading: str) -> str:
    """GitHub's anchor for a heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def test_page_has_every_section_and_table(page: tuple[Path, str]) -> None:
    _, text = page
    for ref in (
        "tab:design_comparison",
        "tab:battery_power_consumption_table",
        "fig:depth_control",
        "fig:sim_reconfig",
        "tab:reconfig_metrics",
        "fig:encoding_eval",
        "fig:stability_comparison",
    ):
        assert re.search(rf"^## \d+\. .*`{ref}`", text, re.M), ref
    assert "## 1. Every figure and table of the paper" in text
    assert re.search(r"^## \d+\. Controllability", text, re.M)
    assert "## 10. Where we differ, and the paper's own inconsistencies" in text
    # paper values beside ours
    for value in ("73.1", "30.3", "| 71 |", "| 22 |", "0.027", "13.2", "| 42 |", "| 46 |"):
        assert value in text, value
    assert text.count("\n| --- |") >= 8  # the Markdown tables
    assert "nemesys results --quick" in text and "make results" in text
    assert "quick mode" in text
    assert "medians from one run on a shared 2-core machine" in text
    assert "not reproducible" in text.lower()


def test_table_of_contents_anchors_match_headings(page: tuple[Path, str]) -> None:
    _, text = page
    anchors = {_slug(h) for h in re.findall(r"^## (.+)$", text, re.M)}
    links = re.findall(r"\]\(#([^)]+)\)", text)
    assert len(links) == 10
    assert set(links) <= anchors


def test_every_linked_image_exists_and_is_a_png(page: tuple[Path, str]) -> None:
    path, text = page
    images = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert {Path(i).name for i in images} == {
        "ber.png",
        "depth_control.png",
        "sim_reconfig.png",
        "stability_comparison.png",
    }
    for image in images:
        assert not Path(image).is_absolute()
        assert (path.parent / image).read_bytes()[:8] == PNG, image
    for link in re.findall(r"(?<!!)\[[^\]]*\]\(([^)#]+)\)", text):
        assert (path.parent / link).exists(), link


def test_inconsistencies_are_spelled_out(page: tuple[Path, str]) -> None:
    _, text = page
    section = text.split("## 10. ", 1)[1]
    assert "2.78 ms" in section and "1 ms" in section and "100 kb/s" in section
    assert "m = 7" in section and "n - k = 16" in section and "(70, 56)" in section
    assert "0.667" in section and "0.778" in section
    assert "6.84 s" in section  # 0.5 m at 73.1 mm/s
    assert "26 ms" in section and "1.62 s" in section  # normalised replan latency
    assert "Core i7" in section


def test_cli_results_passes_its_options(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    seen: dict[str, object] = {}

    def fake(out_md: Path, img_dir: Path, *, quick: bool, progress: object) -> Path:
        seen.update(out_md=out_md, img_dir=img_dir, quick=quick)
        return out_md

    monkeypatch.setattr(results, "generate", fake)
    out = io.StringIO()
    md = tmp_path / "r.md"
    argv = ["results", "--quick", "--out", str(md), "--img-dir", str(tmp_path / "i")]
    assert cli.main(argv, out) == EXIT_OK
    assert seen == {"out_md": md, "img_dir": tmp_path / "i", "quick": True}
    assert out.getvalue().strip() == str(md)
    args = cli.build_parser().parse_args(["results"])
    assert isinstance(args, argparse.Namespace) and args.out is None and not args.quick
    assert cli.build_parser().parse_args(["bench", "reconfig"]).target == "reconfig"


# --- every figure and table of the paper, with a status ------------------------------------


def _status_rows(text: str) -> dict[str, tuple[str, str]]:
    """Section 1's table: paper item -> (status, where or why not)."""
    section = _section(text, "Every figure and table of the paper")
    rows: dict[str, tuple[str, str]] = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
        if len(cells) == 4 and cells[2].startswith("**"):
            rows[cells[0].strip("`")] = (cells[2].strip("*"), cells[3])
    return rows


def _check_statuses(text: str) -> None:
    rows = _status_rows(text)
    assert set(rows) == {i.label for i in results_paper.PAPER_ITEMS}
    for label, (status, where) in rows.items():
        assert status in results_paper.STATUSES, label
        assert len(where) > 20, label  # a place or a reason, not a blank
    not_done = {label for label, (status, _) in rows.items() if status == "not reproduced"}
    assert {"fig:field_eval", "Gazebo world and sensors", "Cfg #1/#2 heave and yaw rates"} <= (
        not_done
    )
    assert "ORB-SLAM3" in rows["fig:field_eval"][1]
    assert rows["fig:stability_comparison"][0] == "reproduced"
    assert rows["controllability rank"][0] == "reproduced"


def test_page_names_every_paper_figure_and_table_with_a_status(page: tuple[Path, str]) -> None:
    _check_statuses(page[1])


def test_committed_page_names_every_paper_figure_and_table() -> None:
    committed = results.DEFAULT_MD.read_text(encoding="utf-8")
    _check_statuses(committed)
    assert "full mode" in committed


def test_item_list_is_the_papers_labels(tmp_path: Path) -> None:
    labels = [i.label for i in results_paper.PAPER_ITEMS if i.label.startswith(("fig:", "tab:"))]
    assert len(labels) == 14 == len(set(labels))
    tex = "".join(f"\\begin{{figure}}\\label{{{lab}}}\\end{{figure}}\n" for lab in labels)
    tex += "\\label{eq:bch_encoding} \\label{subsec:ecc}\n"  # not figures or tables
    assert results_paper.paper_labels(tex) == labels
    paper = tmp_path / "paper.tex"
    paper.write_text(tex, encoding="utf-8")
    assert results_paper.check_against_paper(paper) == 14
    paper.write_text(tex + "\\label{fig:new_one}\n", encoding="utf-8")
    with pytest.raises(ValueError, match="fig:new_one"):
        results_paper.check_against_paper(paper)
    assert results_paper.check_against_paper(tmp_path / "absent.tex") is None


def _section(text: str, title: str) -> str:
    """The body of the section whose heading starts with ``title`` (after its number)."""
    match = re.search(rf"^## \d+\. {re.escape(title)}.*$", text, re.M)
    assert match, title
    return text[match.end() :].split("\n## ", 1)[0]


def test_new_sections_state_their_method(page: tuple[Path, str]) -> None:
    _, text = page
    stab = _section(text, "Passive stability")
    assert "30 deg/s" in stab and "thrusters off" in stab
    assert re.search(r"\| Cfg #2 \| -2 \|.*\*\*capsizes\*\*", stab)
    assert re.search(r"\| Cfg #3 \| 6.5 \|.*\*\*rights itself\*\*", stab)
    assert re.search(r"\| Cfg #1 \| 0 \|.*\*\*neutral\*\*", stab)
    ctl = _section(text, "Controllability")
    assert "**Rank 4**" in ctl and "**Y sway, M pitch**" in ctl and "torpedo" in ctl
    tank = _section(text, "Depth control in the tank")
    assert "from 10 s after each command" in tank and "*Rise*" in tank and "*Settle*" in tank
    rec = _section(text, "Mission adaptation latency and memory")
    assert "MiB" in rec and "(MB)" not in rec
    # The memory's baseline is named: a plain interpreter, no start-up hook preloading modules.
    assert "increment over a plain interpreter" in rec and "`python -I -S`" in rec
    assert "over 2 reruns" in rec and "| min / median / max |" in rec
    assert "whole-frame efficiency 52/100 = 0.52" in text
    assert re.search(r"^\| 2 \| \(72, 56\) \|.*\| 0\.52 \|$", text, re.M)
