"""The rosbridge transmitter: publishes frames to a rosbridge v2 endpoint (the simulated
vehicle, or a real vehicle behind a rosbridge) on ``/nemesys/frame`` and waits for the vehicle's
acknowledgement on ``/nemesys/mission`` (matched as :mod:`station.transmit_acks` says).
Import it from :mod:`station.transmit`.

``send`` is blocking and thread-safe, as ``nemesys send`` wants it; the
connection is the one rosbridge client (:mod:`rosbridge.transport`), on an event loop that the
transmitter runs in a thread of its own from the first send to :meth:`close`.

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
import os
import threading
import time
from collections.abc import Coroutine
from typing import Any, TypeVar

from websockets.exceptions import ConnectionClosed, WebSocketException

from codec import Frame
from rosbridge.client import ClientProtocol
from rosbridge.subscriber_wait import DEFAULT_SUBSCRIBER_WAIT_S, SubscriberWait
from rosbridge.transport import RosbridgeClient
from station.transmit_acks import ACK_SETTLE_S, _AckMatcher, ack_of
from station.transmit_base import (
    DEFAULT_ACK_TIMEOUT_S,
    SendResult,
    Transmitter,
    _message,
    failure_reason,
    frame_msg,
    logger,
)
from vehicle_contract.names import topic_names

DEFAULT_ROSBRIDGE_URL = "ws://127.0.0.1:9090"
DEFAULT_OPEN_TIMEOUT_S = 5.0

T = TypeVar("T")

#: What an acknowledgement queue holds: an acknowledgement, or None when the connection closed.
_Acks = asyncio.Queue[dict[str, Any] | None]


def _why(exc: BaseException) -> str:
    """A connection failure in words: an OS error's own words for its errno (asyncio's text
    is "Connect call failed (address)", and the detail names the URL already)."""
    code = exc.errno if isinstance(exc, OSError) else None
    return os.strerror(code) if isinstance(code, int) and code > 0 else _message(exc)


def _log_wait(wait: SubscriberWait | None, url: str) -> None:
    if wait is None:
        return
    if wait.present:
        logger.info("%s: %s has subscribers %s", url, wait.topic, ", ".join(wait.subscribers or []))
    elif wait.warning is not None:
        logger.warning("%s: %s", url, wait.warning)
    else:
        logger.info("%s: %s", url, wait.note)


class _LoopThread:
    """An event loop in a daemon thread: the blocking ``send`` runs its coroutines there."""

    def __init__(self, name: str) -> None:
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self.loop.run_forever, name=name, daemon=True)
        self._thread.start()

    def run(self, coro: Coroutine[Any, Any, T]) -> T:
        return asyncio.run_coroutine_threadsafe(coro, self.loop).result()

    def stop(self) -> None:
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(5.0)
        if not self._thread.is_alive():
            self.loop.close()


class RosbridgeTransmitter(Transmitter):
    """Publishes frames to a rosbridge v2 endpoint and waits for the vehicle's acknowledgement.

    On connecting it advertises the frame topic (``std_msgs/UInt8MultiArray``) and subscribes to
    the mission topic (``std_msgs/String`` whose ``data`` is a JSON object); each frame is
    published as its bytes, ``{"data": [13 ints]}`` (14 addressed). The connection is opened on
    the first send and kept; a connection found closed is reopened once. Acknowledgements are
    matched as :mod:`station.transmit_acks` says. ``namespace``: the vehicle's ROS namespace
    (both topics under ``/<namespace>/nemesys/...``; "" for none).
    """

    transport = "rosbridge"

    def __init__(
        self,
        url: str = DEFAULT_ROSBRIDGE_URL,
        *,
        open_timeout_s: float = DEFAULT_OPEN_TIMEOUT_S,
        settle_s: float = ACK_SETTLE_S,
        subscriber_wait_s: float = DEFAULT_SUBSCRIBER_WAIT_S,
        namespace: str = "",
    ) -> None:
        super().__init__(url)
        self.url = url
        #: The contract's topic names on this vehicle (ValueError for a bad namespace).
        self.names = topic_names(namespace)
        self.open_timeout_s = open_timeout_s
        self.settle_s = settle_s
        #: On a new connection, the most the first publish waits for the vehicle's subscriber
        #: (0: not at all; see the module docstring).
        self.subscriber_wait_s = subscriber_wait_s
        #: What the wait on the newest connection found, until a send reports it.
        self._wait: SubscriberWait | None = None
        self._protocol = ClientProtocol(
            advertise=[self.names.frame], subscribe=[self.names.mission]
        )
        self._lock = threading.Lock()
        self._thread: _LoopThread | None = None
        self._client: RosbridgeClient | None = None
        self._acks: _Acks | None = None

    @property
    def connected(self) -> bool:
        """The connection is open."""
        client = self._client
        return client is not None and not client.closed

    # --- the blocking face ----------------------------------------------------------------

    def send(self, frame: Frame, *, wait_ack_s: float = DEFAULT_ACK_TIMEOUT_S) -> SendResult:
        with self._lock:
            if self._thread is None:
                self._thread = _LoopThread(f"rosbridge transmitter {self.url}")
            try:
                return self._thread.run(self._send(frame, wait_ack_s))
            except Exception as exc:  # send reports, never raises
                logger.exception("sending to %s", self.url)
                with contextlib.suppress(Exception):
                    self._thread.run(self._drop())
                return self._failed("internal error", f"{type(exc).__name__}: {exc}")

    def close(self) -> None:
        """Close the connection (unsubscribing and unadvertising first) and its thread."""
        with self._lock:
            thread, self._thread = self._thread, None
            if thread is None:
                return
            try:
                thread.run(self._drop(polite=True))
            finally:
                thread.stop()

    # --- on the transmitter's event loop ----------------------------------------------------

    async def _connect(self) -> RosbridgeClient:
        acks: _Acks = asyncio.Queue()

        def on_mission(msg: object) -> None:
            ack = ack_of(msg)
            if ack is not None:
                acks.put_nowait(ack)

        client = await RosbridgeClient.connect(
            self.url,
            self._protocol,
            {self.names.mission: on_mission},
            open_timeout_s=self.open_timeout_s,
            logger=logger,
        )
        client.on_close = lambda: acks.put_nowait(None)
        try:
            await client.open()
            self._wait = await self._await_subscriber(client)
        except BaseException:
            await client.close()
            raise
        logger.info("connected to %s", self.url)
        self._client, self._acks = client, acks
        self._drain()  # acknowledgements that arrived while waiting are old ones
        return client

    async def _await_subscriber(self, client: RosbridgeClient) -> SubscriberWait | None:
        """Wait until the frame topic has a subscriber or the bound (module docstring)."""
        if self.subscriber_wait_s <= 0:
            return None
        wait = SubscriberWait(self.names.frame, self.subscriber_wait_s, time.monotonic())
        while not wait.done(time.monotonic()) and not client.closed:
            if wait.ask(time.monotonic()):
                service, args = wait.request
                timeout_s = wait.timeout_s(time.monotonic())
                answer = await client.call_service(service, args, timeout_s=timeout_s)
                wait.answer(answer, time.monotonic())
            else:
                await asyncio.sleep(wait.timeout_s(time.monotonic()))
        _log_wait(wait, self.url)
        return wait

    def _drain(self) -> None:
        """Discard the acknowledgements that arrived before now."""
        acks = self._acks
        while acks is not None and not acks.empty():
            ack = acks.get_nowait()
            if ack is not None:
                logger.debug("discarding earlier acknowledgement seq=%s", ack.get("seq"))

    async def _ready(self) -> RosbridgeClient:
        client = self._client
        if client is not None:
            self._drain()
            if not client.closed:
                return client
            logger.info("connection to %s was closed; reconnecting", self.url)
            await self._drop()
        return await self._connect()

    async def _publish(self, message: str) -> RosbridgeClient:
        """Publish on a ready connection; if a kept connection turns out closed (the frame was
        not written), publish once more on a new one."""
        reused = self._client is not None
        client = await self._ready()
        try:
            await client.send(message)
        except ConnectionClosed:
            if not reused:
                raise
            logger.info("connection to %s was closed; reconnecting", self.url)
            await self._drop()
            client = await self._ready()
            await client.send(message)
        return client

    async def _drop(self, *, polite: bool = False) -> None:
        client, self._client, self._acks = self._client, None, None
        if client is not None:
            await client.close(*(self._protocol.close_messages() if polite else ()))

    async def _send(self, frame: Frame, wait_ack_s: float) -> SendResult:
        # made before connecting: the publish keeps its id whatever the connection asks first
        message = self._protocol.publish(self.names.frame, frame_msg(frame))
        try:
            await self._publish(message)
        except (OSError, WebSocketException, TimeoutError) as exc:
            await self._drop()
            return self._failed(failure_reason(exc), f"{self.url}: {_why(exc)}")
        acks = self._acks
        wait, self._wait = self._wait, None
        sent_t = time.time()
        logger.info("published frame %s to %s", frame.hex, self.url)
        matcher = _AckMatcher(frame, wait_ack_s, self.settle_s)  # expired at once if not waiting
        closed = False
        while acks is not None and (remaining_s := matcher.remaining_s()) > 0:
            try:
                ack = await asyncio.wait_for(acks.get(), remaining_s)
            except TimeoutError:
                break
            if ack is None:
                logger.info("connection to %s lost while waiting", self.url)
                await self._drop()
                closed = True
                break
            if matcher.offer(ack):
                break
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
