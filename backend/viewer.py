"""The console's 3D view: the vehicle, its paths and its track, drawn with viser.

Everything outside this module works in one frame, NED: ``x`` north, ``y`` east, ``z`` down
(depth, metres, >= 0 below the surface). viser's scene is right-handed with ``+z`` up, so this
module, and only this module, converts to the *view* frame ENU: view ``x`` = east, view
``y`` = north, view ``z`` = up = ``-depth``. Two functions do all of it:

* :func:`ned_to_view` for positions (scalars or numpy arrays);
* :func:`attitude_to_view_wxyz` for the vehicle's heading and roll (a quaternion, ``wxyz``).

The viewer is display only. viser's port has no authentication, so nothing here may transmit
to the vehicle or call back into the console: the scene has no clickable nodes and the GUI
panel holds only a legend (no buttons, no inputs, no callbacks).

Scene tree (viser node names)::

    /surface/grid            horizontal grid at the surface (1 m cells, 10 m sections)
    /scale/axes, /scale/north, /scale/east      north and east arrows from the origin, "N"/"E"
    /scale/depth, /scale/depth_05m ...           depth scale below the origin, labelled every 5 m
    /preview/join, /preview/body                 previewed path: join part and pattern body
    /preview/waypoints, /preview/drops           its waypoints and vertical drop lines to z = 0
    /preview/start, /preview/end, /preview/pattern   labels (start/end depth, depth range)
    /active/path, /active/waypoints, /active/label   the path the vehicle is flying
    /vehicle, /vehicle/hull, /vehicle/nose, /vehicle/info   the vehicle model (hidden until
                                                            the first pose)
    /track/chunk_0000 ..., /track/live, /track/tail the vehicle's track (see update_pose)
    /replay/track, /replay/commands, /replay/cmd_000 ...   a past dive and its commands
    /script/path, /script/steps, /script/step_000 ...      a mission script preview

All public methods are thread-safe (one re-entrant lock) and may be called from the asyncio
loop or from worker threads; viser sends from its own thread.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Sequence
from pathlib import Path as FilePath
from types import TracebackType
from typing import Final, TypeVar

import numpy as np
import numpy.typing as npt
import viser

__all__ = [
    "ACTIVE_RGB",
    "PREVIEW_BODY_RGB",
    "PREVIEW_JOIN_RGB",
    "REPLAY_COMMAND_RGB",
    "REPLAY_RGB",
    "SCRIPT_RGB",
    "TRACK_RGB",
    "Viewer",
    "attitude_to_view_wxyz",
    "client_html_path",
    "ned_to_view",
]

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
#: Vehicle hull size (m): length, beam, height.
HULL_M: Final = (0.6, 0.3, 0.25)
#: At most this many vertical drop lines per path.
MAX_DROPS: Final = 24
#: Depth scale below the origin: length and label spacing (m).
DEPTH_SCALE_M: Final = 20.0
DEPTH_TICK_M: Final = 5.0


def client_html_path() -> FilePath:
    """Path of viser's bundled client page (``viser/client/build/index.html``).

    Serve it same-origin (e.g. FastAPI ``FileResponse`` at ``/viewer``) and open it as
    ``/viewer?websocket=ws://<host>:<port>`` (see :attr:`Viewer.websocket_url`): only the
    websocket then goes to viser's port. It must come from the installed viser, whose server
    rejects clients of another version.
    """
    return FilePath(viser.__file__).resolve().parent / "client" / "build" / "index.html"


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


def _segments(points: FloatArray) -> npt.NDArray[np.float32]:
    """Polyline points ``(N, 3)`` to line segments ``(N - 1, 2, 3)`` (float32)."""
    p = np.asarray(points, dtype=np.float32)
    return np.stack([p[:-1], p[1:]], axis=1)


def _columns(
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


class Viewer:
    """A viser server showing the vehicle, its paths and its track (display only).

    Args:
        host: interface to bind; keep it ``127.0.0.1`` or the console's LAN interface
            (viser's port has no authentication).
        port: port to bind, 0 for one chosen by the OS; viser moves to the next free port
            if it is busy, so always read :attr:`port`.
        max_track_points: the track keeps at most this many points; when full, it is
            thinned to every second point (older parts end up coarser).
        track_min_step_m: a pose adds a track point only once the vehicle has moved more
            than this (m) from the last track point.
        track_redraw_interval_s: the track line is redrawn at most this often (s); between
            redraws a single segment joins the last drawn point to the vehicle.
        track_chunk_segments: the track is drawn in chunks of this many segments; full
            chunks are sent once, only the newest (live) chunk is resent on a redraw.
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 0,
        *,
        max_track_points: int = 20_000,
        track_min_step_m: float = 0.05,
        track_redraw_interval_s: float = 0.5,
        track_chunk_segments: int = 1000,
    ) -> None:
        if max_track_points < 4 or track_chunk_segments < 1:
            raise ValueError("max_track_points must be >= 4 and track_chunk_segments >= 1")
        self._host = host
        self._max_track_points = max_track_points
        self._track_min_step_m = track_min_step_m
        self._track_redraw_interval_s = track_redraw_interval_s
        self._track_chunk_segments = track_chunk_segments
        self._lock = threading.RLock()
        self._stopped = False
        self._nodes: dict[str, viser.SceneNodeHandle] = {}
        # track state (NED metres)
        self._track: list[tuple[float, float, float]] = []
        self._frozen_end = 0  # index of the last point of the frozen chunks
        self._chunks = 0
        self._drawn = 0  # number of track points the track line shows
        self._last_redraw_s = -math.inf
        self._pose_ned: tuple[float, float, float] | None = None
        self._pose_info = ""

        self._server = viser.ViserServer(
            host=host, port=port, label="NemeSys console", verbose=False
        )
        try:
            self._setup_scene()
        except BaseException:
            self._server.stop()
            raise

    # --- server ---------------------------------------------------------------------------

    @property
    def server(self) -> viser.ViserServer:
        """The underlying viser server (for tests and diagnostics; the viewer owns it)."""
        return self._server

    @property
    def port(self) -> int:
        """The port viser actually bound."""
        return self._server.get_port()

    @property
    def url(self) -> str:
        """``http://host:port``: viser's own page (it also serves the client)."""
        return f"http://{self._host}:{self.port}"

    @property
    def websocket_url(self) -> str:
        """``ws://host:port``: the ``websocket=`` parameter for :func:`client_html_path`."""
        return f"ws://{self._host}:{self.port}"

    @staticmethod
    def client_html_path() -> FilePath:
        """See the module-level :func:`client_html_path`."""
        return client_html_path()

    def stop(self) -> None:
        """Stop the server and its threads and free the port. Idempotent."""
        with self._lock:
            if self._stopped:
                return
            self._stopped = True
        self._server.stop()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()

    # --- scene lookup ---------------------------------------------------------------------

    def node(self, name: str) -> viser.SceneNodeHandle | None:
        """The handle of scene node ``name`` (e.g. ``"/preview/body"``), or None if absent."""
        with self._lock:
            return self._nodes.get(name)

    def node_names(self, prefix: str = "/") -> list[str]:
        """Names of the viewer's scene nodes under ``prefix``, sorted."""
        with self._lock:
            return sorted(n for n in self._nodes if n == prefix or n.startswith(prefix))

    @property
    def track_ned_m(self) -> FloatArray:
        """The kept track points, shape ``(N, 3)``, NED metres (a copy)."""
        with self._lock:
            return np.array(self._track, dtype=np.float64).reshape(-1, 3)

    # --- static scene ---------------------------------------------------------------------

    def _setup_scene(self) -> None:
        server = self._server
        server.gui.configure_theme(
            dark_mode=True, show_logo=False, show_share_button=False, control_width="small"
        )
        server.scene.set_up_direction("+z")
        # above and behind (south of) the origin, looking north-down at it; ~25 m away
        server.initial_camera.position = (0.0, -18.0, 17.0)
        server.initial_camera.look_at = (0.0, 0.0, 0.0)
        server.gui.add_markdown(
            "**NemeSys console** (display only)  \n"
            "orange: join, cyan: pattern (preview)  \n"
            "green: active path, yellow: track  \n"
            "magenta: replay, red: commands  \n"
            "violet: mission script  \n"
            "grid: surface, 1 m cells, 10 m sections"
        )
        # a small legend in the bottom-right corner, out of the way of the scene
        server.gui.main_panel.float(x=-10, y=-10, width=260, height=190)
        scene = server.scene
        with server.atomic():
            self._add(
                scene.add_grid(
                    "/surface/grid",
                    width=200.0,
                    height=200.0,
                    plane="xy",
                    cell_size=1.0,
                    section_size=10.0,
                    cell_color=(70, 75, 90),
                    section_color=(120, 130, 150),
                    infinite_grid=True,
                    fade_distance=200.0,
                    plane_color=(30, 80, 130),
                    plane_opacity=0.08,
                    shadow_opacity=0.0,
                )
            )
            axes = ned_to_view([0.0, 10.0, 0.0, 0.0], [0.0, 0.0, 0.0, 10.0], [0.0] * 4)
            colors = np.array([[NORTH_RGB] * 2, [EAST_RGB] * 2], dtype=np.uint8)
            self._add(
                scene.add_line_segments(
                    "/scale/axes",
                    axes.reshape(2, 2, 3),
                    colors,
                    thickness=2.0,
                    thickness_units="screen",
                )
            )
            north = ned_to_view(11.0, 0.0, 0.0)
            east = ned_to_view(0.0, 11.0, 0.0)
            self._add(scene.add_label("/scale/north", "N", position=north, anchor="center-center"))
            self._add(scene.add_label("/scale/east", "E", position=east, anchor="center-center"))
            depth = ned_to_view([0.0, 0.0], [0.0, 0.0], [0.0, DEPTH_SCALE_M])
            ticks = [depth]
            marks = np.arange(DEPTH_TICK_M, DEPTH_SCALE_M + 1e-9, DEPTH_TICK_M)
            for d in marks:
                ticks.append(ned_to_view([0.0, 0.0], [-0.5, 0.5], [d, d]))
                self._add(
                    scene.add_label(
                        f"/scale/depth_{int(d):02d}m",
                        f"{d:g} m",
                        position=ned_to_view(0.0, 0.6, d),
                        anchor="center-left",
                        font_screen_scale=0.8,
                    )
                )
            self._add(
                scene.add_line_segments(
                    "/scale/depth",
                    np.stack(ticks),
                    SCALE_RGB,
                    thickness=1.5,
                    thickness_units="screen",
                )
            )
            self._add(scene.add_frame("/vehicle", show_axes=False, visible=False))
            self._add(
                scene.add_box(
                    "/vehicle/hull", HULL_RGB, HULL_M, cast_shadow=False, receive_shadow=False
                )
            )
            nose = np.array([[[HULL_M[0] / 2, 0.0, 0.0], [HULL_M[0] / 2 + 0.5, 0.0, 0.0]]])
            self._add(
                scene.add_arrows(
                    "/vehicle/nose",
                    nose,
                    NOSE_RGB,
                    shaft_radius=0.025,
                    head_radius=0.06,
                    head_length=0.15,
                )
            )
            self._add(
                scene.add_label(
                    "/vehicle/info",
                    "",
                    position=(0.0, 0.0, 0.45),
                    anchor="bottom-center",
                    font_screen_scale=0.8,
                )
            )

    # --- node bookkeeping -----------------------------------------------------------------

    def _add(self, handle: _H) -> _H:
        self._nodes[handle.name] = handle
        return handle

    def _group(self, name: str) -> None:
        """(Re)create an empty group frame ``name`` (removing what was under it)."""
        self._remove_group(name)
        self._add(self._server.scene.add_frame(name, show_axes=False))

    def _remove_group(self, name: str) -> None:
        handle = self._nodes.pop(name, None)
        for child in [n for n in self._nodes if n.startswith(name + "/")]:
            del self._nodes[child]
        if handle is not None:
            handle.remove()  # removes the children too

    def _remove(self, name: str) -> None:
        handle = self._nodes.pop(name, None)
        if handle is not None:
            handle.remove()

    def _polyline(self, name: str, points: FloatArray, color: Rgb) -> None:
        if len(points) >= 2:
            self._lines(name, _segments(points), color)

    def _lines(self, name: str, segments: npt.NDArray[np.float32], color: Rgb) -> None:
        """Line segments ``name``, path thickness: drawn anew, or their points replaced
        when the node exists (only the points are resent)."""
        handle = self._nodes.get(name)
        if isinstance(handle, viser.LineSegmentsHandle):
            handle.points = segments
            return
        self._add(
            self._server.scene.add_line_segments(
                name, segments, color, thickness=PATH_PX, thickness_units="screen"
            )
        )

    def _points(
        self, name: str, points: FloatArray, color: Rgb | npt.NDArray[np.uint8], size_m: float
    ) -> None:
        self._add(
            self._server.scene.add_point_cloud(
                name,
                np.asarray(points, dtype=np.float32),
                color,
                point_size=size_m,
                point_shape="circle",
                precision="float32",
            )
        )

    def _label(self, name: str, text: str, position: FloatArray) -> None:
        self._add(self._server.scene.add_label(name, text, position=position, anchor="bottom-left"))

    # --- paths ----------------------------------------------------------------------------

    def show_preview(
        self,
        xs: npt.ArrayLike,
        ys: npt.ArrayLike,
        zs: npt.ArrayLike,
        body_start: int = 0,
        label: str = "preview",
    ) -> None:
        """Draw a previewed path (NED metres; replaces the previous preview).

        The join ``[0 .. body_start]`` is drawn in :data:`PREVIEW_JOIN_RGB`, the pattern
        body ``[body_start ..]`` in :data:`PREVIEW_BODY_RGB`; waypoints are a float32 point
        cloud; vertical lines drop from the surface to some waypoints (at most
        :data:`MAX_DROPS`, always the first, ``body_start`` and the last); labels give the
        start and end depth and the depth range.

        Raises:
            ValueError: empty or unequal columns, non-finite values, ``body_start`` out of
                range.
        """
        x, y, z = _columns(xs, ys, zs, "preview")
        n = len(x)
        if not 0 <= body_start < n:
            raise ValueError(f"preview: body_start must index a waypoint, got {body_start}")
        view = ned_to_view(x, y, z)
        with self._lock, self._server.atomic():
            self._group("/preview")
            self._polyline("/preview/join", view[: body_start + 1], PREVIEW_JOIN_RGB)
            self._polyline("/preview/body", view[body_start:], PREVIEW_BODY_RGB)
            colors = np.empty((n, 3), dtype=np.uint8)
            colors[:body_start] = PREVIEW_JOIN_RGB
            colors[body_start:] = PREVIEW_BODY_RGB
            self._points("/preview/waypoints", view, colors, WAYPOINT_M)
            self._drops("/preview/drops", x, y, z, (0, body_start, n - 1))
            z_lo, z_hi = float(z.min()), float(z.max())
            self._label("/preview/start", f"{label} start, depth {z[0]:.1f} m", view[0])
            if n > 1:
                self._label(
                    "/preview/end",
                    f"{label} end, depth {z[-1]:.1f} m (range {z_lo:.1f}-{z_hi:.1f} m)",
                    view[-1],
                )
            if 0 < body_start < n - 1:
                self._label(
                    "/preview/pattern", f"pattern, depth {z[body_start]:.1f} m", view[body_start]
                )

    def clear_preview(self) -> None:
        """Remove the previewed path."""
        with self._lock:
            self._remove_group("/preview")

    def show_active(
        self, xs: npt.ArrayLike, ys: npt.ArrayLike, zs: npt.ArrayLike, label: str = "active"
    ) -> None:
        """Draw the vehicle's active path (NED metres) in :data:`ACTIVE_RGB` (replaces it)."""
        x, y, z = _columns(xs, ys, zs, "active path")
        view = ned_to_view(x, y, z)
        with self._lock, self._server.atomic():
            self._group("/active")
            self._polyline("/active/path", view, ACTIVE_RGB)
            self._points("/active/waypoints", view, ACTIVE_RGB, WAYPOINT_M)
            self._label(
                "/active/label",
                f"{label} (depth {float(z.min()):.1f}-{float(z.max()):.1f} m)",
                view[-1],
            )

    def clear_active(self) -> None:
        """Remove the active path."""
        with self._lock:
            self._remove_group("/active")

    def show_script(
        self,
        xs: npt.ArrayLike,
        ys: npt.ArrayLike,
        zs: npt.ArrayLike,
        step_labels: Sequence[tuple[int, str]] = (),
    ) -> None:
        """Draw a mission script's path (NED metres) in :data:`SCRIPT_RGB` (replaces it).

        Args:
            step_labels: ``(waypoint index, text)`` for each step's start; each gets a
                marker and a label.
        """
        x, y, z = _columns(xs, ys, zs, "script")
        n = len(x)
        for i, _ in step_labels:
            if not 0 <= i < n:
                raise ValueError(f"script: step start {i} does not index a waypoint")
        view = ned_to_view(x, y, z)
        with self._lock, self._server.atomic():
            self._group("/script")
            self._polyline("/script/path", view, SCRIPT_RGB)
            self._drops("/script/drops", x, y, z, (0, n - 1, *(i for i, _ in step_labels)))
            if step_labels:
                starts = [i for i, _ in step_labels]
                self._points("/script/steps", view[starts], SCRIPT_RGB, WAYPOINT_M * 2)
                for k, (i, text) in enumerate(step_labels):
                    self._label(f"/script/step_{k:03d}", f"{text} ({z[i]:.1f} m)", view[i])

    def clear_script(self) -> None:
        """Remove the mission script preview."""
        with self._lock:
            self._remove_group("/script")

    def _drops(
        self,
        name: str,
        x: FloatArray,
        y: FloatArray,
        z: FloatArray,
        always: Sequence[int],
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
        self._add(
            self._server.scene.add_line_segments(
                name,
                np.stack([top, bottom], axis=1),
                DROP_RGB,
                thickness=1.0,
                thickness_units="screen",
            )
        )

    # --- vehicle and track ----------------------------------------------------------------

    def update_pose(
        self,
        t_s: float,
        x_m: float,
        y_m: float,
        z_m: float,
        roll_deg: float,
        heading_deg: float,
    ) -> None:
        """Move the vehicle model to a pose (NED metres, degrees) and extend the track.

        Cheap enough for 10-20 Hz: the vehicle moves in one atomic update; a track point is
        added only when the vehicle has moved more than ``track_min_step_m``; the track line
        is redrawn at most every ``track_redraw_interval_s`` (only its live chunk of up to
        ``track_chunk_segments`` segments is resent), and a single tail segment joins its
        last drawn point to the vehicle in between. Non-finite poses are ignored.
        """
        values = (t_s, x_m, y_m, z_m, roll_deg, heading_deg)
        if not all(math.isfinite(v) for v in values):
            return
        view = ned_to_view(x_m, y_m, z_m)
        wxyz = attitude_to_view_wxyz(heading_deg, roll_deg)
        with self._lock:
            if self._stopped:
                return
            with self._server.atomic():
                vehicle = self._nodes["/vehicle"]
                vehicle.position = view
                vehicle.wxyz = wxyz
                vehicle.visible = True
                self._pose_ned = (x_m, y_m, z_m)
                self._pose_info = f"t {t_s:.0f} s, depth {z_m:.1f} m, hdg {heading_deg % 360:.0f}"
                self._append_track((x_m, y_m, z_m))
                if time.monotonic() - self._last_redraw_s >= self._track_redraw_interval_s:
                    self._redraw_track()
                self._draw_tail()

    def flush_track(self) -> None:
        """Redraw the track line now (normally throttled to ``track_redraw_interval_s``)."""
        with self._lock, self._server.atomic():
            self._redraw_track()
            self._draw_tail()

    def reset_track(self) -> None:
        """Forget and remove the vehicle's track (the vehicle stays where it is)."""
        with self._lock:
            self._remove_group("/track")
            self._track.clear()
            self._undraw_track()

    def _undraw_track(self) -> None:
        """Nothing of the track counts as drawn: the next redraw draws it all."""
        self._frozen_end = 0
        self._chunks = 0
        self._drawn = 0
        self._last_redraw_s = -math.inf

    def _append_track(self, p: tuple[float, float, float]) -> None:
        track = self._track
        if track:
            last = track[-1]
            d2 = (p[0] - last[0]) ** 2 + (p[1] - last[1]) ** 2 + (p[2] - last[2]) ** 2
            if d2 <= self._track_min_step_m**2:
                return
        track.append(p)
        if len(track) > self._max_track_points:
            # thin to every second point, keeping the newest; frozen chunks are redrawn
            self._track = [*track[-2::-2][::-1], track[-1]]
            for name in self.node_names("/track/chunk_"):
                self._remove(name)
            self._undraw_track()

    def _redraw_track(self) -> None:
        track = self._track
        self._last_redraw_s = time.monotonic()
        info = self._nodes.get("/vehicle/info")
        if isinstance(info, viser.LabelHandle):
            info.text = self._pose_info
        if not track:
            return
        if "/track" not in self._nodes:
            self._group("/track")
        # freeze full chunks: drawn once, never resent
        while len(track) - 1 - self._frozen_end >= self._track_chunk_segments:
            end = self._frozen_end + self._track_chunk_segments
            chunk = np.array(track[self._frozen_end : end + 1])
            self._polyline(
                f"/track/chunk_{self._chunks:04d}",
                ned_to_view(chunk[:, 0], chunk[:, 1], chunk[:, 2]),
                TRACK_RGB,
            )
            self._chunks += 1
            self._frozen_end = end
        live = np.array(track[self._frozen_end :])
        self._drawn = len(track)
        if len(live) < 2:
            self._remove("/track/live")
            return
        self._polyline("/track/live", ned_to_view(live[:, 0], live[:, 1], live[:, 2]), TRACK_RGB)

    def _draw_tail(self) -> None:
        """One segment from the last drawn track point to the vehicle."""
        if self._pose_ned is None or self._drawn == 0:
            return
        a = self._track[self._drawn - 1]
        b = self._pose_ned
        self._polyline(
            "/track/tail", ned_to_view([a[0], b[0]], [a[1], b[1]], [a[2], b[2]]), TRACK_RGB
        )

    # --- replay ---------------------------------------------------------------------------

    def show_replay(
        self,
        track: Sequence[tuple[float, float, float, float, float]],
        commands: Sequence[tuple[float, float, float, float, str]] = (),
    ) -> None:
        """Draw a past dive (replaces the previous one).

        Args:
            track: ``(t_s, x_m, y_m, z_m, heading_deg)`` samples in time order (NED); drawn
                in :data:`REPLAY_RGB`, subsampled evenly to at most ``max_track_points``
                (first and last kept). The heading is not drawn.
            commands: ``(t_s, x_m, y_m, z_m, label)`` where a command was acknowledged;
                each gets a marker in :data:`REPLAY_COMMAND_RGB` and a label
                ``"<label> @ <t> s"``.
        """
        samples = np.array([row[1:4] for row in track], dtype=np.float64).reshape(-1, 3)
        if not np.isfinite(samples).all():
            raise ValueError("replay: track positions must be finite numbers")
        if len(samples) > self._max_track_points:
            keep = np.linspace(0, len(samples) - 1, self._max_track_points).round().astype(int)
            samples = samples[np.unique(keep)]
        cmd = np.array([row[1:4] for row in commands], dtype=np.float64).reshape(-1, 3)
        if not np.isfinite(cmd).all():
            raise ValueError("replay: command positions must be finite numbers")
        with self._lock, self._server.atomic():
            self._group("/replay")
            if len(samples):
                view = ned_to_view(samples[:, 0], samples[:, 1], samples[:, 2])
                self._polyline("/replay/track", view, REPLAY_RGB)
                t0, t1 = track[0][0], track[-1][0]
                self._label("/replay/start", f"replay start, {t0:.0f} s", view[0])
                self._label("/replay/end", f"replay end, {t1:.0f} s", view[-1])
            if len(cmd):
                view = ned_to_view(cmd[:, 0], cmd[:, 1], cmd[:, 2])
                self._points("/replay/commands", view, REPLAY_COMMAND_RGB, WAYPOINT_M * 2.5)
                for k, row in enumerate(commands):
                    self._label(f"/replay/cmd_{k:03d}", f"{row[4]} @ {row[0]:.0f} s", view[k])

    def clear_replay(self) -> None:
        """Remove the replayed dive."""
        with self._lock:
            self._remove_group("/replay")
