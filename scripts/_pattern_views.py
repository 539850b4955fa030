"""The two panels of every pattern figure (``scripts/gen_pattern_figures.py``) and what is
drawn on them: the top view (north up, east right, one scale, metre grid) and the depth
profile (depth down against time), the planner's path clipped into tracks, and the markers of
the vehicle's start, the mission anchor and the pattern's entry.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from _pattern_svg import (
    ENTRY,
    FRAME,
    GRID,
    INK,
    MUTED,
    SURFACE,
    Pt,
    Svg,
    arrowhead,
    label,
    num,
    unit_vec,
)

from planner import Path, VehicleState

#: A path piece: ``(t_s, x_m, y_m, z_m)`` per point.
Track = list[tuple[float, float, float, float]]


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
