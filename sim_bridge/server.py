"""The simulated vehicle's rosbridge v2 websocket server (``websockets`` asyncio API).

:class:`BridgeServer` exposes any :class:`~sim_bridge.endpoint.VehicleEndpoint` the way a
real ROS 2 vehicle running ``rosbridge_server`` would: clients (the console, observers,
roslibpy, roslibjs) publish frames on ``/nemesys/frame`` and subscribe to
``/nemesys/pose``, ``/nemesys/mission`` and ``/nemesys/status``. The protocol itself lives in
:mod:`sim_bridge.rosbridge`; this module does the IO, the clock and the logging.

Timing: a tick task advances the endpoint by the elapsed wall time times ``time_scale``
every ``tick_s`` (20 ms by default), publishes every acknowledgement from
``take_missions()``, and publishes the pose at ``pose_hz`` and the status at ``status_hz``.
All endpoint calls happen on the server's event loop, one at a time, so the endpoint needs
no locking.

Clients: each connection has its own :class:`~sim_bridge.rosbridge.ClientSession`
(subscriptions, advertisements, status level) and its own outbox drained by its own writer
task. Mission acknowledgements, service responses and status messages are queued in order;
pose and status keep only the newest message (latest wins), so a slow client gets fewer
poses but never stale ones and never holds the others up. A client whose send stalls for
more than ``send_timeout_s`` or whose queue overflows is disconnected.

Faults: every dropped message is logged on the ``sim_bridge.server`` logger with the client
and the reason, and answered with a rosbridge ``status`` message only if the client opted in
with ``set_level`` (see :mod:`sim_bridge.rosbridge`). Messages above ``max_message_bytes``
are dropped with the connection kept; messages above the hard limit (``hard_max_bytes``,
4 x ``max_message_bytes`` by default) make the ``websockets`` library close that connection
with code 1009. The endpoint never sees a malformed message, and the vehicle keeps flying
whatever the clients do.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import logging
from collections import deque
from collections.abc import Callable
from typing import Any, Final

from websockets.asyncio.server import Server, ServerConnection, serve
from websockets.exceptions import ConnectionClosed, ConnectionClosedError
from websockets.frames import CloseCode

from sim_bridge.endpoint import VehicleEndpoint
from sim_bridge.rosbridge import (
    DEFAULT_MAX_MESSAGE_BYTES,
    FRAME_TOPIC,
    MISSION_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
    ClientSession,
    JsonObject,
    Outcome,
    json_string_msg,
    pose_stamped_msg,
    publish_message,
    to_json,
    uint8_multiarray_msg,
)

logger = logging.getLogger("sim_bridge.server")

#: Default tick period of the simulation clock, seconds.
DEFAULT_TICK_S: Final = 0.02
#: Longest simulated step taken in one tick, wall seconds (a stalled loop does not leap).
MAX_TICK_STEP_S: Final = 0.5
#: Default limit on one send to a client, seconds; a client that stalls longer is dropped.
DEFAULT_SEND_TIMEOUT_S: Final = 5.0
#: Default limit on a client's ordered queue (acks, replies), messages.
DEFAULT_MAX_QUEUE: Final = 1000
#: Default hard limit factor: ``hard_max_bytes = HARD_LIMIT_FACTOR * max_message_bytes``.
HARD_LIMIT_FACTOR: Final = 4
#: An endpoint failure is logged the first time and then once per this many in a row.
_FAILURE_LOG_EVERY: Final = 250


class _Client:
    """One websocket connection: its rosbridge session and its outbox.

    The outbox has an ordered queue (acknowledgements, service responses, status messages,
    frame echoes) and a latest-value slot per streamed topic (pose, status). One writer task
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
        self._send_timeout_s = send_timeout_s
        self._max_queue = max_queue
        self._queue: deque[str] = deque()
        self._latest: dict[str, str] = {}
        self._wake = asyncio.Event()
        self._dropped = False

    def enqueue(self, text: str) -> None:
        """Queue a message that must not be skipped; drop the client if it cannot keep up."""
        if self._dropped:
            return
        if len(self._queue) >= self._max_queue:
            self.drop(f"{self._max_queue} messages queued, client not reading")
            return
        self._queue.append(text)
        self._wake.set()

    def offer_latest(self, topic: str, text: str) -> None:
        """Offer the newest message of a streamed topic; replaces one not yet sent."""
        if self._dropped:
            return
        self._latest[topic] = text
        self._wake.set()

    def drop(self, reason: str) -> None:
        """Disconnect at once (no closing handshake: the client is not reading)."""
        if self._dropped:
            return
        self._dropped = True
        logger.warning("client %s: disconnected: %s", self.name, reason)
        self.ws.transport.abort()

    async def run_writer(self) -> None:
        """Send the outbox in order, then the latest streamed messages, until closed."""
        try:
            while True:
                await self._wake.wait()
                self._wake.clear()
                while self._queue or self._latest:
                    if self._queue:
                        text = self._queue.popleft()
                    else:
                        topic = next(iter(self._latest))
                        text = self._latest.pop(topic)
                    await asyncio.wait_for(self.ws.send(text), self._send_timeout_s)
        except TimeoutError:
            self.drop(f"a send took longer than {self._send_timeout_s:g} s")
        except ConnectionClosed:
            pass


class BridgeServer:
    """rosbridge v2 websocket server in front of a :class:`VehicleEndpoint`.

    ``time_scale`` multiplies wall time into simulated time (0 pauses the vehicle).
    ``pose_hz`` and ``status_hz`` are wall-clock publication rates. ``max_message_bytes``
    is the soft limit on one incoming message (UTF-8 bytes): larger messages are dropped
    and logged, the connection stays up. ``hard_max_bytes`` (default 4 x the soft limit)
    is the websocket limit: a larger message closes that connection (code 1009).
    ``port=0`` picks a free port; read :attr:`port` after :meth:`start`.
    """

    def __init__(
        self,
        endpoint: VehicleEndpoint,
        host: str = "127.0.0.1",
        port: int = 9090,
        time_scale: float = 1.0,
        pose_hz: float = 20.0,
        status_hz: float = 2.0,
        max_message_bytes: int = DEFAULT_MAX_MESSAGE_BYTES,
        *,
        hard_max_bytes: int | None = None,
        tick_s: float = DEFAULT_TICK_S,
        send_timeout_s: float = DEFAULT_SEND_TIMEOUT_S,
        max_queue: int = DEFAULT_MAX_QUEUE,
    ) -> None:
        if not time_scale >= 0.0:
            raise ValueError("time_scale must be >= 0")
        if not (pose_hz > 0.0 and status_hz > 0.0):
            raise ValueError("pose_hz and status_hz must be > 0")
        if max_message_bytes <= 0:
            raise ValueError("max_message_bytes must be > 0")
        hard = HARD_LIMIT_FACTOR * max_message_bytes if hard_max_bytes is None else hard_max_bytes
        if hard < max_message_bytes:
            raise ValueError("hard_max_bytes must be >= max_message_bytes")
        if not (tick_s > 0.0 and send_timeout_s > 0.0 and max_queue > 0):
            raise ValueError("tick_s, send_timeout_s and max_queue must be > 0")
        self._endpoint = endpoint
        self._host = host
        self._requested_port = port
        self.time_scale = time_scale
        self._pose_period_s = 1.0 / pose_hz
        self._status_period_s = 1.0 / status_hz
        self.max_message_bytes = max_message_bytes
        self.hard_max_bytes = hard
        # Tick at least twice per pose period so the pose rate holds.
        self._tick_s = min(tick_s, self._pose_period_s / 2.0)
        self._send_timeout_s = send_timeout_s
        self._max_queue = max_queue
        self._server: Server | None = None
        self._tick_task: asyncio.Task[None] | None = None
        self._clients: set[_Client] = set()
        self._client_ids = itertools.count(1)
        self._stopped = asyncio.Event()
        self._failures: dict[str, int] = {}

    # -- lifecycle ---------------------------------------------------------------------------

    @property
    def port(self) -> int:
        """The bound TCP port (useful with ``port=0``). Raises before :meth:`start`."""
        if self._server is None:
            raise RuntimeError("server not started")
        port: int = self._server.sockets[0].getsockname()[1]
        return port

    @property
    def client_count(self) -> int:
        """Connected clients."""
        return len(self._clients)

    async def start(self) -> None:
        """Bind, start accepting clients and start the simulation clock."""
        if self._server is not None:
            raise RuntimeError("server already started")
        self._stopped.clear()
        self._server = await serve(
            self._serve_client,
            self._host,
            self._requested_port,
            max_size=self.hard_max_bytes,
            close_timeout=2.0,
        )
        self._tick_task = asyncio.create_task(self._tick_loop(), name="sim_bridge tick")
        logger.info(
            "rosbridge server on ws://%s:%d (time scale %g, pose %.4g Hz, status %.4g Hz)",
            self._host,
            self.port,
            self.time_scale,
            1.0 / self._pose_period_s,
            1.0 / self._status_period_s,
        )

    async def stop(self) -> None:
        """Stop the clock, close every connection and release the port. Idempotent."""
        if self._tick_task is not None:
            self._tick_task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._tick_task
            self._tick_task = None
        server, self._server = self._server, None
        if server is not None:
            server.close()
            try:
                await asyncio.wait_for(server.wait_closed(), 3.0)
            except TimeoutError:
                for client in list(self._clients):
                    client.drop("server stopping")
                await server.wait_closed()
            logger.info("rosbridge server stopped")
        self._stopped.set()

    async def serve_forever(self) -> None:
        """Start if needed and serve until :meth:`stop` is called (or this task is cancelled)."""
        if self._server is None:
            await self.start()
        try:
            await self._stopped.wait()
        finally:
            await self.stop()

    # -- connections -------------------------------------------------------------------------

    async def _serve_client(self, ws: ServerConnection) -> None:
        name = f"#{next(self._client_ids)} {_peer(ws)}"
        client = _Client(
            ws,
            ClientSession(self.max_message_bytes),
            name,
            self._send_timeout_s,
            self._max_queue,
        )
        self._clients.add(client)
        logger.info("client %s: connected (%d clients)", name, len(self._clients))
        writer = asyncio.create_task(client.run_writer(), name=f"sim_bridge writer {name}")
        try:
            async for message in ws:
                try:
                    self._on_message(client, message)
                except Exception:
                    # A bug here must not cost the client its connection or the vehicle.
                    logger.exception("client %s: internal error on a message, dropped", name)
        except ConnectionClosedError as exc:
            code = exc.rcvd.code if exc.rcvd is not None else None
            sent = exc.sent.code if exc.sent is not None else None
            if sent == CloseCode.MESSAGE_TOO_BIG:
                logger.warning(
                    "client %s: closed: message above the hard limit of %d bytes",
                    name,
                    self.hard_max_bytes,
                )
            else:
                logger.info(
                    "client %s: connection lost (received close %s, sent %s)", name, code, sent
                )
        finally:
            self._clients.discard(client)
            writer.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await writer
            logger.info("client %s: disconnected (%d clients)", name, len(self._clients))

    def _on_message(self, client: _Client, message: str | bytes) -> None:
        if isinstance(message, str):
            outcome = client.session.receive_text(message)
        else:
            outcome = client.session.receive_binary(message)
        self._log_outcome(client, outcome)
        for reply in outcome.replies:
            client.enqueue(to_json(reply))
        if outcome.frame is not None:
            self._submit(client, outcome.frame)

    def _log_outcome(self, client: _Client, outcome: Outcome) -> None:
        if outcome.error is not None:
            error = outcome.error
            tag = f" (id {error.op_id!r})" if error.op_id is not None else ""
            logger.warning(
                "client %s: dropped message%s: %s: %s",
                client.name,
                tag,
                type(error).__name__,
                error.reason,
            )
        elif outcome.notice is not None:
            logger.info("client %s: %s", client.name, outcome.notice)
        elif outcome.request is not None:
            logger.debug("client %s: %r", client.name, outcome.request)

    def _submit(self, client: _Client, frame: bytes) -> None:
        logger.info(
            "client %s: frame of %d bytes to the vehicle: %s", client.name, len(frame), frame.hex()
        )
        self._guard("endpoint.submit_frame", lambda: self._endpoint.submit_frame(frame))
        self._broadcast(
            FRAME_TOPIC, lambda: publish_message(FRAME_TOPIC, uint8_multiarray_msg(frame))
        )

    # -- clock and publishing ----------------------------------------------------------------

    async def _tick_loop(self) -> None:
        loop = asyncio.get_running_loop()
        last = loop.time()
        next_pose = next_status = last
        while True:
            await asyncio.sleep(self._tick_s)
            now = loop.time()
            wall_dt = now - last
            last = now
            if wall_dt > MAX_TICK_STEP_S:
                logger.warning(
                    "event loop stalled %.3f s; simulated time advanced by %.3f s only",
                    wall_dt,
                    MAX_TICK_STEP_S * self.time_scale,
                )
                wall_dt = MAX_TICK_STEP_S
            self.tick(wall_dt * self.time_scale)
            if now >= next_pose:
                next_pose = _next_deadline(next_pose, self._pose_period_s, now)
                self._guard("pose publication", self._publish_pose)
            if now >= next_status:
                next_status = _next_deadline(next_status, self._status_period_s, now)
                self._guard("status publication", self._publish_status)

    def tick(self, sim_dt_s: float) -> None:
        """Advance the vehicle by ``sim_dt_s`` simulated seconds and publish its acks."""
        if sim_dt_s > 0.0:
            self._guard("endpoint.advance", lambda: self._endpoint.advance(sim_dt_s))
        missions = self._guard("endpoint.take_missions", self._endpoint.take_missions)
        for mission in missions or ():
            try:
                text = to_json(publish_message(MISSION_TOPIC, json_string_msg(mission)))
            except (TypeError, ValueError):
                logger.exception("mission acknowledgement not serializable, dropped: %r", mission)
                continue
            for client in self._subscribers(MISSION_TOPIC):
                client.enqueue(text)

    def _publish_pose(self) -> None:
        self._stream(POSE_TOPIC, "endpoint.pose", self._endpoint.pose, pose_stamped_msg)

    def _publish_status(self) -> None:
        self._stream(STATUS_TOPIC, "endpoint.status", self._endpoint.status, json_string_msg)

    def _stream(
        self, topic: str, what: str, read: Callable[[], Any], to_msg: Callable[[Any], JsonObject]
    ) -> None:
        """Offer the newest value of a streamed topic to its subscribers (latest wins); the
        endpoint is only read when someone listens."""
        subscribers = self._subscribers(topic)
        if not subscribers:
            return
        value = self._guard(what, read)
        if value is not None:
            text = to_json(publish_message(topic, to_msg(value)))
            for client in subscribers:
                client.offer_latest(topic, text)

    def _broadcast(self, topic: str, build: Callable[[], JsonObject]) -> None:
        subscribers = self._subscribers(topic)
        if subscribers:
            text = to_json(build())
            for client in subscribers:
                client.enqueue(text)

    def _subscribers(self, topic: str) -> list[_Client]:
        return [client for client in self._clients if client.session.is_subscribed(topic)]

    def _guard(self, what: str, call: Callable[[], Any]) -> Any:
        """Run one step of the clock; a failure is logged (throttled) and gives ``None``.

        The vehicle keeps flying: a failing endpoint call or publication skips only itself.
        """
        try:
            result = call()
        except Exception:
            count = self._failures.get(what, 0) + 1
            self._failures[what] = count
            if count % _FAILURE_LOG_EVERY == 1:
                logger.exception("%s failed (%d in a row)", what, count)
            return None
        if self._failures.pop(what, None):
            logger.info("%s works again", what)
        return result


def _next_deadline(deadline: float, period: float, now: float) -> float:
    """The next publication time: one period on, or one period from now if behind."""
    deadline += period
    return deadline if deadline > now else now + period


def _peer(ws: ServerConnection) -> str:
    try:
        host, port = ws.remote_address[:2]
    except (TypeError, ValueError):
        return "?"
    return f"{host}:{port}"
