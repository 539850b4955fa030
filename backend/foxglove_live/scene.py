"""The live view's drawings, as Foxglove scene updates (NED in, the scene frame out through
:mod:`backend.foxglove_live.frames`): a path as a line, the believed position with its
uncertainty ring, the ME transmitter with its range ring.

Colours are the console's 3D view's (:mod:`backend.viewer.draw`), so a path looks the same in
both views.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Final

from foxglove.messages import (
    Color,
    CylinderPrimitive,
    LinePrimitive,
    LinePrimitiveLineType,
    Pose,
    Quaternion,
    SceneEntity,
    SceneEntityDeletion,
    SceneEntityDeletionType,
    SceneUpdate,
    SpherePrimitive,
    TextPrimitive,
    Vector3,
)

from backend.foxglove_live.frames import FRAME, point, stamp, vector

Rgb = tuple[int, int, int]

#: The 3D view's colours (backend/viewer/draw.py; not imported: it loads viser).
ACTIVE_RGB: Final[Rgb] = (70, 220, 110)
PREVIEW_JOIN_RGB: Final[Rgb] = (255, 150, 40)
PREVIEW_BODY_RGB: Final[Rgb] = (40, 200, 255)
#: The prediction (the page's chart draws it dashed; here a colour of its own).
PREDICTION_RGB: Final[Rgb] = (165, 145, 255)
#: The believed position (backend/viewer/belief.py).
BELIEF_RGB: Final[Rgb] = (255, 110, 110)
STATION_RGB: Final[Rgb] = (230, 230, 240)
#: Line width on screen (px).
LINE_PX: Final = 2.0
#: Points of a ring (a circle drawn as a closed line).
RING_POINTS: Final = 96
#: Size of the marker at the believed position (m).
MARKER_M: Final = 1.0
#: The transmitter's mast as drawn: diameter and height above the surface (m).
MAST_M: Final = (1.0, 3.0)
TEXT_PX: Final = 14.0


def _at(x_m: float, y_m: float, z_m: float) -> Pose:
    """A NED point as an unrotated pose in the scene frame."""
    return Pose(position=vector(x_m, y_m, z_m), orientation=Quaternion(w=1.0))


def color(rgb: Rgb, alpha: float = 1.0) -> Color:
    return Color(r=rgb[0] / 255.0, g=rgb[1] / 255.0, b=rgb[2] / 255.0, a=alpha)


def _line(
    xs: Sequence[float],
    ys: Sequence[float],
    zs: Sequence[float],
    colors: Sequence[Rgb],
    kind: LinePrimitiveLineType = LinePrimitiveLineType.LineStrip,
) -> LinePrimitive:
    return LinePrimitive(
        type=kind,
        thickness=LINE_PX,
        scale_invariant=True,
        points=[point(x, y, z) for x, y, z in zip(xs, ys, zs, strict=True)],
        colors=[color(c) for c in colors],
    )


def _text(x_m: float, y_m: float, z_m: float, words: str, rgb: Rgb) -> TextPrimitive:
    return TextPrimitive(
        pose=_at(x_m, y_m, z_m),
        billboard=True,
        font_size=TEXT_PX,
        scale_invariant=True,
        color=color(rgb),
        text=words,
    )


def path_update(
    entity: str,
    ns: int,
    xs: Sequence[float],
    ys: Sequence[float],
    zs: Sequence[float],
    label: str,
    rgb: Rgb,
    *,
    body_start: int = 0,
    body_rgb: Rgb | None = None,
) -> SceneUpdate:
    """A path (NED m) as one entity ``entity``, replacing what it showed: a line in ``rgb``
    (from ``body_start`` on in ``body_rgb``, when given: a preview's join, then its
    pattern), labelled at its first point."""
    colors = [rgb if body_rgb is None or i < body_start else body_rgb for i in range(len(xs))]
    texts = [_text(xs[0], ys[0], zs[0], label, rgb)] if len(xs) else []
    return SceneUpdate(
        entities=[
            SceneEntity(
                timestamp=stamp(ns),
                frame_id=FRAME,
                id=entity,
                lines=[_line(xs, ys, zs, colors)],
                texts=texts,
            )
        ]
    )


def deletion(ns: int, entity: str | None = None) -> SceneUpdate:
    """Remove ``entity`` (None: everything the topic showed)."""
    kind = SceneEntityDeletionType.All if entity is None else SceneEntityDeletionType.MatchingId
    return SceneUpdate(
        deletions=[SceneEntityDeletion(timestamp=stamp(ns), type=kind, id=entity or "")]
    )


def ring(x_m: float, y_m: float, z_m: float, radius_m: float) -> tuple[list[float], ...]:
    """A horizontal circle of ``radius_m`` about a NED point, as NED columns (closed by the
    line loop that draws it)."""
    angles = [2.0 * math.pi * k / RING_POINTS for k in range(RING_POINTS)]
    xs = [x_m + radius_m * math.cos(a) for a in angles]
    ys = [y_m + radius_m * math.sin(a) for a in angles]
    return xs, ys, [z_m] * RING_POINTS


def belief_update(
    entity: str, ns: int, x_m: float, y_m: float, z_m: float, sigma_m: float | None, label: str
) -> SceneUpdate:
    """The believed position (NED m): a marker, its one-sigma ring when the uncertainty is
    known, and a label."""
    lines = []
    if sigma_m is not None and sigma_m > 0.0:
        xs, ys, zs = ring(x_m, y_m, z_m, sigma_m)
        loop = LinePrimitiveLineType.LineLoop
        lines.append(_line(xs, ys, zs, [BELIEF_RGB] * len(xs), loop))
    marker = SpherePrimitive(
        pose=_at(x_m, y_m, z_m),
        size=Vector3(x=MARKER_M, y=MARKER_M, z=MARKER_M),
        color=color(BELIEF_RGB, 0.8),
    )
    return SceneUpdate(
        entities=[
            SceneEntity(
                timestamp=stamp(ns),
                frame_id=FRAME,
                id=entity,
                spheres=[marker],
                lines=lines,
                texts=[_text(x_m, y_m, z_m - MARKER_M, label, BELIEF_RGB)],
            )
        ]
    )


def station_update(entity: str, ns: int, x_m: float, y_m: float, range_m: float) -> SceneUpdate:
    """The ME transmitter at the surface (NED m): a mast, and its range ring of ``range_m``
    at the surface."""
    width, height = MAST_M
    xs, ys, zs = ring(x_m, y_m, 0.0, range_m)
    mast = CylinderPrimitive(
        pose=_at(x_m, y_m, -height / 2.0),
        size=Vector3(x=width, y=width, z=height),
        bottom_scale=1.0,
        top_scale=0.3,
        color=color(STATION_RGB),
    )
    return SceneUpdate(
        entities=[
            SceneEntity(
                timestamp=stamp(ns),
                frame_id=FRAME,
                id=entity,
                cylinders=[mast],
                lines=[_line(xs, ys, zs, [STATION_RGB] * len(xs), LinePrimitiveLineType.LineLoop)],
                texts=[
                    _text(x_m, y_m, -height - 1.0, f"ME transmitter ({range_m:g} m)", STATION_RGB)
                ],
            )
        ]
    )


__all__ = [
    "ACTIVE_RGB",
    "BELIEF_RGB",
    "PREDICTION_RGB",
    "PREVIEW_BODY_RGB",
    "PREVIEW_JOIN_RGB",
    "STATION_RGB",
    "belief_update",
    "color",
    "deletion",
    "path_update",
    "ring",
    "station_update",
]
