"""Previews drawn in the pages' 3D views off the request path, latest wins per view."""

from __future__ import annotations

import asyncio
from typing import Any


class PreviewDrawer:
    """A burst of previews (an operator typing, twenty clients) costs one drawing per view
    per ``interval_s``; a preview is drawn in its page's own view only."""

    def __init__(self, interval_s: float) -> None:
        self.interval_s = interval_s
        self._pending: dict[str, tuple[Any, ...]] = {}  # view id -> latest preview
        self._ready = asyncio.Event()

    def later(self, view: str, *preview: Any) -> None:
        """Draw ``preview`` (``Viewer.show_preview``'s arguments after the view) in ``view``."""
        self._pending[view] = preview
        self._ready.set()

    async def run(self, viewer: Any) -> None:
        """Draw what is pending into ``viewer`` (:class:`backend.viewer.viewer.Viewer`) forever."""
        while True:
            await self._ready.wait()
            self._ready.clear()
            pending, self._pending = self._pending, {}
            for view, preview in pending.items():
                viewer.show_preview(view, *preview)
            await asyncio.sleep(self.interval_s)
