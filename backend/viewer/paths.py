"""What a page draws in its own 3D view: a previewed path, a mission script, a past dive.

Each ``*_drawing`` function checks its input (``ValueError`` naming what is wrong) and returns
a :data:`Drawing`: a function that draws it on a :class:`Canvas` (a page's own scene) and
returns its labels, which the view places together with its other drawings' (see
:mod:`backend.viewer.labels`). Node names (under the group the drawing replaces)::

    /preview/join, /preview/body, /preview/waypoints, /preview/drops
    /preview/start, /preview/end, /preview/pattern           labels
    /script/path, /script/drops, /script/steps, /script/step_000 ...
    /replay/track, /replay/commands, /replay/start, /replay/end, /replay/cmd_000 ...
    /replay_at/vehicle, /replay_at/heading          the replay's slider: no label
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import numpy.typing as npt

from backend.viewer.draw import (
    PREVIEW_BODY_RGB,
    PREVIEW_JOIN_RGB,
    REPLAY_AT_RGB,
    REPLAY_COMMAND_RGB,
    REPLAY_RGB,
    SCRIPT_RGB,
    WAYPOINT_M,
    Canvas,
    columns,
    ned_to_view,
)
from backend.viewer.labels import MIN_LABEL_SEPARATION_M, LabelSpec

#: Draws on a page's canvas (inside its group, which it recreates) and returns its labels.
Drawing = Callable[[Canvas], list[LabelSpec]]
#: A replay's labels are at least its extent over this apart (and at least
#: :data:`MIN_LABEL_SEPARATION_M`): seen whole, a dive shows a handful of labels that do not
#: run into each other; the time slider shows every command.
REPLAY_LABELS_ACROSS = 6.0
#: The replayed vehicle's marker (m) and its heading line's length (m).
REPLAY_AT_M = 0.6
REPLAY_AT_NOSE_M = 2.0


def preview_drawing(
    xs: npt.ArrayLike,
    ys: npt.ArrayLike,
    zs: npt.ArrayLike,
    body_start: int = 0,
    label: str = "preview",
) -> Drawing:
    """A previewed path (NED metres).

    The join ``[0 .. body_start]`` is drawn in :data:`PREVIEW_JOIN_RGB`, the pattern body
    ``[body_start ..]`` in :data:`PREVIEW_BODY_RGB`; waypoints are a float32 point cloud;
    vertical lines drop from the surface to some waypoints (always the first, ``body_start``
    and the last); labels give the end depth, the pattern's start depth and the start depth
    (the start is where the vehicle is: dropped when the vehicle's label is there).

    Raises:
        ValueError: empty or unequal columns, non-finite values, ``body_start`` out of range.
    """
    x, y, z = columns(xs, ys, zs, "preview")
    n = len(x)
    if not 0 <= body_start < n:
        raise ValueError(f"preview: body_start must index a waypoint, got {body_start}")
    view = ned_to_view(x, y, z)

    def draw(c: Canvas) -> list[LabelSpec]:
        c.group("/preview")
        c.polyline("/preview/join", view[: body_start + 1], PREVIEW_JOIN_RGB)
        c.polyline("/preview/body", view[body_start:], PREVIEW_BODY_RGB)
        colors = np.empty((n, 3), dtype=np.uint8)
        colors[:body_start] = PREVIEW_JOIN_RGB
        colors[body_start:] = PREVIEW_BODY_RGB
        c.points("/preview/waypoints", view, colors, WAYPOINT_M)
        c.drops("/preview/drops", x, y, z, (0, body_start, n - 1))
        labels = []
        if n > 1:
            labels.append(
                LabelSpec.at("/preview/end", f"{label} end, depth {z[-1]:.1f} m", view[-1])
            )
        if 0 < body_start < n - 1:
            text = f"pattern, depth {z[body_start]:.1f} m"
            labels.append(LabelSpec.at("/preview/pattern", text, view[body_start]))
        start = f"{label} start, depth {z[0]:.1f} m"
        labels.append(LabelSpec.at("/preview/start", start, view[0], lift=False))
        return labels

    return draw


def script_drawing(
    xs: npt.ArrayLike,
    ys: npt.ArrayLike,
    zs: npt.ArrayLike,
    step_labels: Sequence[tuple[int, str]] = (),
) -> Drawing:
    """A mission script's path (NED metres) in :data:`SCRIPT_RGB`.

    Args:
        step_labels: ``(waypoint index, text)`` for each step's start; each gets a marker
            and a label ``"<text> (<depth> m)"``.

    Raises:
        ValueError: bad columns, or a step start that does not index a waypoint.
    """
    x, y, z = columns(xs, ys, zs, "script")
    n = len(x)
    steps = list(step_labels)
    for i, _ in steps:
        if not 0 <= i < n:
            raise ValueError(f"script: step start {i} does not index a waypoint")
    view = ned_to_view(x, y, z)

    def draw(c: Canvas) -> list[LabelSpec]:
        c.group("/script")
        c.polyline("/script/path", view, SCRIPT_RGB)
        c.drops("/script/drops", x, y, z, (0, n - 1, *(i for i, _ in steps)))
        if not steps:
            return []
        starts = [i for i, _ in steps]
        c.points("/script/steps", view[starts], SCRIPT_RGB, WAYPOINT_M * 2)
        return [
            LabelSpec.at(f"/script/step_{k:03d}", f"{text} ({z[i]:.1f} m)", view[i])
            for k, (i, text) in enumerate(steps)
        ]

    return draw


def replay_drawing(
    track: Sequence[tuple[float, float, float, float, float]],
    commands: Sequence[tuple[float, float, float, float, str]] = (),
    *,
    max_points: int = 20_000,
) -> Drawing:
    """A past dive.

    Args:
        track: ``(t_s, x_m, y_m, z_m, heading_deg)`` samples in time order (NED); drawn in
            :data:`REPLAY_RGB`, subsampled evenly to at most ``max_points`` (first and last
            kept). The heading is not drawn.
        commands: ``(t_s, x_m, y_m, z_m, label)`` where a command was acknowledged; each gets
            a marker in :data:`REPLAY_COMMAND_RGB`, and those far enough apart their (short)
            label, in time order: no two of the replay's labels are closer than its extent
            over :data:`REPLAY_LABELS_ACROSS` (the start's says how many went without). The
            track's start and end are labelled (one label when they are that close); the
            time slider (the page) says what happened when.

    Raises:
        ValueError: non-finite positions.
    """
    samples = np.array([row[1:4] for row in track], dtype=np.float64).reshape(-1, 3)
    if not np.isfinite(samples).all():
        raise ValueError("replay: track positions must be finite numbers")
    if len(samples) > max_points:
        keep = np.linspace(0, len(samples) - 1, max_points).round().astype(int)
        samples = samples[np.unique(keep)]
    cmd = np.array([row[1:4] for row in commands], dtype=np.float64).reshape(-1, 3)
    if not np.isfinite(cmd).all():
        raise ValueError("replay: command positions must be finite numbers")
    t1 = track[-1][0] - track[0][0] if track else 0.0
    marks = [str(row[4]) for row in commands]
    track_view = ned_to_view(samples[:, 0], samples[:, 1], samples[:, 2])
    cmd_view = ned_to_view(cmd[:, 0], cmd[:, 1], cmd[:, 2])
    everything = np.concatenate([track_view.reshape(-1, 3), cmd_view.reshape(-1, 3)])
    extent = float(np.ptp(everything, axis=0).max()) if len(everything) else 0.0
    sep = max(MIN_LABEL_SEPARATION_M, extent / REPLAY_LABELS_ACROSS)
    ends = list(track_view[:1]) if len(samples) else []
    if len(samples) and float(np.linalg.norm(track_view[-1] - track_view[0])) >= sep:
        ends.append(track_view[-1])  # the end has a label of its own when far enough
    kept = _apart([*ends, *cmd_view.reshape(-1, 3)], len(ends), sep)
    left_out = len(marks) - len(kept)

    def draw(c: Canvas) -> list[LabelSpec]:
        c.group("/replay")
        labels = []
        if len(cmd):
            c.points("/replay/commands", cmd_view, REPLAY_COMMAND_RGB, WAYPOINT_M * 2.5)
            labels = [LabelSpec.at(f"/replay/cmd_{k:03d}", marks[k], cmd_view[k]) for k in kept]
        if len(samples):
            c.polyline("/replay/track", track_view, REPLAY_RGB)
            start = "replay start" if len(ends) == 2 else f"replay, 0-{t1:.0f} s"
            if left_out:
                start += f" ({left_out} command{'s' if left_out > 1 else ''} unlabelled)"
            labels.append(LabelSpec.at("/replay/start", start, track_view[0]))
            if len(ends) == 2:
                labels.append(LabelSpec.at("/replay/end", f"end, {t1:.0f} s", track_view[-1]))
        return labels

    return draw


def _apart(points: Sequence[npt.ArrayLike], fixed: int, sep_m: float) -> list[int]:
    """Indices (from 0 after the first ``fixed`` points, which are always kept) of the points
    at least ``sep_m`` from every point kept before them, in order."""
    kept_at = [np.asarray(p, dtype=np.float64) for p in points[:fixed]]
    out = []
    for k, p in enumerate(points[fixed:]):
        q = np.asarray(p, dtype=np.float64)
        if all(float(np.linalg.norm(q - a)) >= sep_m for a in kept_at):
            kept_at.append(q)
            out.append(k)
    return out


def replay_at_drawing(x_m: float, y_m: float, z_m: float, heading_deg: float) -> Drawing:
    """The replayed vehicle at the time slider's time (NED): a marker and a line along its
    heading in :data:`REPLAY_AT_RGB`; no label (the page says what it was doing then).

    Raises:
        ValueError: a value that is not a finite number.
    """
    if not all(math.isfinite(v) for v in (x_m, y_m, z_m, heading_deg)):
        raise ValueError("replay position: x_m, y_m, z_m and heading_deg must be finite")
    h = math.radians(heading_deg)
    at = ned_to_view(x_m, y_m, z_m)
    nose = ned_to_view(
        x_m + REPLAY_AT_NOSE_M * math.cos(h), y_m + REPLAY_AT_NOSE_M * math.sin(h), z_m
    )

    def draw(c: Canvas) -> list[LabelSpec]:
        c.group("/replay_at")
        c.points("/replay_at/vehicle", at.reshape(1, 3), REPLAY_AT_RGB, REPLAY_AT_M)
        c.polyline("/replay_at/heading", np.stack([at, nose]), REPLAY_AT_RGB)
        return []

    return draw
