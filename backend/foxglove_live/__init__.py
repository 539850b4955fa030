"""A live Foxglove view of the console (opt-in: ``NEMESYS_FOXGLOVE_PORT``; docs/foxglove.md,
"Live").

A Foxglove WebSocket server (foxglove-sdk) on the console's ``host`` shows what the pages
are told, in Foxglove's well-known schemas: the vehicle's pose, track and fix, the paths
(active, preview, prediction), the believed position with its uncertainty, the transmitter
with its range ring, command records, link health and log lines, on the dive's clock.
Read-only: no client publishing, no services, no parameters.

* :mod:`backend.foxglove_live.frames`: NED -> the scene frame (ENU ``map``), time stamps;
* :mod:`backend.foxglove_live.clock`: the dive's clock in nanoseconds;
* :mod:`backend.foxglove_live.channels`: the channels, their topics and schemas;
* :mod:`backend.foxglove_live.scene`: the drawings (scene updates);
* :mod:`backend.foxglove_live.vehicles`: each vehicle as the view keeps it (a fleet's: every
  vehicle, on its own channels, entities and frame);
* :mod:`backend.foxglove_live.publish`: the news as Foxglove messages;
* :mod:`backend.foxglove_live.server`: the server, following the console.

foxglove-sdk is imported only when the view is on.
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from backend.console import Console


@asynccontextmanager
async def live_view(console: Console) -> AsyncIterator[None]:
    """The live Foxglove view of a started ``console`` while inside (nothing when its
    ``foxglove_port`` setting is unset); ``console.foxglove`` is it meanwhile.

    Raises:
        backend.foxglove_live.server.LiveViewError: its port cannot be listened on.
    """
    port = console.settings.foxglove_port
    if port is None:
        yield
        return
    from backend.foxglove_live.server import FoxgloveLive

    live = FoxgloveLive(console, console.settings.host, port)
    console.foxglove = live
    try:
        yield
    finally:
        console.foxglove = None
        await live.stop()


__all__ = ["live_view"]
