"""The SVG canvas of ``scripts/gen_pattern_figures.py``: the figure size, the colours, number
formatting and a small SVG writer with its arrowheads and labels.

Every coordinate goes through :func:`f2` (at most two decimals, never ``-0.00``), so the same
drawing gives byte-identical files on any machine.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from xml.sax.saxutils import escape

from codec import ParamValue

WIDTH, HEIGHT = 700, 365
TIMES = "\u00d7"

# colours
INK = "#222222"
MUTED = "#666666"
GRID = "#e4e4e4"
FRAME = "#9a9a9a"
BODY = "#1f77b4"
JOIN = "#8c8c8c"
NEW_BODY = "#d62728"
NEW_JOIN = "#e8999a"
OLD_REST = "#aacde6"
ENTRY = "#2ca02c"
DIM = "#b85c00"
SURFACE = "#7fb2d9"

#: World point ``(north, east)`` in metres; screen points are ``(x, y)`` in SVG pixels.
Pt = tuple[float, float]


def f2(value: float) -> str:
    """Two decimals, never ``-0.00``."""
    text = f"{value:.2f}"
    return "0.00" if text == "-0.00" else text


def num(value: float) -> str:
    """Short label text: at most two decimals, no trailing zeros (``2``, ``1.43``)."""
    text = f2(value).rstrip("0").rstrip(".")
    return text or "0"


def unit_value(value: ParamValue, unit: str) -> str:
    if isinstance(value, str):
        return value
    return f"{num(float(value))} {unit}".strip()


class Svg:
    """Collects SVG elements; every coordinate goes through :func:`f2`."""

    def __init__(self, title: str) -> None:
        self.title = title
        self.parts: list[str] = []

    def _el(self, tag: str, attrs: dict[str, float | str], text: str | None = None) -> None:
        a = " ".join(
            f'{k}="{f2(v) if isinstance(v, float | int) else escape(v, {chr(34): "&quot;"})}"'
            for k, v in attrs.items()
        )
        if text is None:
            self.parts.append(f"<{tag} {a}/>")
        else:
            self.parts.append(f"<{tag} {a}>{escape(text)}</{tag}>")

    def line(self, a: Pt, b: Pt, style: str) -> None:
        self._el("line", {"x1": a[0], "y1": a[1], "x2": b[0], "y2": b[1], "style": style})

    def polyline(self, pts: Sequence[Pt], style: str) -> None:
        if len(pts) < 2:
            return
        points = " ".join(f"{f2(x)},{f2(y)}" for x, y in pts)
        self._el("polyline", {"points": points, "style": f"fill:none;{style}"})

    def polygon(self, pts: Sequence[Pt], style: str) -> None:
        points = " ".join(f"{f2(x)},{f2(y)}" for x, y in pts)
        self._el("polygon", {"points": points, "style": style})

    def circle(self, c: Pt, r: float, style: str) -> None:
        self._el("circle", {"cx": c[0], "cy": c[1], "r": r, "style": style})

    def rect(self, x: float, y: float, w: float, h: float, style: str) -> None:
        self._el("rect", {"x": x, "y": y, "width": w, "height": h, "style": style})

    def text(
        self,
        p: Pt,
        text: str,
        anchor: str = "start",
        size: float = 10,
        colour: str = INK,
        weight: str = "normal",
    ) -> None:
        style = f"font-size:{num(size)}px;fill:{colour}"
        if weight != "normal":
            style += f";font-weight:{weight}"
        self._el("text", {"x": p[0], "y": p[1], "text-anchor": anchor, "style": style}, text)

    def render(self) -> str:
        head = (
            '<?xml version="1.0" encoding="UTF-8"?>\n'
            f'<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" '
            f'viewBox="0 0 {WIDTH} {HEIGHT}" style="font-family:sans-serif">\n'
            f"<title>{escape(self.title)}</title>\n"
            f'<rect x="0" y="0" width="{WIDTH}" height="{HEIGHT}" style="fill:#ffffff"/>\n'
        )
        return head + "\n".join(self.parts) + "\n</svg>\n"


def unit_vec(a: Pt, b: Pt) -> Pt:
    dx, dy = b[0] - a[0], b[1] - a[1]
    d = math.hypot(dx, dy)
    return (dx / d, dy / d) if d > 0 else (1.0, 0.0)


def arrowhead(svg: Svg, tip: Pt, d: Pt, colour: str, size: float = 7.0) -> None:
    """Filled triangle at ``tip`` pointing along the unit screen vector ``d``."""
    nx, ny = -d[1], d[0]
    bx, by = tip[0] - d[0] * size, tip[1] - d[1] * size
    w = size * 0.45
    svg.polygon(
        [tip, (bx + nx * w, by + ny * w), (bx - nx * w, by - ny * w)], f"fill:{colour};stroke:none"
    )


def label(svg: Svg, p: Pt, d: Pt, text: str, gap: float = 6.0, colour: str = INK) -> None:
    """Text placed ``gap`` px from ``p`` in the screen direction ``d``, anchored away from it."""
    x, y = p[0] + d[0] * gap, p[1] + d[1] * gap
    anchor = "start" if d[0] > 0.4 else "end" if d[0] < -0.4 else "middle"
    y += 10 if d[1] > 0.4 else -2 if d[1] < -0.4 else 3.5
    lines = text.split("\n")
    if d[1] < -0.4:
        y -= 11 * (len(lines) - 1)
    for k, part in enumerate(lines):
        svg.text((x, y + 11 * k), part, anchor, colour=colour)
