"""The console's link to its vehicle: one persistent connection per target.

* :class:`RosbridgeLink`: a rosbridge v2 websocket (the simulated vehicle, or a real ROS 2
  vehicle running rosbridge_server): advertises ``/nemesys/frame``, subscribes to pose,
  status, mission and datum (every name under the vehicle's namespace, if any), reconnects
  with backoff, hands every message to the console's callbacks.
  On every connection it asks ``/rosapi/topics`` what the vehicle publishes and so learns its
  :class:`Capability`.
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
from enum import StrEnum
from typing import Any, Final

from websockets.exceptions import ConnectionClosed, WebSocketException

from codec import Frame
from rosbridge.auth import auth_message
from rosbridge.client import ClientProtocol, decode_json_string, topics_listing
from rosbridge.protocol import (
    FRAME_TOPIC,
    MISSION_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
    TOPIC_TYPES,
    TOPICS_SERVICE,
    InvalidData,
    canonical_type,
    same_type,
)
from rosbridge.transport import RosbridgeClient, TopicHandler
from station.transmit import LinkCheck, failure_reason, frame_msg
from vehicle_contract.contract import TopicNames, topic_name, topic_names

logger = logging.getLogger("station.link")

Handler = Callable[[dict[str, Any]], None]

#: How long to wait for the answer of ``/rosapi/topics`` after connecting (s).
ROSAPI_TIMEOUT_S: Final = 3.0


class Capability(StrEnum):
    """What a vehicle can report back over its link."""

    #: The vehicle runs the onboard agent: acknowledgements and telemetry.
    ACKS_AND_TELEMETRY = "acks_and_telemetry"
    #: A ROS 2 vehicle without the agent: pose / status, no acknowledgements.
    TELEMETRY_ONLY = "telemetry_only"
    #: An ME modem: nothing comes back.
    NONE = "none"
    #: Not known yet (not connected, or the vehicle could not be asked).
    UNKNOWN = "unknown"

    @property
    def acknowledges(self) -> bool:
        return self is Capability.ACKS_AND_TELEMETRY

    @property
    def telemetry(self) -> bool:
        return self in (Capability.ACKS_AND_TELEMETRY, Capability.TELEMETRY_ONLY)


def capability_of(
    topics: dict[str, str], names: TopicNames | None = None
) -> tuple[Capability, list[str]]:
    """What a vehicle publishing ``topics`` (``{name: type}``, either ROS type spelling) can
    report back, and a named problem for every contract topic missing or of the wrong type.
    ``names``: the contract's topics on this vehicle (its namespace; default none)."""
    problems: list[str] = []
    namespace = names.namespace if names is not None else ""

    def has(base: str) -> bool:
        topic = topic_name(base, namespace)
        if topic not in topics:
            return False
        if not same_type(topics[topic], TOPIC_TYPES[base]):
            problems.append(
                f"{topic} is a {topics[topic]}, not a {canonical_type(TOPIC_TYPES[base])}: "
                "it is ignored"
            )
            return False
        return True

    mission, pose, status = has(MISSION_TOPIC), has(POSE_TOPIC), has(STATUS_TOPIC)
    if topic_name(FRAME_TOPIC, namespace) in topics:
        has(FRAME_TOPIC)  # a wrong type is named; absent is fine: the console advertises it
    if not mission:
        problems.insert(
            0,
            f"no {topic_name(MISSION_TOPIC, namespace)} topic: the vehicle runs no onboard "
            "agent; commands are sent without acknowledgement",
        )
    if not pose:
        problems.append(
            f"no {topic_name(POSE_TOPIC, namespace)} topic: the vehicle's position is not known"
        )
    if not status:
        problems.append(
            f"no {topic_name(STATUS_TOPIC, namespace)} topic: no depth, battery or mode from "
            "the vehicle"
        )
    if mission:
        return Capability.ACKS_AND_TELEMETRY, problems
    if pose or status:
        return Capability.TELEMETRY_ONLY, problems
    return Capability.NONE, problems


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

    Ready (:meth:`wait_connected`) once connected and the capability is known: from the
    answer of ``/rosapi/topics``, or :attr:`Capability.UNKNOWN` with the reason when it does
    not answer within ``rosapi_timeout_s``. An acknowledgement that arrives anyway proves the
    onboard agent runs.
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
                await client.open()
                # what the vehicle publishes, asked again on every connection
                self._set_capability(Capability.UNKNOWN, ["asking /rosapi/topics"])
                self._client = client
                self.connection_problem = None
                backoff = 0.2
                logger.info("link to %s up", self.target)
                answer = await client.call_service(TOPICS_SERVICE, timeout_s=self.rosapi_timeout_s)
                if answer is not None:
                    self._on_topics(answer)
                elif not client.closed:
                    self._rosapi_silent()
                await client.wait_closed()
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

    def _set_capability(self, capability: Capability, problems: list[str]) -> None:
        self.capability = capability
        self.capability_problems = problems
        if self._client is not None and capability is not Capability.UNKNOWN:
            self._ready.set()

    def _rosapi_silent(self) -> None:
        self._set_capability(
            Capability.UNKNOWN,
            [
                f"no answer from {TOPICS_SERVICE} in {self.rosapi_timeout_s:g} s (rosapi not "
                "running?): acknowledgements are not expected; commands are sent as repeated "
                "copies"
            ],
        )
        self._ready.set()

    def _on_topics(self, message: dict[str, Any]) -> None:
        if message.get("result") is False:
            self._set_capability(
                Capability.UNKNOWN,
                [f"{TOPICS_SERVICE} failed: {str(message.get('values'))[:120]}"],
            )
            self._ready.set()
            return
        try:
            topics = topics_listing(message.get("values"))
        except InvalidData as error:
            self._set_capability(Capability.UNKNOWN, [f"{TOPICS_SERVICE}: {error.reason}"])
            self._ready.set()
            return
        capability, problems = capability_of(topics, self.names)
        self._set_capability(capability, problems)
        logger.info("link to %s: %s", self.target, capability)

    # --- what the vehicle publishes (called by the client, on the event loop) ---------------

    def _pose(self, msg: object) -> None:
        self.last_message_s = time.monotonic()
        if isinstance(msg, dict):
            self.on_pose(msg)

    def _status(self, msg: object) -> None:
        self.last_message_s = time.monotonic()
        body = self._json(self.names.status, msg)
        if body is not None:
            self.on_status(body)

    def _mission(self, msg: object) -> None:
        self.last_message_s = time.monotonic()
        body = self._json(self.names.mission, msg)
        if body is None:
            return
        if not self.capability.acknowledges:
            # an acknowledgement is proof the onboard agent runs
            self._set_capability(Capability.ACKS_AND_TELEMETRY, [])
        self.on_mission(body)

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
