"""One whole-frame efficiency, computed from the codec's constants and quoted identically in
docs/protocol.md and docs/results.md."""

from __future__ import annotations

import re
from pathlib import Path

from analysis import ber, efficiency
from codec import FRAME_BITS, PAYLOAD_BITS

DOCS = Path(__file__).resolve().parents[2] / "docs"
QUOTE = re.compile(r"whole-frame efficiency[^.]*?(\d+)/(\d+) = (\d\.\d+)")


def test_the_definition() -> None:
    assert PAYLOAD_BITS == 4 + 6 * 8 == 52 and FRAME_BITS == 100
    assert efficiency.WHOLE_FRAME_EFFICIENCY == 0.52
    assert efficiency.whole_frame_text() == "52/100 = 0.52"
    assert efficiency.whole_frame_efficiency(80) == 52 / 108
    t2 = next(e for e in ber.efficiency_table() if e.t == 2)
    assert t2.frame_efficiency == efficiency.WHOLE_FRAME_EFFICIENCY


def test_both_docs_quote_the_same_figure() -> None:
    for name in ("protocol.md", "results.md"):
        text = (DOCS / name).read_text(encoding="utf-8")
        quotes = QUOTE.findall(text.replace("\n", " "))
        assert quotes, name
        assert set(quotes) == {("52", "100", "0.52")}, (name, quotes)
        assert "56/100" not in text, name
    results = (DOCS / "results.md").read_text(encoding="utf-8")
    # the efficiency table's T = 2 row: its whole-frame column is the same figure
    assert re.search(r"^\| 2 \| \(72, 56\) \|.*\| 0\.52 \|$", results, re.M)
