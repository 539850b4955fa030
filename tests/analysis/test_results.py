"""``nemesys results`` writes the whole page: every section and table, images that exist and
are PNGs, links that resolve, and the paper's inconsistencies spelled out. The BER analysis runs
at a tiny size here (its own tests check its figures); the twin and the reconfiguration bench
run in quick mode."""

from __future__ import annotations

import argparse
import io
import re
from pathlib import Path

import pytest

from analysis import ber, results
from analysis.ber import BerConfig
from backend import cli

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
def page(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    root = tmp_path_factory.mktemp("results")
    img_dir = root / "docs" / "results"
    progress = io.StringIO()
    path = results.generate(
        root / "docs" / "results.md",
        img_dir,
        quick=True,
        progress=progress,
        ber=ber.analyze_config(img_dir, TINY),
    )
    assert "twin" in progress.getvalue() and "reconfig bench" in progress.getvalue()
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
    ):
        assert re.search(rf"^## \d\. .*`{ref}`", text, re.M), ref
    assert "## 7. Where we differ, and the paper's own inconsistencies" in text
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
    assert len(links) == 7
    assert set(links) <= anchors


def test_every_linked_image_exists_and_is_a_png(page: tuple[Path, str]) -> None:
    path, text = page
    images = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert {Path(i).name for i in images} == {"ber.png", "depth_control.png", "sim_reconfig.png"}
    for image in images:
        assert not Path(image).is_absolute()
        assert (path.parent / image).read_bytes()[:8] == PNG, image
    for link in re.findall(r"(?<!!)\[[^\]]*\]\(([^)#]+)\)", text):
        assert (path.parent / link).exists(), link


def test_inconsistencies_are_spelled_out(page: tuple[Path, str]) -> None:
    _, text = page
    section = text.split("## 7. ", 1)[1]
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
    assert cli.main(argv, out) == cli.EXIT_OK
    assert seen == {"out_md": md, "img_dir": tmp_path / "i", "quick": True}
    assert out.getvalue().strip() == str(md)
    args = cli.build_parser().parse_args(["results"])
    assert isinstance(args, argparse.Namespace) and args.out is None and not args.quick
    assert cli.build_parser().parse_args(["bench", "reconfig"]).target == "reconfig"
