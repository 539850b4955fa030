"""The one rosbridge client: a websocket (``websockets``, asyncio) under the sans-IO client
protocol of :mod:`rosbridge.client`. The console's link (:mod:`station.link`), the station's
transmitter (:mod:`station.transmit_rosbridge`) and ``nemesys vehicle-check``
(:mod:`station.vehicle_check`) all talk to a vehicle through it.

As roslibpy does it, the protocol (what is sent, and its ids: :class:`ClientProtocol`) stays
apart from the transport (this module), and what the server sends is dispatched through a
table by ``op``: ``publish`` to the handler registered for its topic, ``service_response`` to
the call waiting for its id, ``status`` to the log. Anything else, and anything that is not a
JSON object, is logged and dropped: a server's message never raises here, and a handler that
fails is logged without taking the connection down.

One reader task per connection does the dispatching; a caller awaits :meth:`call_service`
for an answer, or registers topic handlers and :attr:`RosbridgeClient.on_close`.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable, Mapping
from typing import Final, Self

from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed, WebSocketException

from rosbridge.client import ClientProtocol, decode_server_message
from rosbridge.errors import BinaryMessage, BridgeError, JsonObject

#: A topic's handler: called with the ``msg`` of each ``publish`` on it, on the event loop.
TopicHandler = Callable[[object], None]

#: How long the websocket handshake may take by default (s).
DEFAULT_OPEN_TIMEOUT_S: Final = 5.0
#: The largest message taken from the server (bytes): a vehicle's acknowledgements and status
#: are a few kB; a rosapi listing of a busy ROS graph can be a few hundred.
MAX_MESSAGE_BYTES: Final = 2**22

_logger = logging.getLogger("rosbridge.transport")


class RosbridgeClient:
    """One websocket connection to a rosbridge v2 server (open it with :meth:`connect`).

    ``protocol`` makes the messages (and numbers them); ``handlers`` maps a topic to what
    receives its messages (a mutable table: register before subscribing). ``on_close`` is
    called once when the connection is gone (either side closed it, or it broke). Everything is
    logged on ``logger`` (default ``rosbridge.transport``): each user names its own.
    """

    def __init__(
        self,
        conn: ClientConnection,
        protocol: ClientProtocol,
        handlers: Mapping[str, TopicHandler] | None = None,
        *,
        logger: logging.Logger | None = None,
    ) -> None:
        self.protocol = protocol
        self.handlers: dict[str, TopicHandler] = dict(handlers or {})
        self.on_close: Callable[[], None] | None = None
        self._conn = conn
        self._logger = logger or _logger
        self._pending: dict[str, asyncio.Future[JsonObject | None]] = {}
        self._closed = False
        #: What a server message's ``op`` is dispatched to.
        self._ops: dict[str, Callable[[JsonObject], None]] = {
            "publish": self._on_publish,
            "service_response": self._on_service_response,
            "status": self._on_status,
        }
        self._reader = asyncio.create_task(self._read(), name="rosbridge client reader")

    @classmethod
    async def connect(
        cls,
        url: str,
        protocol: ClientProtocol,
        handlers: Mapping[str, TopicHandler] | None = None,
        *,
        open_timeout_s: float = DEFAULT_OPEN_TIMEOUT_S,
        logger: logging.Logger | None = None,
    ) -> Self:
        """Open the websocket (nothing is sent yet: see :meth:`open`).

        Raises:
            OSError: refused, unreachable, reset.
            TimeoutError: no handshake within ``open_timeout_s``.
            websockets.exceptions.WebSocketException: a bad URL, or a failed handshake.
        """
        conn = await connect(
            url,
            open_timeout=open_timeout_s,
            close_timeout=1.0,
            max_size=MAX_MESSAGE_BYTES,
            proxy=None,
        )
        return cls(conn, protocol, handlers, logger=logger)

    @property
    def closed(self) -> bool:
        """The connection is gone (nothing more will be received)."""
        return self._closed

    # --- sending ------------------------------------------------------------------------------

    async def send(self, *texts: str) -> None:
        """Send messages in order.

        Raises:
            websockets.exceptions.ConnectionClosed: the connection is gone.
        """
        for text in texts:
            await self._conn.send(text)

    async def open(self) -> None:
        """The protocol's advertisements, then its subscriptions."""
        await self.send(*self.protocol.open_messages())

    async def publish(self, topic: str, msg: Mapping[str, object]) -> None:
        """Publish ``msg`` on ``topic`` (advertised by :meth:`open`)."""
        await self.send(self.protocol.publish(topic, msg))

    async def call_service(
        self, service: str, args: Mapping[str, object] | None = None, *, timeout_s: float
    ) -> JsonObject | None:
        """A service's ``service_response`` (``result`` false when it failed), or ``None``
        when none came within ``timeout_s`` or the connection closed first.

        Raises:
            websockets.exceptions.ConnectionClosed: the request could not be sent.
        """
        if self._closed:
            return None
        op_id, text = self.protocol.call_service(service, args)
        future: asyncio.Future[JsonObject | None] = asyncio.get_running_loop().create_future()
        self._pending[op_id] = future
        try:
            await self.send(text)
            return await asyncio.wait_for(future, timeout_s)
        except TimeoutError:
            return None
        finally:
            self._pending.pop(op_id, None)

    # --- closing ------------------------------------------------------------------------------

    async def wait_closed(self) -> None:
        """Return when the connection is gone."""
        await asyncio.shield(self._reader)

    async def close(self, *farewell: str) -> None:
        """Send ``farewell`` (unsubscribes, unadvertises) if still possible, then close."""
        if not self._closed:
            with contextlib.suppress(OSError, WebSocketException):
                await self.send(*farewell)
        await self._conn.close()
        self._reader.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await self._reader

    # --- receiving ----------------------------------------------------------------------------

    async def _read(self) -> None:
        try:
            async for data in self._conn:
                self._dispatch(data)
        except ConnectionClosed:
            pass
        finally:
            self._closed = True
            for future in self._pending.values():
                if not future.done():
                    future.set_result(None)
            if self.on_close is not None:
                self._guarded("the close handler", self.on_close)

    def _dispatch(self, data: str | bytes) -> None:
        try:
            message = decode_server_message(data)
        except BinaryMessage as error:
            self._logger.debug("ignoring %s", error.reason)
            return
        except BridgeError as error:
            self._logger.warning("ignoring %s", error.reason)
            return
        op = message.get("op")
        handler = self._ops.get(op) if isinstance(op, str) else None
        if handler is None:
            self._logger.debug("ignoring a %r message", op)
            return
        handler(message)

    def _on_publish(self, message: JsonObject) -> None:
        topic = message.get("topic")
        handler = self.handlers.get(topic) if isinstance(topic, str) else None
        if handler is None:
            self._logger.debug("ignoring a message on %s", topic)
            return
        msg = message.get("msg")
        self._guarded(f"the handler of {topic}", lambda: handler(msg))

    def _on_service_response(self, message: JsonObject) -> None:
        future = self._pending.get(str(message.get("id")))
        if future is None or future.done():
            self._logger.debug("ignoring an answer nobody waits for: %s", message.get("id"))
            return
        future.set_result(message)

    def _on_status(self, message: JsonObject) -> None:
        level = logging.WARNING if message.get("level") in ("error", "warning") else logging.INFO
        self._logger.log(level, "rosbridge status: %s", message.get("msg", message))

    def _guarded(self, what: str, call: Callable[[], None]) -> None:
        try:
            call()
        except Exception:  # a bug in a handler must not take the connection down
            self._logger.exception("%s failed", what)
