"""View ids: how a page names its own 3D view (no viser import: the API uses it too).

A page makes a random id when it loads, puts it in the websocket URL it gives viser's client
(``ws://host:port/view/<id>``) and sends it as ``X-Nemesys-View`` on its API calls.
"""

from __future__ import annotations

import re
from typing import Final

#: A view id: 8-64 of ``A-Z a-z 0-9 _ -`` (the page makes 32 hex digits).
VIEW_ID_PATTERN: Final = r"^[A-Za-z0-9_-]{8,64}$"
_VIEW_PATH: Final = re.compile(r"^/view/([A-Za-z0-9_-]{8,64})/?(?:\?.*)?$")


def view_id_from_path(path: str | None) -> str | None:
    """A websocket URL's path ``/view/<id>`` -> ``<id>`` (None for any other path)."""
    m = _VIEW_PATH.match(path or "")
    return m.group(1) if m else None
