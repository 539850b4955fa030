"""docs/patterns.md and its figures stay true.

The figures are redrawn with ``scripts/gen_pattern_figures.py`` and compared byte for byte with
the committed ``docs/patterns/*.svg``; every pattern of the dictionary must have a section, a
parameter table listing exactly its fields and a picture; the constants the document quotes
must be the planner's; the ``pycon`` session is run through doctest. When the planner changes,
run ``.venv/bin/python scripts/gen_pattern_figures.py``, look at the figures, and commit them.
"""

from __future__ import annotations

import doctest
import importlib.util
import math
import re
import sys
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import pytest

import planner
from codec import DICTIONARY
from planner._geometry import step_angle

ROOT = Path(__file__).parents[2]
DOC = ROOT / "docs" / "patterns.md"
FIGURES = ROOT / "docs" / "patterns"
SCRIPT = ROOT / "scripts" / "gen_pattern_figures.py"
SVG_NS = "{http://www.w3.org/2000/svg}"

#: Constants the document's table must quote, with the planner's value (MAX_STEP_RAD in deg).
CONSTANTS: dict[str, float] = {
    "CHORD_TOL_M": planner.CHORD_TOL_M,
    "MAX_STEP_RAD": math.degrees(planner.MAX_STEP_RAD),
    "DEPTH_RATE_MPS": planner.DEPTH_RATE_MPS,
    "HEAVE_CAPABILITY_MPS": planner.HEAVE_CAPABILITY_MPS,
    "YAW_RATE_DPS": planner.YAW_RATE_DPS,
    "MIN_TURN_RADIUS_M": planner.MIN_TURN_RADIUS_M,
    "LEAD_TURN_RADII": planner.LEAD_TURN_RADII,
    "HOVER_APPROACH_MPS": planner.HOVER_APPROACH_MPS,
    "MAX_WAYPOINTS": planner.MAX_WAYPOINTS,
}


#: Coordinate attributes of the SVG elements the script writes, as ``x, y`` pairs.
COORDINATES = {"line": ("x1", "y1", "x2", "y2"), "circle": ("cx", "cy"), "text": ("x", "y")}


@pytest.fixture(scope="module")
def doc() -> str:
    return DOC.read_text(encoding="utf-8")


def _generator(monkeypatch: pytest.MonkeyPatch) -> Callable[[Path | None], list[Path]]:
    """``main`` of the figure script (``scripts/`` is not a package), loaded as Python runs a
    script: its folder first on the path, where its drawing modules are."""
    monkeypatch.syspath_prepend(str(SCRIPT.parent))
    spec = importlib.util.spec_from_file_location("gen_pattern_figures", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    main: Callable[[Path | None], list[Path]] = module.main
    return main


def _sections(doc: str) -> dict[str, str]:
    """``### heading`` -> the text up to the next heading."""
    parts = re.split(r"^(#{2,3} .*)$", doc, flags=re.MULTILINE)
    return {parts[i].lstrip("#").strip(): parts[i + 1] for i in range(1, len(parts) - 1, 2)}


def test_figures_are_current(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    written = _generator(monkeypatch)(tmp_path)
    names = sorted(p.name for p in written)
    assert names == sorted(p.name for p in tmp_path.iterdir())
    committed = sorted(p.name for p in FIGURES.glob("*.svg"))
    assert names == committed, "run scripts/gen_pattern_figures.py (new or stale figures)"
    stale = [n for n in names if (tmp_path / n).read_bytes() != (FIGURES / n).read_bytes()]
    assert not stale, f"figures differ from the planner's output, regenerate: {stale}"


def test_figures_are_deterministic(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    main = _generator(monkeypatch)
    first, second = tmp_path / "1", tmp_path / "2"
    for a, b in zip(main(first), main(second), strict=True):
        assert a.read_bytes() == b.read_bytes(), a.name


def test_every_pattern_has_a_section_and_picture(doc: str) -> None:
    sections = _sections(doc)
    for pattern in DICTIONARY.values():
        heading = f"{pattern.label} (ID {pattern.id})"
        assert heading in sections, f"no section '### {heading}'"
        body = sections[heading]
        link = f"![{pattern.name}](patterns/{pattern.name}.svg)"
        assert link in body, f"{heading}: no picture link {link}"
        assert (FIGURES / f"{pattern.name}.svg").is_file()
        fields = re.findall(r"^\| `(\w+)` \|", body, flags=re.MULTILINE)
        assert fields == [f.name for f in pattern.fields], f"{heading}: parameter table"
        for what in ("**Anchored to**", "**Starts**"):
            assert what in body, f"{heading}: says nothing under {what}"


def test_every_picture_link_resolves(doc: str) -> None:
    links = re.findall(r"!\[[^\]]*\]\((patterns/[^)]+)\)", doc)
    assert {f"patterns/scenario_{k}.svg" for k in "abc"} <= set(links)
    missing = [link for link in links if not (DOC.parent / link).is_file()]
    assert not missing


def test_constants_match_the_planner(doc: str) -> None:
    rows = dict(re.findall(r"^\| `([A-Z_]+)` \| ([0-9.]+)\b", doc, flags=re.MULTILINE))
    assert set(CONSTANTS) <= set(rows), f"constants table lacks {set(CONSTANTS) - set(rows)}"
    for name, value in rows.items():
        expected = CONSTANTS.get(name, getattr(planner, name))
        assert float(value) == pytest.approx(expected, rel=1e-12), name


def test_derived_figures_match_the_planner(doc: str) -> None:
    speed = planner.MIN_TURN_RADIUS_M * math.radians(planner.YAW_RATE_DPS)
    chords = [math.ceil(2 * math.pi / step_angle(r) - 1e-9) for r in (5.0, 0.5, 100.0)]
    expected = [
        f"This is {planner.turn_radius_m(0.5):.2f} m at 0.5 m/s",
        f"Below {speed:.2f} m/s",
        f"{math.radians(planner.YAW_RATE_DPS):.3f} rad/s",
        f"A 5 m circle is therefore {chords[0]} chords and a 0.5 m one is {chords[1]}",
        f"{planner.HEAVE_CAPABILITY_MPS * 1000:.1f} mm/s",
        f"From 2 m this takes {2 / planner.HEAVE_CAPABILITY_MPS:.1f} s",
        f"{chords[2]} chords per turn, so {f'{255 * chords[2]:,}'.replace(',', ' ')} waypoints",
    ]
    missing = [text for text in expected if text not in " ".join(doc.split())]
    assert not missing, f"update docs/patterns.md: {missing}"


def test_figures_are_well_formed_svg() -> None:
    for file in sorted(FIGURES.glob("*.svg")):
        root = ET.parse(file).getroot()
        assert root.tag == f"{SVG_NS}svg", file.name
        _, _, width, height = (float(v) for v in root.attrib["viewBox"].split())
        for el in root.iter():
            tag = el.tag.removeprefix(SVG_NS)
            if tag in ("polyline", "polygon"):
                coords = [float(c) for pt in el.attrib["points"].split() for c in pt.split(",")]
            elif tag in ("line", "circle", "text"):
                coords = [float(el.attrib[k]) for k in COORDINATES[tag]]
            else:
                continue
            xs, ys = coords[0::2], coords[1::2]
            assert all(0 <= x <= width for x in xs), f"{file.name}: {tag} outside the viewBox"
            assert all(0 <= y <= height for y in ys), f"{file.name}: {tag} outside the viewBox"


def test_python_session(doc: str) -> None:
    fence = re.compile(r"^```pycon\n(.*?)^```$", re.MULTILINE | re.DOTALL)
    sessions = [(doc.count("\n", 0, m.start()) + 1, m.group(1)) for m in fence.finditer(doc)]
    assert sessions, "no pycon session found"
    parser = doctest.DocTestParser()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    report: list[str] = []
    globs: dict[str, object] = {"__name__": "patterns_md"}
    failed = 0
    for line, body in sessions:
        test = parser.get_doctest(body, globs, f"patterns.md:{line}", str(DOC), line)
        failed += runner.run(test, out=report.append, clear_globs=False).failed
        globs = test.globs
    assert failed == 0, "".join(report)
