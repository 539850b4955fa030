"""Parts of the bridge server: one connection's outbox (:class:`ClientOutbox`), and the
guard around endpoint calls (:class:`EndpointGuard`).

Acknowledgements, service responses and fragments are queued in order; pose and status keep
only the newest message (latest wins), so a slow client gets fewer poses but never stale ones
and never holds the others up. A client whose send stalls for more than ``send_timeout_s`` or
whose queue overflows is disconnected.
"""

from __future__ import annotations

import asyncio
import logging
from collections import deque
from collections.abc import Callable
from typing import Any, Final

from websockets.asyncio.server import ServerConnection
from websockets.exceptions import ConnectionClosed

from rosbridge.protocol import ClientSession

logger = logging.getLogger("rosbridge.server")

#: Default limit on one send to a client, seconds; a client that stalls longer is dropped.
DEFAULT_SEND_TIMEOUT_S: Final = 5.0
#: Default limit on a client's ordered queue (acks, replies), messages.
DEFAULT_MAX_QUEUE: Final = 1000
#: An endpoint failure is logged the first time and then once per this many in a row.
FAILURE_LOG_EVERY: Final = 250


class ClientOutbox:
    """One websocket connection: its rosbridge session and its outbox.

    The outbox has an ordered queue (acknowledgements, service responses, fragments, frame
    echoes) and a latest-value slot per streamed topic (pose, status). One writer task
    drains it, so a slow client only slows itself.
    """

    def __init__(
        self,
        ws: ServerConnection,
        session: ClientSession,
        name: str,
        send_timeout_s: float,
        max_queue: int,
    ) -> None:
        self.ws = ws
        self.session = session
        self.name = name
        self.connected_at = 0.0
        self._send_timeout_s = send_timeout_s
        self._max_queue = max_queue
        self._queue: deque[str | bytes] = deque()
        self._latest: dict[str, tuple[str | bytes, ...]] = {}
        self._wake = asyncio.Event()
        self._dropped = False

    def enqueue(self, *texts: str | bytes) -> None:
        """Queue messages that must not be skipped; drop the client if it cannot keep up."""
        if self._dropped or not texts:
            return
        if len(self._queue) + len(texts) > self._max_queue:
            self.drop(f"{self._max_queue} messages queued, client not reading")
            return
        self._queue.extend(texts)
        self._wake.set()

    def offer_latest(self, topic: str, *texts: str | bytes) -> None:
        """Offer the newest message of a streamed topic; replaces one not yet sent."""
        if self._dropped or not texts:
            return
        self._latest[topic] = texts
        self._wake.set()

    def drop(self, reason: str) -> None:
        """Disconnect at once (no closing handshake: the client is not reading)."""
        if self._dropped:
            return
        self._dropped = True
        logger.warning("client %s: disconnected: %s", self.name, reason)
        self.ws.transport.abort()

    async def run_writer(self) -> None:
        """Send the outbox in order, then the latest streamed messages, until closed
        (``str`` as a text frame, ``bytes`` as a binary frame)."""
        try:
            while True:
                await self._wake.wait()
                self._wake.clear()
                while self._queue or self._latest:
                    if self._queue:
                        texts: tuple[str | bytes, ...] = (self._queue.popleft(),)
                    else:
                        texts = self._latest.pop(next(iter(self._latest)))
                    for text in texts:
                        await asyncio.wait_for(self.ws.send(text), self._send_timeout_s)
        except TimeoutError:
            self.drop(f"a send took longer than {self._send_timeout_s:g} s")
        except ConnectionClosed:
            pass


def peer_of(ws: ServerConnection) -> str:
    try:
        host, port = ws.remote_address[:2]
    except (TypeError, ValueError):
        return "?"
    return f"{host}:{port}"


class EndpointGuard:
    """Runs one step of the clock; a failure is logged (throttled) and gives ``None``."""

    def __init__(self) -> None:
        self._failures: dict[str, int] = {}

    def __call__(self, what: str, call: Callable[[], Any]) -> Any:
        """Run one step of the clock; a failure is logged (throttled) and gives ``None``.

        The vehicle keeps flying: a failing endpoint call or publication skips only itself.
        """
        try:
            result = call()
        except Exception:
            count = self._failures.get(what, 0) + 1
            self._failures[what] = count
            if count % FAILURE_LOG_EVERY == 1:
                logger.exception("%s failed (%d in a row)", what, count)
            return None
        if self._failures.pop(what, None):
            logger.info("%s works again", what)
        return result
