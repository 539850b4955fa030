"""viser's client page: the 3D view a page embeds, served by the console from the installed viser.

The console serves it same-origin (``/viewer/``) so that only the page's websocket goes to
viser's port (:attr:`backend.viewer.viewer.Viewer.websocket_url`).
"""

from __future__ import annotations

from pathlib import Path as FilePath

import viser


def client_html_path() -> FilePath:
    """Path of viser's bundled client page (``viser/client/build/index.html``).

    Serve it same-origin (e.g. FastAPI ``FileResponse`` at ``/viewer``) and open it as
    ``/viewer?websocket=ws://<host>:<port>/view/<view id>`` (see :attr:`Viewer.websocket_url`):
    only the websocket then goes to viser's port. It must come from the installed viser, whose
    server rejects clients of another version.
    """
    return FilePath(viser.__file__).resolve().parent / "client" / "build" / "index.html"
