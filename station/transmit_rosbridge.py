"""The rosbridge transmitter: publishes frames to a rosbridge v2 endpoint (the simulated
vehicle, or a real vehicle behind a rosbridge) on ``/nemesys/frame`` and waits for the vehicle's
acknowledgement on ``/nemesys/mission`` (matched as :mod:`station.transmit_acks` says).
Import it from :mod:`station.transmit`.

Waiting for the vehicle's subscriber
------------------------------------
On a new connection the transmitter advertises ``/nemesys/frame`` and, before its first
publish, waits until the vehicle subscribes to it (:mod:`rosbridge.subscriber_wait`): a real
rosbridge_server creates a new publisher for the advertisement, and a vehicle subscriber not
yet matched to it would miss a frame published at once. It asks ``/rosapi/subscribers`` and
publishes as soon as a subscriber is listed; if rosapi cannot tell, it publishes
``subscriber_wait_s`` (1 s) after advertising; if rosapi says nobody subscribes for that long,
it publishes anyway and the result's ``warning`` says the frame may be lost. Whatever the wait
found is added to ``detail`` when no acknowledgement came back. A kept connection does not
wait again.
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
import time

from websockets.asyncio.client import connect as async_connect
from websockets.exceptions import ConnectionClosed, WebSocketException
from websockets.protocol import State
from websockets.sync.client import ClientConnection as SyncConnection
from websockets.sync.client import connect as sync_connect

from codec import Frame
from rosbridge.client import ClientProtocol
from rosbridge.protocol import FRAME_TOPIC, MISSION_TOPIC
from rosbridge.subscriber_wait import DEFAULT_SUBSCRIBER_WAIT_S, SubscriberWait
from station.transmit_acks import (
    ACK_SETTLE_S,
    _AckMatcher,
    _AsyncLink,
    _mission_of,
    _server_message,
)
from station.transmit_base import (
    DEFAULT_ACK_TIMEOUT_S,
    SendResult,
    Transmitter,
    _message,
    failure_reason,
    frame_msg,
    logger,
)

DEFAULT_ROSBRIDGE_URL = "ws://127.0.0.1:9090"
DEFAULT_OPEN_TIMEOUT_S = 5.0


def _log_wait(wait: SubscriberWait | None, url: str) -> None:
    if wait is None:
        return
    if wait.present:
        logger.info("%s: %s has subscribers %s", url, wait.topic, ", ".join(wait.subscribers or []))
    elif wait.warning is not None:
        logger.warning("%s: %s", url, wait.warning)
    else:
        logger.info("%s: %s", url, wait.note)


class RosbridgeTransmitter(Transmitter):
    """Publishes frames to a rosbridge v2 endpoint and waits for the vehicle's acknowledgement.

    On connecting it advertises :data:`FRAME_TOPIC` (``std_msgs/UInt8MultiArray``) and
    subscribes to :data:`MISSION_TOPIC` (``std_msgs/String`` whose ``data`` is a JSON object);
    each frame is published as ``{"data": [13 ints]}``. The connection is opened on the first
    send and kept; a connection found closed is reopened once. ``send`` (sync, thread-safe) and
    ``send_async`` (asyncio) each keep their own connection. Acknowledgements are matched as
    :mod:`station.transmit_acks` says.
    """

    transport = "rosbridge"

    def __init__(
        self,
        url: str = DEFAULT_ROSBRIDGE_URL,
        *,
        open_timeout_s: float = DEFAULT_OPEN_TIMEOUT_S,
        settle_s: float = ACK_SETTLE_S,
        subscriber_wait_s: float = DEFAULT_SUBSCRIBER_WAIT_S,
    ) -> None:
        super().__init__(url)
        self.url = url
        self.open_timeout_s = open_timeout_s
        self.settle_s = settle_s
        #: On a new connection, the most the first publish waits for the vehicle's subscriber
        #: (0: not at all; see the module docstring).
        self.subscriber_wait_s = subscriber_wait_s
        #: What the wait on the newest connection found, until a send reports it.
        self._wait: SubscriberWait | None = None
        self._protocol = ClientProtocol(advertise=[FRAME_TOPIC], subscribe=[MISSION_TOPIC])
        self._conn: SyncConnection | None = None
        self._lock = threading.Lock()
        self._link: _AsyncLink | None = None
        self._alock: asyncio.Lock | None = None
        self._alock_loop: asyncio.AbstractEventLoop | None = None

    @property
    def connected(self) -> bool:
        """The sync connection is open."""
        return self._conn is not None and self._conn.state is State.OPEN

    # sync ---------------------------------------------------------------------------------

    def _connect(self) -> SyncConnection:
        conn = sync_connect(
            self.url, open_timeout=self.open_timeout_s, close_timeout=1.0, proxy=None
        )
        try:
            for message in self._protocol.open_messages():
                conn.send(message)
            self._wait = self._await_subscriber(conn)
        except BaseException:
            conn.close()
            raise
        logger.info("connected to %s", self.url)
        return conn

    def _new_wait(self) -> SubscriberWait | None:
        if self.subscriber_wait_s <= 0:
            return None
        return SubscriberWait(self._protocol, FRAME_TOPIC, self.subscriber_wait_s, time.monotonic())

    def _await_subscriber(self, conn: SyncConnection) -> SubscriberWait | None:
        """Block until the frame topic has a subscriber or the bound (module docstring);
        acknowledgements arriving meanwhile are old ones and are dropped."""
        wait = self._new_wait()
        while wait is not None and not wait.done(time.monotonic()):
            if (ask := wait.ask(time.monotonic())) is not None:
                conn.send(ask)
            try:
                data = conn.recv(timeout=wait.timeout_s(time.monotonic()))
            except TimeoutError:
                continue
            message = _server_message(data)
            if message is not None and not wait.offer(message, time.monotonic()):
                logger.debug("while waiting for a subscriber, ignoring %s", message.get("op"))
        _log_wait(wait, self.url)
        return wait

    def _drain(self, conn: SyncConnection) -> None:
        while True:
            try:
                data = conn.recv(timeout=0)
            except TimeoutError:
                return
            ack = _mission_of(data)
            if ack is not None:
                logger.debug("discarding earlier acknowledgement seq=%s", ack.get("seq"))

    def _ready(self) -> SyncConnection:
        if self._conn is not None:
            try:
                self._drain(self._conn)
                if self._conn.state is State.OPEN:
                    return self._conn
            except ConnectionClosed:
                pass
            logger.info("connection to %s was closed; reconnecting", self.url)
            self._drop()
        self._conn = self._connect()
        return self._conn

    def _publish(self, frame: Frame) -> SyncConnection:
        """Publish on a ready connection; if a kept connection turns out closed (the frame was
        not written), publish once more on a new one."""
        message = self._protocol.publish(FRAME_TOPIC, frame_msg(frame))
        reused = self._conn is not None
        conn = self._ready()
        try:
            conn.send(message)
        except ConnectionClosed:
            if not reused:
                raise
            logger.info("connection to %s was closed; reconnecting", self.url)
            self._drop()
            conn = self._ready()
            conn.send(message)
        return conn

    def _drop(self) -> None:
        conn, self._conn = self._conn, None
        if conn is not None:
            conn.close()

    def send(self, frame: Frame, *, wait_ack_s: float = DEFAULT_ACK_TIMEOUT_S) -> SendResult:
        with self._lock:
            try:
                return self._send(frame, wait_ack_s)
            except Exception as exc:  # send reports, never raises
                logger.exception("sending to %s", self.url)
                self._drop()
                return self._failed("internal error", f"{type(exc).__name__}: {exc}")

    def _send(self, frame: Frame, wait_ack_s: float) -> SendResult:
        try:
            conn = self._publish(frame)
        except (OSError, WebSocketException) as exc:
            self._drop()
            return self._failed(failure_reason(exc), f"{self.url}: {_message(exc)}")
        wait, self._wait = self._wait, None
        sent_t = time.time()
        logger.info("published frame %s to %s", frame.hex, self.url)
        matcher = _AckMatcher(frame, wait_ack_s, self.settle_s)  # expired at once if not waiting
        closed = False
        try:
            while (remaining_s := matcher.remaining_s()) > 0:
                try:
                    data = conn.recv(timeout=remaining_s)
                except TimeoutError:
                    break
                ack = _mission_of(data)
                if ack is not None and matcher.offer(ack):
                    break
        except (OSError, WebSocketException) as exc:
            logger.info("connection to %s lost while waiting: %s", self.url, exc)
            self._drop()
            closed = True
        return self._outcome(matcher, sent_t, wait_ack_s, closed, wait)

    def _outcome(
        self,
        matcher: _AckMatcher,
        sent_t: float,
        wait_ack_s: float,
        closed: bool,
        wait: SubscriberWait | None = None,
    ) -> SendResult:
        warning = wait.warning if wait is not None else None
        note = f"; {wait.note}" if wait is not None and wait.note else ""
        if wait_ack_s <= 0:
            return SendResult(
                ok=True,
                transport=self.transport,
                target=self.target,
                sent_t=sent_t,
                detail=f"published; not waiting for an acknowledgement{note}",
                warning=warning,
            )
        if matcher.ack is None:
            if closed:
                return self._failed(
                    "connection closed",
                    f"{self.url} closed the connection after the frame was published, "
                    f"before an acknowledgement{note}",
                    sent_t,
                    warning,
                )
            return self._failed(
                "timeout",
                f"frame published, no acknowledgement within {wait_ack_s:g} s{note}",
                sent_t,
                warning,
            )
        detail = {
            "exact": "acknowledged",
            "near": "acknowledged (the frame arrived with bit errors)",
            "first": "acknowledged by order: the acknowledgement's frame_hex is not the sent "
            "frame's (bit slip, or another station's frame)",
        }[matcher.match or "first"]
        return SendResult(
            ok=True,
            transport=self.transport,
            target=self.target,
            sent_t=sent_t,
            ack=matcher.ack,
            ack_match=matcher.match,
            detail=detail,
            warning=warning,
        )

    def close(self) -> None:
        """Close the sync connection (unsubscribing and unadvertising first). An async
        connection is aborted; from async code prefer :meth:`aclose`."""
        with self._lock:
            conn, self._conn = self._conn, None
            if conn is not None:
                try:
                    for message in self._protocol.close_messages():
                        conn.send(message)
                except (OSError, WebSocketException) as exc:
                    logger.debug("closing %s: %s", self.url, exc)
                conn.close()
        link, self._link = self._link, None
        if link is not None:
            link.abort_threadsafe()

    # async --------------------------------------------------------------------------------

    def _async_lock(self) -> asyncio.Lock:
        loop = asyncio.get_running_loop()
        if self._alock is None or self._alock_loop is not loop:
            self._alock, self._alock_loop = asyncio.Lock(), loop
        return self._alock

    async def _async_ready(self) -> _AsyncLink:
        link = self._link
        if link is not None:
            if link.loop is asyncio.get_running_loop():
                link.drain()
                if not link.closed and link.conn.state is State.OPEN:
                    return link
                logger.info("connection to %s was closed; reconnecting", self.url)
            await self._async_drop()
        conn = await async_connect(
            self.url, open_timeout=self.open_timeout_s, close_timeout=1.0, proxy=None
        )
        try:
            for message in self._protocol.open_messages():
                await conn.send(message)
        except BaseException:
            await conn.close()
            raise
        logger.info("connected to %s", self.url)
        self._link = _AsyncLink(conn)
        self._wait = await self._async_await_subscriber(self._link)
        return self._link

    async def _async_await_subscriber(self, link: _AsyncLink) -> SubscriberWait | None:
        """:meth:`_await_subscriber` on the async connection."""
        wait = self._new_wait()
        while wait is not None and not wait.done(time.monotonic()):
            if (ask := wait.ask(time.monotonic())) is not None:
                await link.conn.send(ask)
            try:
                message = await asyncio.wait_for(
                    link.responses.get(), wait.timeout_s(time.monotonic())
                )
            except TimeoutError:
                continue
            wait.offer(message, time.monotonic())
        link.drain()
        _log_wait(wait, self.url)
        return wait

    async def _async_publish(self, frame: Frame) -> _AsyncLink:
        """As :meth:`_publish`, on the async connection."""
        message = self._protocol.publish(FRAME_TOPIC, frame_msg(frame))
        reused = self._link is not None
        link = await self._async_ready()
        try:
            await link.conn.send(message)
        except ConnectionClosed:
            if not reused:
                raise
            logger.info("connection to %s was closed; reconnecting", self.url)
            await self._async_drop()
            link = await self._async_ready()
            await link.conn.send(message)
        return link

    async def _async_drop(self, *, polite: bool = False) -> None:
        link, self._link = self._link, None
        if link is None:
            return
        if link.loop is not asyncio.get_running_loop():  # opened under another event loop
            link.abort_threadsafe()
            return
        if polite and not link.closed:
            try:
                for message in self._protocol.close_messages():
                    await link.conn.send(message)
            except (OSError, WebSocketException) as exc:
                logger.debug("closing %s: %s", self.url, exc)
        await link.conn.close()
        link.reader.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await link.reader

    async def send_async(
        self, frame: Frame, *, wait_ack_s: float = DEFAULT_ACK_TIMEOUT_S
    ) -> SendResult:
        """:meth:`send` on the running event loop (its own connection)."""
        async with self._async_lock():
            try:
                return await self._send_async(frame, wait_ack_s)
            except Exception as exc:  # send reports, never raises
                logger.exception("sending to %s", self.url)
                await self._async_drop()
                return self._failed("internal error", f"{type(exc).__name__}: {exc}")

    async def _send_async(self, frame: Frame, wait_ack_s: float) -> SendResult:
        try:
            link = await self._async_publish(frame)
        except (OSError, WebSocketException) as exc:
            await self._async_drop()
            return self._failed(failure_reason(exc), f"{self.url}: {_message(exc)}")
        wait, self._wait = self._wait, None
        sent_t = time.time()
        logger.info("published frame %s to %s", frame.hex, self.url)
        matcher = _AckMatcher(frame, wait_ack_s, self.settle_s)  # expired at once if not waiting
        closed = False
        while (remaining_s := matcher.remaining_s()) > 0:
            try:
                ack = await asyncio.wait_for(link.acks.get(), remaining_s)
            except TimeoutError:
                break
            if ack is None:
                logger.info("connection to %s lost while waiting", self.url)
                await self._async_drop()
                closed = True
                break
            if matcher.offer(ack):
                break
        return self._outcome(matcher, sent_t, wait_ack_s, closed, wait)

    async def aclose(self) -> None:
        """Close both connections, unsubscribing and unadvertising first."""
        await self._async_drop(polite=True)
        await asyncio.to_thread(self.close)
