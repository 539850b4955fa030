"""The dimension annotations of the pattern figures (``scripts/gen_pattern_figures.py``): each
pattern's parameters drawn onto the top view (dimension lines, radii, notes, a held heading,
reference circles), placed from the plan's own geometry.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from _pattern_svg import DIM, TIMES, Pt, Svg, arrowhead, label, num, unit_value, unit_vec
from _pattern_views import TopView

from planner import Plan


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
