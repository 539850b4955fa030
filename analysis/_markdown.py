"""Markdown helpers for the results page: tables, numbers, relative links, heading anchors."""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from pathlib import Path


def table(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """A GitHub Markdown table; ``|`` inside a cell is escaped."""

    def line(cells: Sequence[str]) -> str:
        return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"

    return "\n".join([line(headers), line(["---"] * len(headers)), *(line(r) for r in rows)])


def num(value: object, digits: int = 4) -> str:
    """A number in ``digits`` significant figures (``-`` for None, yes/no for a bool)."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if value != 0 and (abs(value) < 1e-3 or abs(value) >= 1e6):
            return f"{value:.{digits - 1}e}"
        return f"{value:.{digits}g}"
    return str(value)


def pct(value: float) -> str:
    """A fraction as a percentage with three decimals."""
    return f"{value * 100:.3f} %"


def link(path: Path, base: Path) -> str:
    """``path`` relative to ``base`` (the page's directory), with forward slashes."""
    return Path(os.path.relpath(path.resolve(), base.resolve())).as_posix()


def slug(heading: str) -> str:
    """GitHub's anchor for a heading's text."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def kib_text(kib: float) -> str:
    """A size the kernel reports in kB (KiB, 1024 bytes) as MiB."""
    return f"{kib / 1024:.2f} MiB"


__all__ = ["kib_text", "link", "num", "pct", "slug", "table"]
