"""Draw the figures of ``docs/patterns.md`` from the planner itself.

For every pattern of the command dictionary (``surface`` included) the planner expands the
pattern's default command for one vehicle state, :data:`START`, and this script draws
``docs/patterns/<name>.svg``: a top view (north up, east right, equal scale, metre grid) beside
the depth profile (depth against time, depth increasing downward). It also replays the paper's
three retasking scenarios (Fig. ``sim_reconfig``) as ``scenario_a.svg`` .. ``scenario_c.svg``:
the first command is planned, the vehicle is taken part-way along it, and the second command
is planned from there with the first as the running plan.

The pictures are the planner's output, not drawings of it:
``tests/planner/test_patterns_doc.py`` regenerates them and fails if the committed files
differ. After a planner change, run (from the repository root)::

    .venv/bin/python scripts/gen_pattern_figures.py [OUT_DIR]

Standard library and the project's packages only. Every number is written with at most two
decimals and nothing depends on the clock or the machine, so a rerun gives byte-identical files.
"""

from __future__ import annotations

import argparse
import math
import pathlib
from collections.abc import Sequence
from dataclasses import dataclass
from xml.sax.saxutils import escape

import codec
import planner
from codec import Command, ParamValue
from planner import Path, Plan, VehicleState

REPO_ROOT = pathlib.Path(__file__).resolve().parent.parent
#: Where the figures go by default.
OUT_DIR = REPO_ROOT / "docs" / "patterns"

#: The vehicle state every pattern figure starts from: at the origin, 2 m deep, heading east
#: at 0.5 m/s, with no plan running (so the mission anchor is the vehicle's position).
START = VehicleState(x_m=0.0, y_m=0.0, z_m=2.0, heading_deg=90.0, speed_mps=0.5)

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
#: A path piece: ``(t_s, x_m, y_m, z_m)`` per point.
Track = list[tuple[float, float, float, float]]


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


# --- SVG writer ---------------------------------------------------------------------------


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


# --- layout -------------------------------------------------------------------------------


@dataclass(frozen=True)
class Box:
    x: float
    y: float
    w: float
    h: float

    @property
    def right(self) -> float:
        return self.x + self.w

    @property
    def bottom(self) -> float:
        return self.y + self.h


TOP_BOX = Box(52.0, 62.0, 300.0, 260.0)
PROFILE_BOX = Box(420.0, 62.0, 258.0, 260.0)


def nice_step(minimum: float) -> float:
    """Smallest 1, 2 or 5 times a power of ten that is at least ``minimum``."""
    k = math.floor(math.log10(minimum))
    for m in (1.0, 2.0, 5.0, 10.0):
        step = m * 10.0**k
        if step >= minimum * (1 - 1e-9):
            return step
    return 10.0 ** (k + 1)  # pragma: no cover (the loop ends at 10)


def ticks(lo: float, hi: float, step: float) -> list[float]:
    return [i * step for i in range(math.ceil(lo / step - 1e-9), math.floor(hi / step + 1e-9) + 1)]


class TopView:
    """North up, east right, one scale for both axes, fitted around ``points``."""

    def __init__(self, box: Box, points: Sequence[Pt], margin_px: float = 34.0) -> None:
        ns = [p[0] for p in points]
        es = [p[1] for p in points]
        span_n = max(max(ns) - min(ns), 8.0)
        span_e = max(max(es) - min(es), 8.0)
        self.box = box
        self.cn = (max(ns) + min(ns)) / 2
        self.ce = (max(es) + min(es)) / 2
        self.scale = min((box.w - 2 * margin_px) / span_e, (box.h - 2 * margin_px) / span_n)

    def xy(self, p: Pt) -> Pt:
        b = self.box
        return (
            b.x + b.w / 2 + (p[1] - self.ce) * self.scale,
            b.y + b.h / 2 - (p[0] - self.cn) * self.scale,
        )

    def screen_dir(self, north: float, east: float) -> Pt:
        """Screen unit vector of a world direction."""
        return unit_vec((0.0, 0.0), (east, -north))

    def draw_frame(self, svg: Svg) -> None:
        b, s = self.box, self.scale
        step = nice_step(42.0 / s)
        e_lo, e_hi = self.ce - b.w / 2 / s, self.ce + b.w / 2 / s
        n_lo, n_hi = self.cn - b.h / 2 / s, self.cn + b.h / 2 / s
        grid = f"stroke:{GRID};stroke-width:1"
        for e in ticks(e_lo, e_hi, step):
            x = self.xy((0.0, e))[0]
            svg.line((x, b.y), (x, b.bottom), grid)
            svg.text((x, b.bottom + 13), num(e), "middle", 9, MUTED)
        for n in ticks(n_lo, n_hi, step):
            y = self.xy((n, 0.0))[1]
            svg.line((b.x, y), (b.right, y), grid)
            svg.text((b.x - 4, y + 3), num(n), "end", 9, MUTED)
        svg.rect(b.x, b.y, b.w, b.h, f"fill:none;stroke:{FRAME};stroke-width:1")
        svg.text((b.x, b.y - 6), "north (m)", "start", 10, MUTED)
        svg.text((b.x + b.w / 2, b.bottom + 28), "east (m)", "middle", 10, MUTED)
        svg.text((b.right, b.y - 6), f"top view, grid {num(step)} m", "end", 10, MUTED)


class ProfileView:
    """Depth (down) against time."""

    def __init__(self, box: Box, t_end: float, depths: Sequence[float]) -> None:
        z_lo, z_hi = min(depths), max(depths)
        pad = max(0.5, 0.16 * (z_hi - z_lo))
        self.box = box
        self.t_end = max(t_end, 1.0)
        self.z_lo, self.z_hi = z_lo - pad, z_hi + pad

    def xy(self, t: float, z: float) -> Pt:
        b = self.box
        return (
            b.x + t / self.t_end * b.w,
            b.y + (z - self.z_lo) / (self.z_hi - self.z_lo) * b.h,
        )

    def draw_frame(self, svg: Svg) -> None:
        b = self.box
        grid = f"stroke:{GRID};stroke-width:1"
        t_step = nice_step(self.t_end * 50.0 / b.w)
        for t in ticks(0.0, self.t_end, t_step):
            x = self.xy(t, 0.0)[0]
            svg.line((x, b.y), (x, b.bottom), grid)
            svg.text((x, b.bottom + 13), num(t), "middle", 9, MUTED)
        z_step = nice_step((self.z_hi - self.z_lo) * 28.0 / b.h)
        for z in ticks(self.z_lo, self.z_hi, z_step):
            y = self.xy(0.0, z)[1]
            svg.line((b.x, y), (b.right, y), grid)
            svg.text((b.x - 4, y + 3), num(z), "end", 9, MUTED)
        if self.z_lo < 0.0 < self.z_hi:
            y = self.xy(0.0, 0.0)[1]
            svg.line((b.x, y), (b.right, y), f"stroke:{SURFACE};stroke-width:1.5")
            svg.text((b.x + 40, y - 3), "surface", "start", 9, SURFACE)
        svg.rect(b.x, b.y, b.w, b.h, f"fill:none;stroke:{FRAME};stroke-width:1")
        svg.text((b.x, b.y - 6), "depth (m), down", "start", 10, MUTED)
        svg.text((b.x + b.w / 2, b.bottom + 28), "time (s)", "middle", 10, MUTED)

    def mark_time(self, svg: Svg, t: float, text: str) -> None:
        """A dotted vertical line at ``t`` with ``text`` at its foot."""
        x, b = self.xy(t, 0.0)[0], self.box
        svg.line((x, b.y), (x, b.bottom), f"stroke:{MUTED};stroke-width:1;stroke-dasharray:2 3")
        svg.text((x + 3, b.bottom - 5), text, "start", 9, MUTED)

    def end_labels(self, svg: Svg, track: Sequence[tuple[float, float]]) -> None:
        """Label the first and last depth of ``track`` (``(t, z)`` points) clear of the line."""
        pts = [self.xy(t, z) for t, z in track]
        first, last = pts[0], pts[-1]
        after = next((p for p in pts if abs(p[1] - first[1]) > 0.5), first)
        above = after[1] >= first[1]  # the line leaves downward or level: label above it
        y = first[1] - 5 if above else first[1] + 13
        svg.text((first[0] + 4, y), f"start {num(track[0][1])} m", "start", 10)
        before = next((p for p in reversed(pts) if abs(p[1] - last[1]) > 0.5), last)
        above = before[1] >= last[1]  # the line arrives from below or level: label above it
        y = last[1] - 5 if above else last[1] + 13
        svg.text((last[0] - 2, y), f"end {num(track[-1][1])} m", "end", 10)


# --- tracks -------------------------------------------------------------------------------


def clip(path: Path, t0: float, t1: float) -> Track:
    """The path between ``t0`` and ``t1`` (s after it starts), ends interpolated."""
    if t1 <= t0:
        return []
    a, b = path.sample(t0), path.sample(t1)
    out: Track = [(t0, a.x_m, a.y_m, a.z_m)]
    for i, t in enumerate(path.times):
        if t0 < t < t1:
            out.append((t, path.xs[i], path.ys[i], path.zs[i]))
    out.append((t1, b.x_m, b.y_m, b.z_m))
    return out


def body_time(path: Path) -> float:
    return path.times[path.body_start]


def world(track: Track) -> list[Pt]:
    return [(x, y) for _, x, y, _ in track]


def draw_track(
    svg: Svg,
    view: TopView,
    track: Track,
    style: str,
    colour: str | None = None,
    arrows: list[Pt] | None = None,
) -> None:
    """Polyline of ``track``; with ``colour``, direction arrows every ~90 px of screen length.

    ``arrows`` collects the arrow positions so later tracks do not stack arrows on them.
    """
    pts: list[Pt] = []
    for p in world(track):
        q = view.xy(p)
        if not pts or math.dist(q, pts[-1]) > 0.05:
            pts.append(q)
    svg.polyline(pts, style)
    if colour is None or arrows is None or len(pts) < 2:
        return
    seg = [math.dist(pts[i], pts[i + 1]) for i in range(len(pts) - 1)]
    total = sum(seg)
    if total < 30.0:
        return
    count = max(1, round(total / 90.0))
    targets = [(k + 0.5) * total / count for k in range(count)]
    run, i = 0.0, 0
    for s in targets:
        while i < len(seg) - 1 and run + seg[i] < s:
            run += seg[i]
            i += 1
        f = (s - run) / seg[i] if seg[i] > 0 else 0.0
        a, b = pts[i], pts[i + 1]
        tip = (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]))
        if all(math.dist(tip, q) > 40.0 for q in arrows):
            d = unit_vec(a, b)
            arrowhead(svg, (tip[0] + d[0] * 3.5, tip[1] + d[1] * 3.5), d, colour)
            arrows.append(tip)


def profile_points(track: Track, offset_s: float = 0.0) -> list[tuple[float, float]]:
    return [(t + offset_s, z) for t, _, _, z in track]


def draw_profile(
    svg: Svg, view: ProfileView, pts: Sequence[tuple[float, float]], style: str
) -> None:
    svg.polyline([view.xy(t, z) for t, z in pts], style)


def solid(colour: str) -> str:
    return f"stroke:{colour};stroke-width:2;stroke-linejoin:round"


def dashed(colour: str) -> str:
    return f"stroke:{colour};stroke-width:1.6;stroke-dasharray:5 3"


# --- markers ------------------------------------------------------------------------------


def draw_start(svg: Svg, view: TopView, state: VehicleState, text: str | None = "start") -> None:
    """The vehicle's pose: an arrow along its heading from its position."""
    p = view.xy((state.x_m, state.y_m))
    h = state.heading_rad
    d = view.screen_dir(math.cos(h), math.sin(h))
    tip = (p[0] + d[0] * 20, p[1] + d[1] * 20)
    svg.line(p, (tip[0] - d[0] * 5, tip[1] - d[1] * 5), f"stroke:{INK};stroke-width:2")
    arrowhead(svg, tip, d, INK, 8.0)
    svg.circle(p, 2.5, f"fill:{INK}")
    if text:
        label(svg, p, (-d[0], -d[1]), text)


def draw_anchor(
    svg: Svg, view: TopView, anchor: Pt, d: Pt = (-0.6, 0.8), text: str = "anchor"
) -> None:
    p = view.xy(anchor)
    style = f"fill:none;stroke:{INK};stroke-width:1.2"
    svg.circle(p, 6.0, style)
    svg.line((p[0] - 6, p[1]), (p[0] + 6, p[1]), style)
    svg.line((p[0], p[1] - 6), (p[0], p[1] + 6), style)
    label(svg, p, d, text, 8.0)


def draw_entry(svg: Svg, view: TopView, entry: Pt, d: Pt, text: str = "entry") -> None:
    p = view.xy(entry)
    svg.circle(p, 4.0, f"fill:{ENTRY};stroke:#ffffff;stroke-width:1")
    if text:
        label(svg, p, d, text, 7.0, ENTRY)


def entry_side(view: TopView, path: Path, anchor: Pt) -> Pt:
    """Screen direction for the entry label: across the path there, away from the anchor."""
    i = path.body_start
    e = view.xy((path.xs[i], path.ys[i]))
    nxt = next(
        (
            q
            for k in range(i + 1, len(path))
            if math.dist(q := view.xy((path.xs[k], path.ys[k])), e) > 1
        ),
        None,
    )
    a = view.xy(anchor)
    out = unit_vec(a, e) if math.dist(a, e) > 1.0 else (0.0, -1.0)
    if nxt is None:
        return out
    d = unit_vec(e, nxt)
    n = (-d[1], d[0])
    return n if n[0] * out[0] + n[1] * out[1] >= 0 else (-n[0], -n[1])


# --- dimension annotations ----------------------------------------------------------------


@dataclass(frozen=True)
class Dim:
    """A dimension line from ``a`` to ``b``, drawn ``offset`` px toward the world direction
    ``away``."""

    a: Pt
    b: Pt
    away: Pt
    text: str
    offset: float = 14.0


@dataclass(frozen=True)
class Radius:
    """A radius from ``centre`` to ``to``, labelled beside its middle, past its end
    (``at_end``) or at the world point ``callout`` with a leader line to its middle."""

    centre: Pt
    to: Pt
    text: str
    at_end: bool = False
    callout: Pt | None = None


@dataclass(frozen=True)
class Note:
    """Text ``gap`` px from a world point in the screen direction ``d``."""

    at: Pt
    d: Pt
    text: str
    gap: float = 8.0


@dataclass(frozen=True)
class HeadingArrow:
    at: Pt
    heading_deg: float
    text: str


@dataclass(frozen=True)
class RefCircle:
    centre: Pt
    radius: float


Annotation = Dim | Radius | Note | HeadingArrow | RefCircle


def annotation_points(notes: Sequence[Annotation]) -> list[Pt]:
    out: list[Pt] = []
    for n in notes:
        if isinstance(n, Dim):
            out += [n.a, n.b]
        elif isinstance(n, Radius):
            out += [n.centre, n.to] + ([n.callout] if n.callout else [])
        elif isinstance(n, RefCircle):
            c, r = n.centre, n.radius
            out += [(c[0] - r, c[1] - r), (c[0] + r, c[1] + r)]
        else:
            out.append(n.at)
    return out


def draw_annotations(svg: Svg, view: TopView, notes: Sequence[Annotation]) -> None:
    thin = f"stroke:{DIM};stroke-width:1"
    for n in notes:
        if isinstance(n, RefCircle):
            c = view.xy(n.centre)
            svg.circle(c, n.radius * view.scale, f"fill:none;{thin};stroke-dasharray:2 3")
        elif isinstance(n, Dim):
            a, b = view.xy(n.a), view.xy(n.b)
            o = view.screen_dir(*n.away)
            a2 = (a[0] + o[0] * n.offset, a[1] + o[1] * n.offset)
            b2 = (b[0] + o[0] * n.offset, b[1] + o[1] * n.offset)
            svg.line((a[0] + o[0] * 3, a[1] + o[1] * 3), (a2[0] + o[0] * 4, a2[1] + o[1] * 4), thin)
            svg.line((b[0] + o[0] * 3, b[1] + o[1] * 3), (b2[0] + o[0] * 4, b2[1] + o[1] * 4), thin)
            svg.line(a2, b2, thin)
            d = unit_vec(a2, b2)
            arrowhead(svg, b2, d, DIM, 6.0)
            arrowhead(svg, a2, (-d[0], -d[1]), DIM, 6.0)
            mid = ((a2[0] + b2[0]) / 2, (a2[1] + b2[1]) / 2)
            label(svg, mid, o, n.text, 4.0, DIM)
        elif isinstance(n, Radius):
            c, p = view.xy(n.centre), view.xy(n.to)
            d = unit_vec(c, p)
            svg.line(c, (p[0] - d[0] * 4, p[1] - d[1] * 4), thin)
            arrowhead(svg, p, d, DIM, 6.0)
            if n.callout is not None:
                mid = ((c[0] + p[0]) / 2, (c[1] + p[1]) / 2)
                q = view.xy(n.callout)
                svg.line(mid, q, f"stroke:{DIM};stroke-width:0.8;stroke-dasharray:1 2")
                label(svg, q, unit_vec(mid, q), n.text, 3.0, DIM)
            elif n.at_end:
                label(svg, p, d, n.text, 5.0, DIM)
            else:
                mid = ((c[0] + p[0]) / 2, (c[1] + p[1]) / 2)
                side = (-d[1], d[0]) if d[1] <= 0 else (d[1], -d[0])  # the upper side
                label(svg, mid, side, n.text, 4.0, DIM)
        elif isinstance(n, HeadingArrow):
            p = view.xy(n.at)
            h = math.radians(n.heading_deg)
            d = view.screen_dir(math.cos(h), math.sin(h))
            tip = (p[0] + d[0] * 28, p[1] + d[1] * 28)
            svg.line(p, (tip[0] - d[0] * 5, tip[1] - d[1] * 5), f"stroke:{DIM};stroke-width:2")
            arrowhead(svg, tip, d, DIM, 8.0)
            label(svg, tip, d, n.text, 4.0, DIM)
        else:
            label(svg, view.xy(n.at), n.d, n.text, n.gap, DIM)


def polar(centre: Pt, radius: float, bearing_deg: float) -> Pt:
    b = math.radians(bearing_deg)
    return centre[0] + radius * math.cos(b), centre[1] + radius * math.sin(b)


def pattern_notes(p: Plan) -> list[Annotation]:
    """Dimension annotations of the pattern's parameters, placed from the plan's geometry."""
    name = p.pattern
    params = p.command.params
    pattern = p.command.pattern

    def val(key: str) -> float:
        v = params[key]
        assert not isinstance(v, str)
        return float(v)

    def txt(key: str) -> str:
        return f"{key} {unit_value(params[key], pattern.field(key).unit)}"

    ax, ay = p.anchor
    if name in ("square", "box_orbit"):
        half = val("side_span") / 2 if name == "square" else val("radius")
        if name == "square":
            return [
                Dim((ax + half, ay - half), (ax + half, ay + half), (1.0, 0.0), txt("side_span"))
            ]
        return [
            Radius(p.anchor, (ax, ay - half), txt("radius") + "\n(half-width)"),
            Note((ax - half, ay), (0.0, 1.0), f"laps {params['laps']}", 6.0),
        ]
    if name == "circle":
        return [Radius(p.anchor, polar(p.anchor, val("radius"), p.angle_deg + 135), txt("radius"))]
    if name == "helix":
        r = val("radius")
        return [
            Radius(p.anchor, polar(p.anchor, r, p.angle_deg + 135), txt("radius")),
            Note(
                (ax - r, ay),
                (0.0, 1.0),
                f"turns {params['turns']}: {num(val('start_depth'))} m to "
                f"{num(val('end_depth'))} m",
                6.0,
            ),
        ]
    if name == "spiral":
        r0, r1 = val("initial_radius"), val("final_radius")
        return [
            RefCircle(p.anchor, r0),
            RefCircle(p.anchor, r1),
            Radius(
                p.anchor,
                polar(p.anchor, r0, p.angle_deg + 225),
                txt("initial_radius"),
                callout=polar(p.anchor, r1 * 1.1, p.angle_deg + 245),
            ),
            Radius(p.anchor, polar(p.anchor, r1, p.angle_deg + 135), txt("final_radius"), True),
            Note((ax - r1, ay), (0.0, 1.0), f"loops {params['loops']}", 6.0),
        ]
    if name == "lawnmower":
        ox, oy = p.origin
        a = math.radians(p.angle_deg)
        u = (math.cos(a), math.sin(a))
        v = (-u[1], u[0])  # starboard of the lane axis
        length = val("sweep_length")

        def at(along: float, off: float) -> Pt:
            return ox + along * u[0] + off * v[0], oy + along * u[1] + off * v[1]

        last = p.lanes[-1]
        return [
            Dim(at(0.0, p.lanes[0]), at(length, p.lanes[0]), (-v[0], -v[1]), txt("sweep_length")),
            Dim(
                at(length, p.lanes[0]),
                at(length, p.lanes[1]),
                (-u[0], -u[1]),
                txt("lane_spacing"),
                28.0,
            ),
            Note(
                at(length / 2, last),
                view_dir_of(v),
                f"laps {params['laps']}: {len(p.lanes)} lanes",
                10.0,
            ),
        ]
    if name == "straight":
        path = p.path
        end = (path.xs[-1], path.ys[-1])
        h = math.radians(val("heading"))
        left = (math.sin(h), -math.cos(h))  # port side of the line
        dist = val("duration") * val("speed")
        return [
            Dim(
                p.origin,
                end,
                left,
                f"duration {TIMES} speed\n= {num(val('duration'))} s {TIMES} "
                f"{num(val('speed'))} m/s\n= {num(dist)} m",
            ),
            Note(end, view_dir_of((math.cos(h), math.sin(h))), txt("heading"), 8.0),
        ]
    if name == "hover":
        hold = p.path.hold_heading_deg
        return [HeadingArrow(p.origin, hold if hold is not None else 0.0, txt("heading") + " held")]
    return []


def view_dir_of(v: Pt) -> Pt:
    """Screen direction of a world direction, without a view (north up, east right)."""
    return unit_vec((0.0, 0.0), (v[1], -v[0]))


# --- figures ------------------------------------------------------------------------------


def header(svg: Svg, lines: Sequence[str]) -> None:
    for k, text in enumerate(lines):
        if k == 0:
            svg.text((10.0, 17.0), text, "start", 13, INK, "bold")
        else:
            svg.text((10.0, 17.0 + 13.5 * k), text, "start", 10.5, MUTED)


def state_text(s: VehicleState) -> str:
    return (
        f"x {num(s.x_m)} m N, y {num(s.y_m)} m E, {num(s.z_m)} m deep, "
        f"heading {s.heading_deg:03.0f}°, {num(s.speed_mps)} m/s"
    )


def make(name: str, **changes: ParamValue) -> Command:
    """The pattern's default command with ``changes``."""
    pattern = codec.DICTIONARY[name]
    return codec.make_command(pattern, {**pattern.defaults, **changes})[0]


def pattern_figure(name: str) -> str:
    pattern = codec.DICTIONARY[name]
    command = make(name)
    p = planner.plan(command, START)
    path = p.path
    t_body, t_end = body_time(path), path.duration_s
    join, body = clip(path, 0.0, t_body), clip(path, t_body, t_end)
    notes = pattern_notes(p)

    svg = Svg(f"{name}: {command.describe()}")
    if name in planner.REPEATING_PATTERNS:
        ends = "repeats until retasked"
    elif name == "surface":
        ends = f"rises in place at {num(planner.HEAVE_CAPABILITY_MPS * 1000)} mm/s, then stays up"
    elif name == "hover":
        ends = "the duration counts from when it takes effect, depth change included"
    else:
        ends = "then holds at the end"
    header(
        svg,
        [
            f"{name} (ID {pattern.id}): {pattern.doc}",
            f"{command.describe()}; {ends}",
            f"start: {state_text(START)}, no plan running · dashed: join · solid: pattern",
        ],
    )
    world_pts = [*world(join), *world(body), p.anchor, *annotation_points(notes)]
    view = TopView(TOP_BOX, world_pts)
    view.draw_frame(svg)
    draw_annotations(svg, view, notes)
    arrows: list[Pt] = []
    draw_track(svg, view, join, dashed(JOIN), JOIN, arrows)
    draw_track(svg, view, body, solid(BODY), BODY, arrows)
    entry = (path.xs[path.body_start], path.ys[path.body_start])
    if name in ("hover", "surface"):
        what = "hold point" if name == "hover" else "surfacing point"
        draw_start(svg, view, START, None)
        draw_anchor(svg, view, p.anchor, (0.6, 0.8), f"start = anchor = {what}")
    else:
        together = math.dist(p.anchor, (START.x_m, START.y_m)) < 0.01
        at_start = math.dist(entry, (START.x_m, START.y_m)) < 0.01
        draw_entry(svg, view, entry, entry_side(view, path, p.anchor), "" if at_start else "entry")
        draw_start(svg, view, START, None if together else "start = entry" if at_start else "start")
        draw_anchor(svg, view, p.anchor, text="start = anchor" if together else "anchor")

    prof = ProfileView(PROFILE_BOX, t_end, path.zs)
    prof.draw_frame(svg)
    draw_profile(svg, prof, profile_points(join), dashed(JOIN))
    draw_profile(svg, prof, profile_points(body), solid(BODY))
    prof.end_labels(svg, profile_points(clip(path, 0.0, t_end)))
    if path.loop_start is not None:
        prof.mark_time(svg, path.times[path.loop_start], "repeated lap")
    return svg.render()


@dataclass(frozen=True)
class Scenario:
    """One of the paper's retasking scenarios (Fig. sim_reconfig)."""

    key: str
    title: str
    first: Command
    switch_s: float
    second: Command


SCENARIOS = (
    Scenario(
        "a",
        "Scenario (a): lawnmower sweep length extended mid-survey (same pattern)",
        make("lawnmower", depth=5.0, sweep_length=30.0, lane_spacing=10.0, laps=2),
        40.0,
        make("lawnmower", depth=5.0, sweep_length=50.0, lane_spacing=10.0, laps=2),
    ),
    Scenario(
        "b",
        "Scenario (b): helix around a panel, then a square at constant depth",
        make("helix", start_depth=2.0, end_depth=8.0, radius=5.0, turns=3),
        100.0,
        make("square", depth=5.0, side_span=8.0),
    ),
    Scenario(
        "c",
        "Scenario (c): square around a pod, then a circle at another depth",
        make("square", depth=5.0, side_span=10.0),
        150.0,
        make("circle", depth=10.0, radius=8.0, direction="ccw"),
    ),
)


def retask_state(first: Plan, t_s: float) -> VehicleState:
    """The vehicle ``t_s`` into ``first``, as the planner sees it when the retask arrives."""
    sp = first.path.sample(t_s)
    speed = sp.speed_mps if sp.speed_mps > 0 else START.speed_mps
    return VehicleState(
        sp.x_m, sp.y_m, sp.z_m, heading_deg=sp.course_deg, speed_mps=speed, t_s=first.t0_s + t_s
    )


def scenario_plans(s: Scenario) -> tuple[Plan, VehicleState, Plan]:
    """``(first plan, vehicle state at the switch, second plan)``."""
    first = planner.plan(s.first, START)
    state = retask_state(first, s.switch_s)
    return first, state, planner.plan(s.second, state, first)


def draw_retask(svg: Svg, view: TopView, state: VehicleState, entry: Pt, entry_d: Pt) -> None:
    """Diamond where the retask arrives, labelled across the course (clear of the entry's label)."""
    q = view.xy((state.x_m, state.y_m))
    svg.polygon(
        [(q[0], q[1] - 6), (q[0] + 6, q[1]), (q[0], q[1] + 6), (q[0] - 6, q[1])],
        f"fill:#ffffff;stroke:{NEW_BODY};stroke-width:1.5",
    )
    h = state.heading_rad
    d = view.screen_dir(math.cos(h), math.sin(h))
    side = (d[1], -d[0]) if d[0] >= 0 else (-d[1], d[0])  # across the course, upward
    if math.dist(entry, q) < 80.0 and side[0] * entry_d[0] + side[1] * entry_d[1] > 0:
        side = (-side[0], -side[1])
    label(svg, q, side, f"retask, t = {num(state.t_s)} s", 9.0)


def scenario_figure(s: Scenario) -> str:
    first, state, second = scenario_plans(s)
    ts = s.switch_s
    p1, p2 = first.path, second.path
    flown_join = clip(p1, 0.0, min(ts, body_time(p1)))
    flown_body = clip(p1, body_time(p1), ts)
    rest = clip(p1, ts, p1.duration_s)
    new_join = clip(p2, 0.0, body_time(p2))
    new_body = clip(p2, body_time(p2), p2.duration_s)

    svg = Svg(f"scenario {s.key}: {s.first.describe()} -> {s.second.describe()}")
    header(
        svg,
        [
            s.title,
            f"(i) blue, from t = 0 s: {s.first.describe()}",
            f"(ii) red, sent at t = {num(ts)} s: {s.second.describe()}",
        ],
    )
    tracks = [flown_join, flown_body, rest, new_join, new_body]
    world_pts = [p for tr in tracks for p in world(tr)] + [first.anchor, second.anchor]
    view = TopView(TOP_BOX, world_pts)
    view.draw_frame(svg)
    arrows: list[Pt] = []
    draw_track(svg, view, rest, f"stroke:{OLD_REST};stroke-width:1.5;stroke-dasharray:1 3")
    draw_track(svg, view, flown_join, dashed(JOIN), JOIN, arrows)
    draw_track(svg, view, flown_body, solid(BODY), BODY, arrows)
    draw_track(svg, view, new_join, dashed(NEW_JOIN), NEW_JOIN, arrows)
    draw_track(svg, view, new_body, solid(NEW_BODY), NEW_BODY, arrows)
    together = math.dist(first.anchor, (START.x_m, START.y_m)) < 0.01
    draw_start(svg, view, START, None if together else "start")
    if math.dist(first.anchor, second.anchor) > 0.01:
        draw_anchor(svg, view, first.anchor, (-1.0, 0.0), "anchor (i)")
        draw_anchor(svg, view, second.anchor, (1.0, 0.0), "anchor (ii)")
    else:
        draw_anchor(svg, view, second.anchor, text="start = anchor" if together else "anchor")
    entry = (p2.xs[p2.body_start], p2.ys[p2.body_start])
    e_side = entry_side(view, p2, second.anchor)
    if math.dist(entry, (state.x_m, state.y_m)) > 0.01:
        draw_entry(svg, view, entry, e_side, "new entry")
    draw_retask(svg, view, state, view.xy(entry), e_side)

    t_end = ts + p2.duration_s
    flown = profile_points(flown_join) + profile_points(flown_body)
    new = profile_points(new_join, ts) + profile_points(new_body, ts)
    prof = ProfileView(PROFILE_BOX, t_end, [z for _, z in flown + new])
    prof.draw_frame(svg)
    prof.mark_time(svg, ts, "retask")
    draw_profile(svg, prof, profile_points(flown_join), dashed(JOIN))
    draw_profile(svg, prof, profile_points(flown_body), solid(BODY))
    draw_profile(svg, prof, profile_points(new_join, ts), dashed(NEW_JOIN))
    draw_profile(svg, prof, profile_points(new_body, ts), solid(NEW_BODY))
    prof.end_labels(svg, flown + new)
    return svg.render()


def figures() -> dict[str, str]:
    """File name -> SVG text, in a fixed order."""
    out = {f"{name}.svg": pattern_figure(name) for name in codec.DICTIONARY}
    out.update({f"scenario_{s.key}.svg": scenario_figure(s) for s in SCENARIOS})
    return out


def main(out_dir: pathlib.Path | None = None) -> list[pathlib.Path]:
    """Write every figure into ``out_dir`` (default :data:`OUT_DIR`); returns the files."""
    target = OUT_DIR if out_dir is None else out_dir
    target.mkdir(parents=True, exist_ok=True)
    written: list[pathlib.Path] = []
    for name, text in figures().items():
        file = target / name
        file.write_text(text, encoding="utf-8", newline="\n")
        written.append(file)
    return written


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("out_dir", nargs="?", type=pathlib.Path, help=f"default: {OUT_DIR}")
    args = parser.parse_args()
    for written_file in main(args.out_dir):
        print(written_file)
