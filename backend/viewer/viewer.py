"""The console's 3D view: the vehicle, its paths and its track, drawn with viser.

Frames: everything outside the ``viewer*`` modules works in NED; :mod:`backend.viewer.draw`
converts to viser's view frame (ENU, ``+z`` up) with :func:`ned_to_view` and
:func:`attitude_to_view_wxyz`, and nothing else does.

The viewer is display only. viser's port has no authentication, so nothing here may transmit
to the vehicle or call back into the console: the scene has no clickable nodes and the GUI
panel holds only a legend (no buttons, no inputs, no callbacks).

Two kinds of scene. The **shared** scene (``server.scene``, every page sees it) holds the
vehicle's state, the same for all::

    /surface/grid            horizontal grid at the surface (1 m cells, 10 m sections)
    /scale/axes, /scale/north, /scale/east      north and east arrows from the origin, "N"/"E"
    /scale/depth, /scale/depth_05m ...           depth scale below the origin, labelled every 5 m
    /active/path, /active/waypoints, /active/label   the path the vehicle is flying
    /vehicle, /vehicle/hull, /vehicle/nose, /vehicle/info   the vehicle model (hidden until
                                                            the first pose)
    /track/chunk_0000 ..., /track/live, /track/tail the vehicle's track (backend.viewer.track)
    /belief/ring, /belief/point, /belief/label   the believed position when it is not the
                                                 last fix (backend.viewer.belief)

Each page's **own** view (a viser client, :mod:`backend.viewer.views`) holds what that page
asked for: its preview (``/preview/...``), mission script preview (``/script/...``) and replay
(``/replay/...``), see :mod:`backend.viewer.paths`; a page's labels are decluttered against
each other and the shared ones (:mod:`backend.viewer.labels`). Methods taking a ``view_id``
draw in that page's view only; ``None`` (an API call without ``X-Nemesys-View``) draws nothing.

All public methods are thread-safe (one re-entrant lock) and may be called from the asyncio
loop or from worker threads; viser sends from its own thread.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Sequence
from pathlib import Path as FilePath
from types import TracebackType

import numpy.typing as npt
import viser

from backend.viewer.client_page import client_html_path
from backend.viewer.draw import (
    ACTIVE_RGB,
    PREVIEW_BODY_RGB,
    PREVIEW_JOIN_RGB,
    REPLAY_COMMAND_RGB,
    REPLAY_RGB,
    SCRIPT_RGB,
    TRACK_RGB,
    WAYPOINT_M,
    Canvas,
    FloatArray,
    attitude_to_view_wxyz,
    columns,
    ned_to_view,
)
from backend.viewer.labels import LabelSpec, declutter
from backend.viewer.paths import preview_drawing, replay_at_drawing, replay_drawing, script_drawing
from backend.viewer.scene import VEHICLE_LABEL_UP_M, setup_scene
from backend.viewer.track import Track
from backend.viewer.views import Views

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
    "ned_to_view",
]


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
        self._lock = threading.RLock()
        self._stopped = False
        self._pose_ned: tuple[float, float, float] | None = None
        self._pose_info = ""
        #: the shared scene's labels (view frame, m): static ones, then the active path's
        self._static_labels: dict[str, tuple[float, float, float]] = {}
        self._active_label: tuple[float, float, float] | None = None

        self._server = viser.ViserServer(
            host=host, port=port, label="NemeSys console", verbose=False
        )
        try:
            self._shared = Canvas(self._server.scene)
            self._track = Track(
                self._shared,
                max_points=max_track_points,
                min_step_m=track_min_step_m,
                redraw_interval_s=track_redraw_interval_s,
                chunk_segments=track_chunk_segments,
            )
            self._static_labels = setup_scene(self._server, self._shared)
            self._views = Views(self._server, self._lock, self._reserved_labels)
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
        """``ws://host:port``: the ``websocket=`` parameter for
        :func:`~backend.viewer.client_page.client_html_path`
        (a page appends ``/view/<its view id>``)."""
        return f"ws://{self._host}:{self.port}"

    @staticmethod
    def client_html_path() -> FilePath:
        """See :func:`backend.viewer.client_page.client_html_path`."""
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
        """The handle of shared scene node ``name`` (e.g. ``"/active/path"``), or None."""
        with self._lock:
            return self._shared.nodes.get(name)

    def node_names(self, prefix: str = "/") -> list[str]:
        """Names of the shared scene's nodes under ``prefix``, sorted."""
        with self._lock:
            return self._shared.node_names(prefix)

    def view_ids(self) -> list[str]:
        """The ids of the views whose page is connected, sorted."""
        return self._views.ids()

    def view_node(self, view_id: str, name: str) -> viser.SceneNodeHandle | None:
        """The handle of node ``name`` in view ``view_id``'s own scene, or None."""
        return self._views.node(view_id, name)

    def view_node_names(self, view_id: str, prefix: str = "/") -> list[str]:
        """Names of the nodes in view ``view_id``'s own scene under ``prefix``, sorted."""
        return self._views.node_names(view_id, prefix)

    def view_labels(self, view_id: str) -> list[LabelSpec]:
        """The labels drawn in view ``view_id``'s own scene (``shown``: the text drawn)."""
        return self._views.labels(view_id)

    def shared_label_positions(self) -> dict[str, tuple[float, float, float]]:
        """The shared scene's labels now, by node name (view frame, m; the vehicle's where
        it is)."""
        with self._lock:
            out = dict(self._static_labels)
            if self._active_label is not None:
                out["/active/label"] = self._active_label
            if self._pose_ned is not None:
                p = ned_to_view(*self._pose_ned)
                out["/vehicle/info"] = (float(p[0]), float(p[1]), p[2] + VEHICLE_LABEL_UP_M)
            for name in self._shared.node_names("/fleet/"):  # a fleet's vehicles' labels
                node = self._shared.nodes[name]
                if isinstance(node, viser.LabelHandle):
                    x, y, z = (float(v) for v in node.position)
                    out[name] = (x, y, z)
            return out

    def _reserved_labels(self) -> list[tuple[float, float, float]]:
        return list(self.shared_label_positions().values())

    @property
    def track_ned_m(self) -> FloatArray:
        """The kept track points, shape ``(N, 3)``, NED metres (a copy)."""
        with self._lock:
            return self._track.ned_m

    # --- the shared scene: the active path ----------------------------------------------------

    def show_active(
        self, xs: npt.ArrayLike, ys: npt.ArrayLike, zs: npt.ArrayLike, label: str = "active"
    ) -> None:
        """Draw the vehicle's active path (NED metres) in :data:`ACTIVE_RGB` (replaces it),
        in the shared scene; its label keeps clear of the compass and depth scale."""
        x, y, z = columns(xs, ys, zs, "active path")
        view = ned_to_view(x, y, z)
        text = f"{label} (depth {float(z.min()):.1f}-{float(z.max()):.1f} m)"
        with self._lock, self._server.atomic():
            c = self._shared
            c.group("/active")
            c.polyline("/active/path", view, ACTIVE_RGB)
            c.points("/active/waypoints", view, ACTIVE_RGB, WAYPOINT_M)
            placed = declutter(
                [LabelSpec.at("/active/label", text, view[-1])], list(self._static_labels.values())
            )
            self._active_label = placed[0].position if placed else None
            if placed:
                c.label("/active/label", text, placed[0].position)
            self._views.relabel()

    def draw_shared(self, draw: Callable[[Canvas], None]) -> None:
        """Draw on the shared scene, atomically (the believed position:
        :mod:`backend.viewer.belief`)."""
        with self._lock, self._server.atomic():
            if not self._stopped:
                draw(self._shared)

    def clear_active(self) -> None:
        """Remove the active path."""
        with self._lock:
            self._shared.remove_group("/active")
            self._active_label = None
            self._views.relabel()

    # --- a page's own view: preview, script, replay ---------------------------------------

    def show_preview(
        self,
        view_id: str | None,
        xs: npt.ArrayLike,
        ys: npt.ArrayLike,
        zs: npt.ArrayLike,
        body_start: int = 0,
        label: str = "preview",
    ) -> None:
        """Draw a previewed path (NED metres) in view ``view_id`` (replaces its preview); see
        :func:`backend.viewer.paths.preview_drawing`.

        Raises:
            ValueError: empty or unequal columns, non-finite values, ``body_start`` out of
                range.
        """
        drawing = preview_drawing(xs, ys, zs, body_start, label)
        if view_id is not None:
            self._views.show(view_id, "/preview", drawing)

    def clear_preview(self, view_id: str) -> bool:
        """Remove view ``view_id``'s preview (False: there was none)."""
        return self._views.clear(view_id, "/preview")

    def show_script(
        self,
        view_id: str | None,
        xs: npt.ArrayLike,
        ys: npt.ArrayLike,
        zs: npt.ArrayLike,
        step_labels: Sequence[tuple[int, str]] = (),
    ) -> None:
        """Draw a mission script's path in view ``view_id`` (replaces it); see
        :func:`backend.viewer.paths.script_drawing`."""
        drawing = script_drawing(xs, ys, zs, step_labels)
        if view_id is not None:
            self._views.show(view_id, "/script", drawing)

    def clear_script(self, view_id: str) -> bool:
        """Remove view ``view_id``'s mission script preview (False: there was none)."""
        return self._views.clear(view_id, "/script")

    def show_replay(
        self,
        view_id: str | None,
        track: Sequence[tuple[float, float, float, float, float]],
        commands: Sequence[tuple[float, float, float, float, str]] = (),
    ) -> None:
        """Draw a past dive in view ``view_id`` (replaces the previous one); see
        :func:`backend.viewer.paths.replay_drawing` (at most ``max_track_points``)."""
        drawing = replay_drawing(track, commands, max_points=self._max_track_points)
        if view_id is not None:
            self._views.show(view_id, "/replay", drawing)

    def show_replay_at(
        self, view_id: str, x_m: float, y_m: float, z_m: float, heading_deg: float
    ) -> None:
        """Draw the replayed vehicle at the slider's time in view ``view_id`` (replaces it);
        see :func:`backend.viewer.paths.replay_at_drawing`."""
        self._views.show(view_id, "/replay_at", replay_at_drawing(x_m, y_m, z_m, heading_deg))

    def clear_replay(self, view_id: str) -> bool:
        """Remove view ``view_id``'s replay and its slider's marker (False: there was none)."""
        marker = self._views.clear(view_id, "/replay_at")
        return self._views.clear(view_id, "/replay") or marker

    # --- the shared scene: vehicle and track --------------------------------------------

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
                vehicle = self._shared.nodes["/vehicle"]
                vehicle.position = view
                vehicle.wxyz = wxyz
                vehicle.visible = True
                self._pose_ned = (x_m, y_m, z_m)
                self._pose_info = f"t {t_s:.0f} s, depth {z_m:.1f} m, hdg {heading_deg % 360:.0f}"
                if self._track.add((x_m, y_m, z_m), self._pose_ned):
                    self._show_info()

    def _show_info(self) -> None:
        info = self._shared.nodes.get("/vehicle/info")
        if isinstance(info, viser.LabelHandle) and info.text != self._pose_info:
            info.text = self._pose_info

    def flush_track(self) -> None:
        """Redraw the track line now (normally throttled to ``track_redraw_interval_s``)."""
        with self._lock, self._server.atomic():
            self._track.redraw()
            self._track.tail(self._pose_ned)
            self._show_info()

    def reset_track(self) -> None:
        """Forget and remove the vehicle's track (the vehicle stays where it is)."""
        with self._lock:
            self._track.reset()
