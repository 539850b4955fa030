"""Per-page views: each page's preview, script preview and replay, drawn in its own 3D view.

A page makes a random view id when it loads and opens viser's client with the websocket URL
``ws://host:port/view/<id>``; it sends the same id as ``X-Nemesys-View`` on its API calls.
viser gives the connection a :class:`viser.ClientHandle` whose ``scene`` only that page sees;
:class:`Views` keeps view id -> client and draws the page's drawings there. The vehicle, its
track and its active path stay in the shared scene (the vehicle's state, the same for all).

A drawing for a view whose page has not connected yet (its 3D view still loading) is kept, at
most :data:`MAX_PENDING_VIEWS` of them for :data:`PENDING_TTL_S`, and drawn when it connects.
A view whose page disconnects is dropped with everything drawn in it.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Final

import viser

from backend.viewer.draw import Canvas
from backend.viewer.ids import view_id_from_path
from backend.viewer.labels import LabelSpec, declutter
from backend.viewer.paths import Drawing

logger = logging.getLogger("backend.viewer.viewer")

#: The per-view groups, in the order their labels are placed (first: kept when they clash).
GROUPS: Final = ("/preview", "/script", "/replay", "/replay_at")
#: Views drawn for before their page connected: at most this many, kept this long (s).
MAX_PENDING_VIEWS: Final = 32
PENDING_TTL_S: Final = 120.0


class ViserInternalsChangedError(RuntimeError):
    """viser no longer keeps the raw websocket connections where this module reads them."""


def websocket_path(server: viser.ViserServer, client_id: int) -> str | None:
    """The path of the websocket URL client ``client_id`` connected with (e.g.
    ``/view/<id>``), or None when that connection is gone.

    viser 1.1.1 has no public API for it: this reads the private
    ``server._websock_server._live_connections[client_id].request.path`` (a
    ``websockets`` ``ServerConnection``). This function is the only place that does.

    Raises:
        ViserInternalsChangedError: those attributes are not there any more.
    """
    infra = getattr(server, "_websock_server", None)
    live = getattr(infra, "_live_connections", None)
    if not isinstance(live, dict):
        raise ViserInternalsChangedError(
            f"viser {viser.__version__}: no _websock_server._live_connections; "
            "backend/viewer/views.py:websocket_path must be adapted"
        )
    connection = live.get(client_id)
    if connection is None:
        return None
    path = getattr(getattr(connection, "request", None), "path", None)
    if not isinstance(path, str):
        raise ViserInternalsChangedError(
            f"viser {viser.__version__}: a live connection has no request.path; "
            "backend/viewer/views.py:websocket_path must be adapted"
        )
    return path


@dataclass
class View:
    """One page's view: its viser client (None until it connects) and its drawings."""

    id: str
    client: viser.ClientHandle | None = None
    canvas: Canvas | None = None
    drawings: dict[str, Drawing] = field(default_factory=dict)
    labels: dict[str, LabelSpec] = field(default_factory=dict)  # placed, by node name
    specs: dict[str, list[LabelSpec]] = field(default_factory=dict)  # wanted, by group
    touched_s: float = field(default_factory=time.monotonic)


class Views:
    """View id -> :class:`View`, fed by viser's client connect and disconnect callbacks.

    Args:
        server: the viser server whose clients are the views.
        lock: the viewer's lock, held around every change.
        reserved: the shared scene's label anchors now (view frame, m): a page's labels keep
            clear of them.
    """

    def __init__(
        self,
        server: viser.ViserServer,
        lock: threading.RLock,
        reserved: Callable[[], Sequence[tuple[float, float, float]]],
    ) -> None:
        self._server = server
        self._lock = lock
        self._reserved = reserved
        self._views: dict[str, View] = {}
        server.on_client_connect(self._connect)
        server.on_client_disconnect(self._disconnect)

    # --- connections ----------------------------------------------------------------------

    def _connect(self, client: viser.ClientHandle) -> None:
        try:
            view_id = view_id_from_path(websocket_path(self._server, client.client_id))
        except ViserInternalsChangedError as err:
            logger.error("per-page 3D views are off: %s", err)
            return
        if view_id is None:
            return  # viser's page opened without a view: it sees the shared scene only
        with self._lock:
            if client.client_id not in self._server.get_clients():
                return  # gone again before this callback ran
            view = self._views.get(view_id)
            if view is None:
                view = self._views[view_id] = View(view_id)
            view.client = client
            view.canvas = Canvas(client.scene)
            view.labels = {}
            view.touched_s = time.monotonic()
            with client.atomic():
                for group in GROUPS:
                    if group in view.drawings:
                        view.specs[group] = view.drawings[group](view.canvas)
                self._place_labels(view)

    def _disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            for view_id, view in list(self._views.items()):
                if view.client is not None and view.client.client_id == client.client_id:
                    del self._views[view_id]

    def _prune(self) -> None:
        """Forget views never connected that are too old or too many."""
        now = time.monotonic()
        pending = [v for v in self._views.values() if v.client is None]
        pending.sort(key=lambda v: v.touched_s)
        excess = len(pending) - MAX_PENDING_VIEWS
        for k, view in enumerate(pending):
            if k < excess or now - view.touched_s > PENDING_TTL_S:
                del self._views[view.id]

    # --- drawing --------------------------------------------------------------------------

    def show(self, view_id: str, group: str, drawing: Drawing) -> None:
        """Draw ``drawing`` in view ``view_id`` (replacing what ``group`` held)."""
        with self._lock:
            view = self._views.get(view_id)
            if view is None:
                self._prune()
                view = self._views[view_id] = View(view_id)
            view.touched_s = time.monotonic()
            view.drawings[group] = drawing
            if view.client is None or view.canvas is None:
                return  # drawn when the page's 3D view connects
            with view.client.atomic():
                specs = drawing(view.canvas)
                if specs or view.specs.get(group):  # a drawing without labels moves none
                    view.specs[group] = specs
                    self._place_labels(view)

    def clear(self, view_id: str, group: str) -> bool:
        """Remove ``group`` from view ``view_id``; False when it held nothing."""
        with self._lock:
            view = self._views.get(view_id)
            if view is None or view.drawings.pop(group, None) is None:
                return False
            view.specs.pop(group, None)
            if view.client is not None and view.canvas is not None:
                with view.client.atomic():
                    view.canvas.remove_group(group)
                    self._place_labels(view)
            return True

    def relabel(self) -> None:
        """Place every view's labels again (the shared labels moved)."""
        with self._lock:
            for view in self._views.values():
                if view.client is not None:
                    with view.client.atomic():
                        self._place_labels(view)

    def _place_labels(self, view: View) -> None:
        canvas = view.canvas
        assert canvas is not None
        for name in view.labels:
            canvas.remove(name)
        wanted = [s for g in GROUPS for s in view.specs.get(g, [])]
        placed = declutter(wanted, self._reserved())
        view.labels = {s.name: s for s in placed}
        for s in placed:
            canvas.label(s.name, s.shown, s.position)

    # --- lookup ---------------------------------------------------------------------------

    def ids(self, *, connected: bool = True) -> list[str]:
        """The view ids (only those whose page is connected, by default), sorted."""
        with self._lock:
            return sorted(k for k, v in self._views.items() if v.client or not connected)

    def node_names(self, view_id: str, prefix: str = "/") -> list[str]:
        """Names of the nodes drawn in view ``view_id`` under ``prefix`` ([] if none)."""
        with self._lock:
            view = self._views.get(view_id)
            return [] if view is None or view.canvas is None else view.canvas.node_names(prefix)

    def node(self, view_id: str, name: str) -> viser.SceneNodeHandle | None:
        with self._lock:
            view = self._views.get(view_id)
            return None if view is None or view.canvas is None else view.canvas.nodes.get(name)

    def labels(self, view_id: str) -> list[LabelSpec]:
        """The labels drawn in view ``view_id`` (text as shown in ``merged``/``shown``)."""
        with self._lock:
            view = self._views.get(view_id)
            return [] if view is None else list(view.labels.values())
