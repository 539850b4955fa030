"""The console's link to its vehicle: one persistent connection per target.

* :class:`RosbridgeLink`: a rosbridge v2 websocket (the simulated vehicle, or a real ROS 2
  vehicle running rosbridge_server): advertises ``/nemesys/frame``, subscribes to pose,
  status, mission and datum (every name under the vehicle's namespace, if any), reconnects
  with backoff, hands every message to the console's callbacks.
  On every connection, and every :data:`GRAPH_POLL_S` while connected, it asks rosapi who
  publishes and subscribes the contract's topics (:mod:`station.vehicle_graph`: the one rule,
  shared with ``vehicle-check``) and so learns its :class:`Capability`.
* :mod:`station.link_modem`: an ME modem (frames out, nothing back), and the hybrid link
  (frames over the modem, telemetry and acknowledgements over rosbridge); ``open_link``.

Every link declares its :class:`Capability`: what the vehicle can report back over it.

The connection is the one rosbridge client (:mod:`rosbridge.transport`, over the sans-IO
:class:`rosbridge.client.ClientProtocol`), shared with the station's transmitter and
``nemesys vehicle-check``; this module is what the console makes of it.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import time
from collections.abc import Callable
from typing import Any, Final

from websockets.exceptions import ConnectionClosed, WebSocketException

from codec import Frame
from rosbridge.auth import auth_message
from rosbridge.client import ClientProtocol, decode_json_string
from rosbridge.protocol import (
    MISSION_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
    InvalidData,
)
from rosbridge.transport import RosbridgeClient, TopicHandler
from station.capability import Capability, capability_of
from station.link_acks import SeenAcks
from station.transmit import LinkCheck, failure_reason, frame_msg
from station.vehicle_graph import GraphUnknown, VehicleGraph, read_graph
from vehicle_contract.contract import DATUM_TOPIC
from vehicle_contract.names import topic_names

logger = logging.getLogger("station.link")

__all__ = ["Capability", "Link", "RosbridgeLink", "capability_of"]

Handler = Callable[[dict[str, Any]], None]

#: How long to wait for rosapi's answers (s).
ROSAPI_TIMEOUT_S: Final = 3.0
#: How often a connected link asks the graph again (s): a publisher that appears (the onboard
#: agent started, or the pose publisher after the console subscribed) is seen within it.
GRAPH_POLL_S: Final = 2.0


class Link:
    """What the console needs from a link to a vehicle."""

    def __init__(self, target: str) -> None:
        self.target = target
        self.on_pose: Handler = lambda _m: None
        self.on_status: Handler = lambda _m: None
        self.on_mission: Handler = lambda _m: None
        #: The vehicle's datum message (contract schema ``datum``), when it sends one.
        self.on_datum: Handler = lambda _m: None
        self.last_message_s: float | None = None  # time.monotonic() of the last message
        self._capability = Capability.UNKNOWN
        self._capability_problems: list[str] = []
        #: Why the link is down (None while connected, or before the first try).
        self.connection_problem: str | None = None

    @property
    def capability(self) -> Capability:
        """What the vehicle can report back over this link: the one place the console's
        delivery rules (copies, acknowledgements) read it from."""
        return self._capability

    @capability.setter
    def capability(self, value: Capability) -> None:
        self._capability = value

    @property
    def capability_problems(self) -> list[str]:
        """Why the capability is not more (named problems)."""
        return self._capability_problems

    @capability_problems.setter
    def capability_problems(self, value: list[str]) -> None:
        self._capability_problems = value

    @property
    def acknowledges(self) -> bool:
        """Whether the vehicle's acknowledgements come back over this link."""
        return self.capability.acknowledges

    @property
    def telemetry(self) -> bool:
        """Whether poses and status come back over this link."""
        return self.capability.telemetry

    @property
    def connected(self) -> bool:
        return False

    async def start(self) -> None:
        """Begin connecting (returns at once; the link keeps trying in the background)."""

    async def stop(self) -> None:
        """Close the link."""

    async def transmit(self, frame: Frame) -> str | None:
        """Send one frame; ``None`` when it left the station, else why it could not."""
        raise NotImplementedError

    async def test(self) -> list[LinkCheck]:
        """Check every path of the link now without sending a frame (here: what the link
        knows of its connection; a modem opens and checks its port or gateway)."""
        problem = None if self.connected else self.connection_problem or "not connected"
        detail = f"connected; the vehicle reports: {self.capability.value}"
        return [LinkCheck("rosbridge", self.target, problem is None, problem, problem or detail)]


class RosbridgeLink(Link):
    """A persistent rosbridge connection: frames out, pose/status/mission in.

    Ready (:meth:`wait_connected`) once connected and the graph asked: the capability from it
    (:func:`capability_of`), or :attr:`Capability.UNKNOWN` with the reason when rosapi does not
    answer within ``rosapi_timeout_s``; then an acknowledgement that arrives anyway proves the
    onboard agent runs. While connected the graph is asked again every ``graph_poll_s``: the
    capability follows it (a failed question keeps the last answer), and a subscribed topic
    that gained a publisher is subscribed again, since rosbridge fixed the subscription's QoS
    from the publishers there when it was made (RELIABLE unless a BEST_EFFORT one was there:
    a best-effort pose publisher that starts later is not heard until then). Every connection
    subscribes afresh. Acknowledgements survive a short reconnect through the status's
    ``recent_acks`` (the vehicle contract: the last ones, as published): those the link has
    not delivered go to the console, and one delivered again (that, or a transient-local
    replay) goes to it once.
    """

    def __init__(
        self,
        target: str,
        open_timeout_s: float = 3.0,
        rosapi_timeout_s: float = ROSAPI_TIMEOUT_S,
        auth_secret: str | None = None,
        namespace: str = "",
        *,
        frames: bool = True,
        graph_poll_s: float = GRAPH_POLL_S,
    ) -> None:
        super().__init__(target)
        #: The contract's topic names on this vehicle (``namespace``: its ROS namespace).
        self.names = topic_names(namespace)
        #: Frames go out over this connection (False: telemetry and acknowledgements only, the
        #: frames going by an ME modem: :class:`station.link_modem.HybridLink`).
        self.frames = frames
        #: The training bridge's secret: the link authenticates first (``auth`` op).
        self.auth_secret = auth_secret
        self.open_timeout_s = open_timeout_s
        self.rosapi_timeout_s = rosapi_timeout_s
        self.graph_poll_s = graph_poll_s
        self._client: RosbridgeClient | None = None
        self._task: asyncio.Task[None] | None = None
        self._ready = asyncio.Event()
        names = self.names
        self._protocol = ClientProtocol(
            advertise=[names.frame] if frames else [],
            subscribe=[names.pose, names.status, names.mission, names.datum],
        )
        #: What each subscribed topic's messages go to.
        self._handlers: dict[str, TopicHandler] = {
            names.pose: self._pose,
            names.status: self._status,
            names.mission: self._mission,
            names.datum: self._datum,
        }
        #: Each contract topic -> its name on this vehicle (asked about, subscribed to).
        self._names = names.by_topic()
        #: The contract topics subscribed to: subscribed again when they gain a publisher (the
        #: optional datum only once a node publishes it).
        self._subscribed = (POSE_TOPIC, STATUS_TOPIC, MISSION_TOPIC, DATUM_TOPIC)
        #: On this connection: the graph answered once; an acknowledgement arrived.
        self._graph_known = False
        self._acked = False
        self._unknown: GraphUnknown | None = None
        #: The acknowledgements delivered, over every connection.
        self._seen = SeenAcks()

    @property
    def connected(self) -> bool:
        return self._client is not None

    async def start(self) -> None:
        self._task = asyncio.create_task(self._run(), name=f"link {self.target}")

    async def wait_connected(self, timeout_s: float) -> bool:
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(self._ready.wait(), timeout_s)
        return self.connected

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
            self._task = None

    async def _run(self) -> None:
        backoff = 0.2
        while True:
            client: RosbridgeClient | None = None
            try:
                client = await RosbridgeClient.connect(
                    self.target,
                    self._protocol,
                    self._handlers,
                    open_timeout_s=self.open_timeout_s,
                    logger=logger,
                )
                if self.auth_secret is not None:
                    auth = auth_message(
                        self.auth_secret, "nemesys-console", self.target, time.time()
                    )
                    await client.send(json.dumps(auth))
                self._graph_known = self._acked = False
                self._unknown = None
                # asked before subscribing: the publishers each subscription is made with
                graph = await read_graph(client, self.rosapi_timeout_s, names=self._names)
                await client.open()
                self._client = client
                self.connection_problem = None
                backoff = 0.2
                logger.info("link to %s up", self.target)
                await self._watch(client, graph)
            except asyncio.CancelledError:
                raise
            except (OSError, WebSocketException, TimeoutError) as err:
                self.connection_problem = f"not connected to {self.target}: {failure_reason(err)}"
                logger.warning("link to %s: %s", self.target, failure_reason(err))
            finally:
                if self._client is not None:
                    self.connection_problem = f"the connection to {self.target} closed"
                self._client = None
                self._ready.clear()
                self._set_capability(Capability.UNKNOWN, [])
                if client is not None:
                    await client.close()
            await asyncio.sleep(backoff)
            backoff = min(backoff * 2, 5.0)

    async def _watch(self, client: RosbridgeClient, graph: VehicleGraph | GraphUnknown) -> None:
        """Follow the graph until the connection closes (see the class doc)."""
        bridges: frozenset[str] | None = None
        subscribed_with: dict[str, frozenset[str]] | None = None
        while True:
            self._on_graph(graph)
            if isinstance(graph, VehicleGraph):
                bridges = graph.bridges
                now = {t: frozenset(graph.publishers.get(t, ())) for t in self._subscribed}
                if subscribed_with is not None:
                    grown = [
                        self._names[t] for t in now if now[t] - subscribed_with.get(t, frozenset())
                    ]
                    if grown:
                        logger.info(
                            "link to %s: new publishers on %s: subscribing again",
                            self.target,
                            ", ".join(grown),
                        )
                        await client.send(*self._protocol.resubscribe(grown))
                subscribed_with = now
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(client.wait_closed(), self.graph_poll_s)
            if client.closed:
                return
            graph = await read_graph(client, self.rosapi_timeout_s, bridges, self._names)

    def _set_capability(self, capability: Capability, problems: list[str]) -> None:
        self.capability = capability
        self.capability_problems = problems
        if self._client is not None and capability is not Capability.UNKNOWN:
            self._ready.set()

    def _on_graph(self, graph: VehicleGraph | GraphUnknown) -> None:
        if isinstance(graph, VehicleGraph):
            self._graph_known = True
            capability, problems = capability_of(graph, frames_over_rosbridge=self.frames)
            if capability is not self.capability:
                logger.info("link to %s: %s", self.target, capability)
            self._set_capability(capability, problems)
        elif not self._graph_known:  # once known, a failed question keeps the last answer
            self._unknown = graph
            why = f"{graph}: acknowledgements are not expected; commands go as repeated copies"
            if self._acked:
                self._set_capability(Capability.ACKS_AND_TELEMETRY, [str(graph)])
            else:
                self._set_capability(Capability.UNKNOWN, [why])
        else:
            logger.warning("link to %s: %s (keeping the last answer)", self.target, graph)
        self._ready.set()

    # --- what the vehicle publishes (called by the client, on the event loop) ---------------

    def _pose(self, msg: object) -> None:
        self.last_message_s = time.monotonic()
        if isinstance(msg, dict):
            self.on_pose(msg)

    def _status(self, msg: object) -> None:
        self.last_message_s = time.monotonic()
        body = self._json(self.names.status, msg)
        if body is None:
            return
        recent = body.get("recent_acks")
        if isinstance(recent, list):
            # the vehicle's last acknowledgements: one published while the console
            # reconnected is not lost (those in the first status read predate the console)
            for ack in self._seen.missed(recent):
                logger.info(
                    "link: acknowledgement seq=%s from the status's recent_acks", ack["seq"]
                )
                self._take_ack(ack)
        self.on_status(body)

    def _mission(self, msg: object) -> None:
        self.last_message_s = time.monotonic()
        body = self._json(self.names.mission, msg)
        if body is not None:
            self._take_ack(body)

    def _take_ack(self, ack: dict[str, Any]) -> None:
        """One acknowledgement to the console, unless it went already (a repeat: a transient-
        local replay, or the status's recent_acks)."""
        if not self._seen.first(ack):
            logger.debug("link: acknowledgement seq=%s delivered already", ack.get("seq"))
            return
        self._acked = True
        if not self._graph_known and not self.capability.acknowledges:
            # rosapi cannot tell: an acknowledgement is proof the onboard agent runs
            why = [] if self._unknown is None else [str(self._unknown)]
            self._set_capability(Capability.ACKS_AND_TELEMETRY, why)
        self.on_mission(ack)

    def _datum(self, msg: object) -> None:
        body = self._json(self.names.datum, msg)
        if body is not None:
            self.on_datum(body)

    @staticmethod
    def _json(topic: str, msg: object) -> dict[str, Any] | None:
        try:
            return decode_json_string(msg)
        except InvalidData as error:
            logger.warning("link: ignoring a %s message: %s", topic, error.reason)
            return None

    async def transmit(self, frame: Frame) -> str | None:
        client = self._client
        if not self.frames:
            return f"frames do not go over {self.target} (telemetry only)"
        if client is None:
            return "not connected to the vehicle"
        try:
            await client.publish(self.names.frame, frame_msg(frame))
        except (OSError, ConnectionClosed) as err:
            return failure_reason(err)
        return None
