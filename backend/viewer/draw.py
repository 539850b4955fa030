"""Drawing for the 3D view: the NED -> view frame conversion, colours, and :class:`Canvas`.

Everything outside the ``viewer*`` modules works in NED: ``x`` north, ``y`` east, ``z`` down
(depth, metres, >= 0 below the surface). viser's scene is right-handed with ``+z`` up, so the
view frame is ENU: view ``x`` = east, view ``y`` = north, view ``z`` = up = ``-depth``. Two
functions do all of the conversion:

* :func:`ned_to_view` for positions (scalars or numpy arrays);
* :func:`attitude_to_view_wxyz` for the vehicle's heading and roll (a quaternion, ``wxyz``).

A :class:`Canvas` draws through one viser scene, the shared one (``server.scene``: every page
sees it) or one page's own (``client.scene``), and keeps the handles of what it drew by name.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Final, TypeVar

import numpy as np
import numpy.typing as npt
import viser

Rgb = tuple[int, int, int]
FloatArray = npt.NDArray[np.float64]
_H = TypeVar("_H", bound=viser.SceneNodeHandle)

#: Previewed path: the join from the vehicle to the pattern (``[0 .. body_start]``).
PREVIEW_JOIN_RGB: Final[Rgb] = (255, 150, 40)
#: Previewed path: the pattern body (``[body_start ..]``).
PREVIEW_BODY_RGB: Final[Rgb] = (40, 200, 255)
#: The path the vehicle is flying.
ACTIVE_RGB: Final[Rgb] = (70, 220, 110)
#: The vehicle's live track.
TRACK_RGB: Final[Rgb] = (255, 235, 90)
#: A past dive's track, and its command markers.
REPLAY_RGB: Final[Rgb] = (220, 90, 220)
REPLAY_COMMAND_RGB: Final[Rgb] = (255, 80, 80)
#: The replayed vehicle at the time slider's time.
REPLAY_AT_RGB: Final[Rgb] = (255, 255, 255)
#: A mission script preview.
SCRIPT_RGB: Final[Rgb] = (165, 145, 255)
HULL_RGB: Final[Rgb] = (255, 200, 0)
NOSE_RGB: Final[Rgb] = (255, 60, 60)
DROP_RGB: Final[Rgb] = (125, 125, 145)
NORTH_RGB: Final[Rgb] = (230, 80, 80)
EAST_RGB: Final[Rgb] = (80, 200, 80)
SCALE_RGB: Final[Rgb] = (160, 160, 175)

#: Line thickness of paths and tracks (screen pixels).
PATH_PX: Final = 3.0
#: Waypoint marker size (m).
WAYPOINT_M: Final = 0.08
#: At most this many vertical drop lines per path.
MAX_DROPS: Final = 24


def ned_to_view(x_m: npt.ArrayLike, y_m: npt.ArrayLike, z_m: npt.ArrayLike) -> FloatArray:
    """NED metres to the view frame (east, north, up) = ``(y, x, -z)``.

    Args:
        x_m: north (m), a scalar or an array.
        y_m: east (m), same shape as ``x_m``.
        z_m: depth (m, positive down), same shape as ``x_m``.

    Returns:
        Shape ``(..., 3)`` (``(3,)`` for scalars): view ``x`` = east, ``y`` = north,
        ``z`` = up = ``-depth``. float64; viser casts to float32 when drawing.
    """
    x = np.asarray(x_m, dtype=np.float64)
    y = np.asarray(y_m, dtype=np.float64)
    z = np.asarray(z_m, dtype=np.float64)
    # `+ 0.0` turns the -0.0 of a surface point into 0.0
    return np.stack(np.broadcast_arrays(y, x, -z + 0.0), axis=-1)


def attitude_to_view_wxyz(
    heading_deg: float, roll_deg: float = 0.0
) -> tuple[float, float, float, float]:
    """Vehicle attitude to a view-frame quaternion ``(w, x, y, z)`` for its scene node.

    The vehicle model is built in a body frame with ``+x`` forward (the nose), ``+y`` to
    port, ``+z`` up. The returned rotation takes that body frame to the view frame (ENU):

    * heading ``psi`` is degrees clockwise from north (NED yaw), so the nose points along
      view ``(sin psi, cos psi, 0)``: a yaw of ``90 - psi`` degrees about view ``+z``;
    * roll ``phi`` is NED roll, positive with the starboard side down: a rotation by ``phi``
      about the body's ``+x`` (forward) axis, applied before the yaw.

    ``q = q_yaw(90 deg - psi) * q_roll(phi)``. Pitch is not shown (poses carry none).
    """
    yaw = math.radians(90.0 - heading_deg) / 2.0
    roll = math.radians(roll_deg) / 2.0
    cy, sy = math.cos(yaw), math.sin(yaw)
    cr, sr = math.cos(roll), math.sin(roll)
    return (cy * cr, cy * sr, sy * sr, sy * cr)


def segments(points: FloatArray) -> npt.NDArray[np.float32]:
    """Polyline points ``(N, 3)`` to line segments ``(N - 1, 2, 3)`` (float32)."""
    p = np.asarray(points, dtype=np.float32)
    return np.stack([p[:-1], p[1:]], axis=1)


def columns(
    xs: npt.ArrayLike, ys: npt.ArrayLike, zs: npt.ArrayLike, what: str
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Check NED waypoint columns: equal lengths, at least one point, all finite."""
    x = np.asarray(xs, dtype=np.float64).reshape(-1)
    y = np.asarray(ys, dtype=np.float64).reshape(-1)
    z = np.asarray(zs, dtype=np.float64).reshape(-1)
    if len(x) == 0 or len(y) != len(x) or len(z) != len(x):
        raise ValueError(f"{what}: xs, ys, zs must be non-empty and of equal length")
    if not (np.isfinite(x).all() and np.isfinite(y).all() and np.isfinite(z).all()):
        raise ValueError(f"{what}: waypoints must be finite numbers")
    return x, y, z


class Canvas:
    """Scene nodes drawn through one viser scene, kept by name (not thread-safe: the
    :class:`backend.viewer.viewer.Viewer` holds its lock around every use)."""

    def __init__(self, scene: viser.SceneApi) -> None:
        self.scene = scene
        self.nodes: dict[str, viser.SceneNodeHandle] = {}

    def node_names(self, prefix: str = "/") -> list[str]:
        """Names of the nodes under ``prefix``, sorted."""
        return sorted(n for n in self.nodes if n == prefix or n.startswith(prefix))

    def add(self, handle: _H) -> _H:
        self.nodes[handle.name] = handle
        return handle

    def group(self, name: str) -> None:
        """(Re)create an empty group frame ``name`` (removing what was under it)."""
        self.remove_group(name)
        self.add(self.scene.add_frame(name, show_axes=False))

    def remove_group(self, name: str) -> None:
        handle = self.nodes.pop(name, None)
        for child in [n for n in self.nodes if n.startswith(name + "/")]:
            del self.nodes[child]
        if handle is not None:
            handle.remove()  # removes the children too

    def remove(self, name: str) -> None:
        handle = self.nodes.pop(name, None)
        if handle is not None:
            handle.remove()

    def polyline(self, name: str, points: FloatArray, color: Rgb) -> None:
        if len(points) >= 2:
            self.lines(name, segments(points), color)

    def lines(self, name: str, segs: npt.NDArray[np.float32], color: Rgb) -> None:
        """Line segments ``name``, path thickness: drawn anew, or their points replaced
        when the node exists (only the points are resent)."""
        handle = self.nodes.get(name)
        if isinstance(handle, viser.LineSegmentsHandle):
            handle.points = segs
            return
        self.add(
            self.scene.add_line_segments(
                name, segs, color, thickness=PATH_PX, thickness_units="screen"
            )
        )

    def points(
        self, name: str, points: FloatArray, color: Rgb | npt.NDArray[np.uint8], size_m: float
    ) -> None:
        self.add(
            self.scene.add_point_cloud(
                name,
                np.asarray(points, dtype=np.float32),
                color,
                point_size=size_m,
                point_shape="circle",
                precision="float32",
            )
        )

    def label(self, name: str, text: str, position: npt.ArrayLike) -> None:
        self.add(
            self.scene.add_label(
                name, text, position=np.asarray(position, dtype=np.float64), anchor="bottom-left"
            )
        )

    def drops(
        self, name: str, x: FloatArray, y: FloatArray, z: FloatArray, always: Sequence[int]
    ) -> None:
        """Vertical lines from the surface down to waypoints (every k-th and ``always``)."""
        n = len(x)
        step = max(1, math.ceil(n / MAX_DROPS))
        idx = np.unique(np.concatenate([np.arange(0, n, step), np.asarray(always, dtype=int)]))
        idx = idx[np.abs(z[idx]) > 1e-3]
        if len(idx) == 0:
            return
        top = ned_to_view(x[idx], y[idx], np.zeros(len(idx)))
        bottom = ned_to_view(x[idx], y[idx], z[idx])
        self.add(
            self.scene.add_line_segments(
                name,
                np.stack([top, bottom], axis=1),
                DROP_RGB,
                thickness=1.0,
                thickness_units="screen",
            )
        )
