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

The drawing is in three parts beside this script: ``_pattern_svg.py`` (the SVG writer, colours
and number formatting), ``_pattern_views.py`` (the top view and depth profile, tracks and
markers) and ``_pattern_notes.py`` (the dimension annotations of each pattern's parameters);
this script composes the figures and writes them.
"""

from __future__ import annotations

import argparse
import math
import pathlib
from collections.abc import Sequence
from dataclasses import dataclass

from _pattern_notes import annotation_points, draw_annotations, pattern_notes
from _pattern_svg import (
    BODY,
    INK,
    JOIN,
    MUTED,
    NEW_BODY,
    NEW_JOIN,
    OLD_REST,
    Pt,
    Svg,
    label,
    num,
)
from _pattern_views import (
    PROFILE_BOX,
    TOP_BOX,
    ProfileView,
    TopView,
    body_time,
    clip,
    dashed,
    draw_anchor,
    draw_entry,
    draw_profile,
    draw_start,
    draw_track,
    entry_side,
    profile_points,
    solid,
    world,
)

import codec
import planner
from codec import Command, ParamValue
from planner import Plan, VehicleState

REPO_ROOT = pathlib.Path(__file__).resolve().parent.parent
#: Where the figures go by default.
OUT_DIR = REPO_ROOT / "docs" / "patterns"

#: The vehicle state every pattern figure starts from: at the origin, 2 m deep, heading east
#: at 0.5 m/s, with no plan running (so the mission anchor is the vehicle's position).
START = VehicleState(x_m=0.0, y_m=0.0, z_m=2.0, heading_deg=90.0, speed_mps=0.5)


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
