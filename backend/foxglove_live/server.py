"""The live Foxglove view's server: a Foxglove WebSocket server (foxglove-sdk) that follows the
console's news, started and stopped with the app (:func:`backend.foxglove_live.live_view`).

* **What it shows**: the news every page gets, as a page gets it (the view is one more
  client of :class:`backend.telemetry.TelemetryHub`), converted by
  :class:`backend.foxglove_live.publish.Publisher` (with a fleet, every vehicle's); the
  previews and predictions the pages ask for (:meth:`FoxgloveLive.preview`,
  :meth:`FoxgloveLive.prediction`); the ME
  transmitter, looked at with each link health; the console's log lines (a logging handler
  on the console's loggers, at the level logging is configured to).
* **Read-only**: the server advertises only the ``time`` capability (the dive's clock, so
  Foxglove's plots count it): no client publishing, no services, no parameters; a client's
  advertise is refused by the SDK with an error status.
* **Never in the way**: one context per console (two apps in one process keep their
  channels apart); the SDK sends on its own threads, dropping a slow client's oldest
  messages; nothing is built for a channel no client subscribes to, except what stays drawn.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Final

import foxglove
from foxglove.messages import Log
from foxglove.websocket import Capability, ChannelView, Client, ServerListener, WebSocketServer
from pydantic import TypeAdapter

from backend.foxglove_live.channels import PREDICTION, PREVIEW, Channels
from backend.foxglove_live.clock import DiveClock
from backend.foxglove_live.frames import stamp
from backend.foxglove_live.publish import Publisher, level_of
from backend.messages import LinkMessage, News
from backend.security import TokenRedactor

if TYPE_CHECKING:
    from backend.console import Console

logger = logging.getLogger("backend.foxglove_live")

#: The server's name, as Foxglove shows it.
SERVER_NAME: Final = "NemeSys Console"
#: The loggers whose lines the view shows (the console's own, its links and its bridge).
LOGGERS: Final = ("backend", "station", "rosbridge")
_NEWS: TypeAdapter[News] = TypeAdapter(News)


class LiveViewError(RuntimeError):
    """The live view cannot start (its port is taken, its host cannot be bound)."""


class _Listener(ServerListener):
    """The SDK's callbacks (on its threads): a subscription gets what stays drawn again."""

    def __init__(self, live: FoxgloveLive) -> None:
        self.live = live

    def on_subscribe(self, client: Client, channel: ChannelView) -> None:
        self.live.subscribed(channel.topic)


class _LogLines(logging.Handler):
    """The console's log lines on the ``/log`` channel (any thread; tokens scrubbed)."""

    def __init__(self, live: FoxgloveLive, secrets: Sequence[str]) -> None:
        super().__init__()
        self.live = live
        self.addFilter(TokenRedactor(secrets))
        self.setFormatter(logging.Formatter("%(message)s"))

    def emit(self, record: logging.LogRecord) -> None:
        try:
            ns = self.live.clock.now()
            line = Log(
                timestamp=stamp(ns),
                level=level_of(record.levelno),
                message=self.format(record),
                name=record.name,
                file=record.filename,
                line=record.lineno,
            )
            self.live.channels.log.log(line, log_time=ns)
        except Exception:  # a log line must never fail the code that logs it
            self.handleError(record)


class FoxgloveLive:
    """The live Foxglove view of one running console, on ``host``:``port`` (0: any free port;
    :attr:`port` says which)."""

    def __init__(self, console: Console, host: str, port: int) -> None:
        self.console = console
        self.context = foxglove.Context()
        fleet = console.fleet
        #: A fleet's vehicles by name, with their addresses (empty: the single vehicle).
        vehicles = {v.name: v.address for v in fleet.vehicles.values()} if fleet.configured else {}
        self.channels = Channels(self.context, list(vehicles))
        dives = console.dives
        self.clock = DiveClock(lambda: None if dives is None else dives.start_t_s)
        self._loop = asyncio.get_running_loop()
        try:
            self.server: WebSocketServer = foxglove.start_server(
                name=SERVER_NAME,
                host=host,
                port=port,
                capabilities=[Capability.Time],
                server_listener=_Listener(self),
                context=self.context,
            )
        except RuntimeError as err:
            self.channels.close()
            raise LiveViewError(
                f"the live Foxglove view (NEMESYS_FOXGLOVE_PORT={port}) cannot listen on "
                f"{host}:{port}: {err}; choose another port, or unset NEMESYS_FOXGLOVE_PORT"
            ) from err
        self.publisher = Publisher(
            self.channels,
            self.clock,
            tick=self.server.broadcast_time,
            new_session=self.server.clear_session,
            monotonic=time.monotonic,
            vehicles=vehicles,
        )
        self._lines = _LogLines(self, [console.settings.token])
        for name in LOGGERS:
            logging.getLogger(name).addHandler(self._lines)
        self._task = asyncio.create_task(self._follow(), name="foxglove live view")
        logger.info("live Foxglove view on ws://%s:%d", host, self.port)

    @property
    def port(self) -> int:
        """The port the server listens on."""
        return self.server.port

    async def stop(self) -> None:
        """Stop following the news, close the channels and the server."""
        for name in LOGGERS:
            logging.getLogger(name).removeHandler(self._lines)
        self._task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await self._task
        self.channels.close()
        self.server.stop()

    # --- the news, as a page gets it -----------------------------------------------------

    async def send_text(self, data: str) -> None:
        """One ``/ws`` message (the hub's :class:`backend.telemetry.Sender`); one that cannot
        be shown is logged and skipped (the view goes on with the next)."""
        try:
            item = _NEWS.validate_json(data)
            self.publisher.news(item)
            if isinstance(item, LinkMessage):  # every second: has the transmitter moved?
                self.publisher.station(self.console.station(), self.console.settings.me_range_m)
        except Exception:
            logger.exception("the live Foxglove view could not show %.80s", data)

    async def _follow(self) -> None:
        """Be one of the hub's clients for as long as the view runs (again, if ever dropped
        for falling behind)."""
        self.publisher.station(self.console.station(), self.console.settings.me_range_m)
        fleet = self.console.fleet
        for vehicle in fleet.vehicles.values():  # the single one's is the console's
            self.publisher.active(vehicle.active_path, fleet.news_name(vehicle))
        while True:
            await self.console.hub.serve(self)
            logger.warning("the live Foxglove view fell behind the news; following again")

    # --- what the pages ask for (any thread: handed to the event loop) --------------------

    def preview(
        self,
        xs: Sequence[float],
        ys: Sequence[float],
        zs: Sequence[float],
        body_start: int,
        label: str,
    ) -> None:
        """A preview a page drew in its 3D view (NED m): the latest one is shown."""
        self._soon(self.publisher.path, PREVIEW.topic, xs, ys, zs, label, body_start)

    def prediction(
        self, xs: Sequence[float], ys: Sequence[float], zs: Sequence[float], label: str
    ) -> None:
        """A prediction a page asked for (NED m): the latest one is shown."""
        self._soon(self.publisher.path, PREDICTION.topic, xs, ys, zs, label)

    def subscribed(self, topic: str) -> None:
        """A client subscribed to ``topic`` (an SDK thread): what stays drawn, again."""
        if topic in self.publisher.latched:
            self._soon(self.publisher.resend, topic)

    def _soon(self, call: Any, *args: Any) -> None:
        with contextlib.suppress(RuntimeError):  # the loop is closed: the view is gone
            self._loop.call_soon_threadsafe(call, *args)


__all__ = ["LOGGERS", "SERVER_NAME", "FoxgloveLive", "LiveViewError"]
