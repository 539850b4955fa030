"""The simulated vehicle's rosbridge v2 websocket server (``websockets`` asyncio API).

:class:`BridgeServer` exposes any :class:`~vehicle_contract.endpoint.VehicleEndpoint` the way a real
ROS 2 vehicle running ``rosbridge_server`` and ``rosapi`` does (the NemeSys topics, and the
server's own ``/rosout``, ``/client_count``, ``/connected_clients``). The protocol is
:mod:`rosbridge.protocol` (sans-IO); this module does the IO, the clocks and the logging.

A tick task advances the endpoint by the elapsed wall time times ``time_scale`` every
``tick_s``, publishes every acknowledgement, the pose at ``pose_hz``, the status at
``status_hz``, and what queued subscriptions release. Endpoint calls happen on the server's
event loop, one at a time. Each connection has its own session and outbox
(:mod:`rosbridge.outbox`), so a slow client only slows itself.

As the ROS 2 server, nothing is sent back for a failed message: it is logged on
``rosbridge.server`` and published on ``/rosout`` (``rcl_interfaces/msg/Log``, node
``rosbridge_websocket``: :mod:`rosbridge.rosout`). A message above ``hard_max_bytes`` (10 MiB,
tornado's limit) closes that connection (1009). The endpoint never sees a malformed message.
"""

from __future__ import annotations

import asyncio
import contextlib
import http
import itertools
import logging
import time
from collections.abc import Callable, Iterable
from typing import Any, Final

from websockets.asyncio.server import Server, ServerConnection, serve
from websockets.exceptions import ConnectionClosedError
from websockets.frames import CloseCode
from websockets.http11 import Request, Response

from rosbridge.auth import AuthGate
from rosbridge.outbox import (
    DEFAULT_MAX_QUEUE,
    DEFAULT_SEND_TIMEOUT_S,
    ClientOutbox,
    EndpointGuard,
    peer_of,
)
from rosbridge.protocol import (
    CLIENT_COUNT_TOPIC,
    CONNECTED_CLIENTS_TOPIC,
    DEFAULT_MAX_MESSAGE_BYTES,
    BridgeError,
    ClientSession,
    Graph,
    JsonObject,
    LogLine,
    Outcome,
    connected_clients_msg,
    json_string_msg,
    pose_stamped_msg,
)
from rosbridge.rosout import BridgeLog
from vehicle_contract.endpoint import FleetEndpoint, VehicleEndpoint
from vehicle_contract.names import TopicNames, topic_names

logger = logging.getLogger("rosbridge.server")

#: Default tick period of the simulation clock, seconds.
DEFAULT_TICK_S: Final = 0.02
#: Longest simulated step taken in one tick, wall seconds (a stalled loop does not leap).
MAX_TICK_STEP_S: Final = 0.5


class BridgeServer:
    """rosbridge v2 websocket server in front of a :class:`VehicleEndpoint`.

    ``time_scale`` multiplies wall time into simulated time (0 pauses the vehicle).
    ``pose_hz`` and ``status_hz`` are wall-clock publication rates. ``max_message_bytes`` is
    the limit on one incoming message (UTF-8 bytes): a larger one is dropped and logged, the
    connection stays up. ``hard_max_bytes`` (default: ``max_message_bytes``) is the websocket
    limit: a larger message closes that connection (code 1009), as tornado does above 10 MiB.
    ``url_path`` is the only path served (``"/"``, as the real server; others get 404);
    ``None`` serves any path. ``port=0`` picks a free port; read :attr:`port` after
    :meth:`start`. With ``auth_secret`` (the console's training bridge) a client may publish
    only after the ``auth`` op (:mod:`rosbridge.auth`); before it may subscribe.

    A :class:`~vehicle_contract.endpoint.FleetEndpoint` (``nemesys sim --vehicles``) is served
    on one server: each vehicle's node and topics under its namespace (``/auv1/nemesys/pose``,
    node ``/auv1/nemesys_vehicle``), its pose, status and acknowledgements published there, and
    a frame published on any vehicle's frame topic or on ``/nemesys/frame`` (the station's
    transmitter, node ``/nemesys_me_transmitter``) handed once to the fleet's shared link.
    """

    def __init__(
        self,
        endpoint: VehicleEndpoint | FleetEndpoint,
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
        url_path: str | None = "/",
        auth_secret: str | None = None,
    ) -> None:
        if not time_scale >= 0.0:
            raise ValueError("time_scale must be >= 0")
        if not (pose_hz > 0.0 and status_hz > 0.0):
            raise ValueError("pose_hz and status_hz must be > 0")
        if max_message_bytes <= 0:
            raise ValueError("max_message_bytes must be > 0")
        hard = max_message_bytes if hard_max_bytes is None else hard_max_bytes
        if hard < max_message_bytes:
            raise ValueError("hard_max_bytes must be >= max_message_bytes")
        if not (tick_s > 0.0 and send_timeout_s > 0.0 and max_queue > 0):
            raise ValueError("tick_s, send_timeout_s and max_queue must be > 0")
        self._endpoint = endpoint
        #: Each vehicle with its topic names: the one endpoint under the contract's names, or
        #: a fleet's vehicles under their namespaces.
        self._vehicles: tuple[tuple[TopicNames, VehicleEndpoint], ...] = (
            tuple((topic_names(ns), v) for ns, v in endpoint.members.items())
            if isinstance(endpoint, FleetEndpoint)
            else ((topic_names(), endpoint),)
        )
        #: Topics streamed latest-wins to each client (every vehicle's pose and status).
        self._streamed = frozenset(
            name for names, _ in self._vehicles for name in (names.pose, names.status)
        )
        self._host = host
        self._requested_port = port
        self.time_scale = time_scale
        self._pose_period_s = 1.0 / pose_hz
        self._status_period_s = 1.0 / status_hz
        self.max_message_bytes = max_message_bytes
        self.hard_max_bytes = hard
        self.url_path = url_path
        self.auth_secret = auth_secret
        # Tick at least twice per pose period so the pose rate holds.
        self._tick_s = min(tick_s, self._pose_period_s / 2.0)
        self._send_timeout_s = send_timeout_s
        self._max_queue = max_queue
        self.graph = Graph(
            clock=time.monotonic,
            ros_time=self._ros_time,
            namespaces=(tuple(endpoint.members) if isinstance(endpoint, FleetEndpoint) else ()),
        )
        self._server: Server | None = None
        self._tick_task: asyncio.Task[None] | None = None
        self._clients: set[ClientOutbox] = set()
        self._client_ids = itertools.count(1)
        self._stopped = asyncio.Event()
        self._guard = EndpointGuard()
        self._log = BridgeLog(self._publish, self._ros_time)
        self._publish_clients()

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
            compression=None,  # tornado's default: no permessage-deflate
            process_request=self._check_path,
        )
        self._tick_task = asyncio.create_task(self._tick_loop(), name="rosbridge tick")
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

    def _check_path(self, ws: ServerConnection, request: Request) -> Response | None:
        path = request.path.split("?", 1)[0]
        if self.url_path is None or path == self.url_path:
            return None
        return ws.respond(http.HTTPStatus.NOT_FOUND, "404: Not Found\n")

    async def _serve_client(self, ws: ServerConnection) -> None:
        name = f"#{next(self._client_ids)} {peer_of(ws)}"
        gate = AuthGate(self.auth_secret) if self.auth_secret is not None else None
        session = ClientSession(self.max_message_bytes, self.graph, auth=gate)
        client = ClientOutbox(ws, session, name, self._send_timeout_s, self._max_queue)
        client.connected_at = self._ros_time()
        self._clients.add(client)
        self._log.node(name, f"Client connected. {len(self._clients)} clients total.")
        self._publish_clients()
        writer = asyncio.create_task(client.run_writer(), name=f"rosbridge writer {name}")
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
                    "client %s: closed: message above the limit of %d bytes",
                    name,
                    self.hard_max_bytes,
                )
            else:
                logger.info(
                    "client %s: connection lost (received close %s, sent %s)", name, code, sent
                )
        finally:
            self._clients.discard(client)
            session.close()
            writer.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await writer
            self._log.node(name, f"Client disconnected. {len(self._clients)} clients total.")
            self._publish_clients()

    def _on_message(self, client: ClientOutbox, message: str | bytes) -> None:
        session = client.session
        if isinstance(message, str):
            outcomes = session.receive(message)
        else:
            outcomes = session.receive_binary(message)
        for outcome in outcomes:
            self._act(client, outcome)

    def _act(self, client: ClientOutbox, outcome: Outcome) -> None:
        self._log_lines(client, outcome.logs)
        if outcome.request is not None and outcome.error is None:
            logger.debug("client %s: %r", client.name, outcome.request)
        for reply in outcome.replies:
            try:
                client.enqueue(*client.session.encode(reply))
            except BridgeError as error:
                self._log_lines(client, [LogLine(40, f"{reply['op']}: {error.reason}")])
        client.enqueue(*outcome.texts)
        publication = outcome.publication
        if publication is not None:
            if publication.frame is not None:
                self._submit(client, publication.frame)
            self._publish(publication.topic, publication.msg)
        if outcome.close:
            client.drop("the real server drops a connection that sends non-UTF-8 binary")

    def _log_lines(self, client: ClientOutbox, lines: Iterable[LogLine]) -> None:
        self._log.lines(client.name, client.session.client_id, lines)

    def _submit(self, client: ClientOutbox, frame: bytes) -> None:
        logger.info(
            "client %s: frame of %d bytes to the vehicle: %s", client.name, len(frame), frame.hex()
        )
        self._guard("endpoint.submit_frame", lambda: self._endpoint.submit_frame(frame))

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
            for client in list(self._clients):
                client.enqueue(*client.session.poll())
                self._log_lines(client, client.session.drain_logs())

    def tick(self, sim_dt_s: float) -> None:
        """Advance the vehicle (every vehicle of a fleet) by ``sim_dt_s`` simulated seconds and
        publish its acks."""
        if sim_dt_s > 0.0:
            self._guard("endpoint.advance", lambda: self._endpoint.advance(sim_dt_s))
        for names, vehicle in self._vehicles:
            missions = self._guard("endpoint.take_missions", vehicle.take_missions)
            for mission in missions or ():
                try:
                    msg = json_string_msg(mission)
                except (TypeError, ValueError):
                    logger.exception(
                        "mission acknowledgement not serializable, dropped: %r", mission
                    )
                    continue
                self._publish(names.mission, msg)

    def _publish_pose(self) -> None:
        for names, vehicle in self._vehicles:
            self._stream(names.pose, "endpoint.pose", vehicle.pose, pose_stamped_msg)

    def _publish_status(self) -> None:
        for names, vehicle in self._vehicles:
            self._stream(names.status, "endpoint.status", vehicle.status, json_string_msg)

    def _stream(
        self, topic: str, what: str, read: Callable[[], Any], to_msg: Callable[[Any], JsonObject]
    ) -> None:
        """Publish the newest value of a streamed topic; the endpoint is only read when
        someone listens."""
        if not self._subscribers(topic):
            return
        value = self._guard(what, read)
        if value is not None:
            self._publish(topic, to_msg(value))

    def _publish(self, topic: str, msg: JsonObject) -> None:
        """A message on ``topic`` (absolute name) to every client subscribed to it, through
        each client's subscription (throttle, queue, fragments)."""
        for client in self._subscribers(topic):
            texts = client.session.deliver(topic, msg)
            if topic in self._streamed:
                client.offer_latest(topic, *texts)
            else:
                client.enqueue(*texts)
            self._log_lines(client, client.session.drain_logs())

    def _publish_clients(self) -> None:
        """/client_count and /connected_clients: latched, republished on every change."""
        count = {"data": len(self._clients)}
        clients = connected_clients_msg(
            [(peer_of(c.ws).rsplit(":", 1)[0], c.connected_at) for c in self._clients]
        )
        for topic, msg in ((CLIENT_COUNT_TOPIC, count), (CONNECTED_CLIENTS_TOPIC, clients)):
            self.graph.latched[topic] = msg
            self._publish(topic, msg)

    def _subscribers(self, topic: str) -> list[ClientOutbox]:
        return [client for client in self._clients if client.session.is_subscribed(topic)]

    def _ros_time(self) -> float:
        try:
            return float(self._endpoint.t_s)
        except Exception:
            return 0.0


def _next_deadline(deadline: float, period: float, now: float) -> float:
    """The next publication time: one period on, or one period from now if behind."""
    deadline += period
    return deadline if deadline > now else now + period
