"""The console's link to its vehicle: one persistent connection per target.

* :class:`RosbridgeLink`: a rosbridge v2 websocket (the simulated vehicle, or a real ROS 2
  vehicle running rosbridge_server): advertises ``/nemesys/frame``, subscribes to pose,
  status and mission, reconnects with backoff, hands every message to the console's callbacks.
  On every connection it asks ``/rosapi/topics`` what the vehicle publishes and so learns its
  :class:`Capability`.
* :class:`ModemLink`: an ME transmitter on a serial port or behind a TCP gateway
  (:class:`station.transmit.SerialTransmitter`): frames out, nothing back.

Every link declares its :class:`Capability`: what the vehicle can report back over it.

The protocol side (the messages, :class:`rosbridge.client.ClientProtocol`, and their
decoding) lives in :mod:`rosbridge.client`, shared with the station's transmitter; this
module is the transport.
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

from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed, InvalidURI

from codec import Frame
from rosbridge.auth import auth_message
from rosbridge.client import (
    ClientProtocol,
    decode_json_string,
    decode_server_message,
    topics_listing,
)
from rosbridge.protocol import (
    FRAME_TOPIC,
    MISSION_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
    TOPIC_TYPES,
    TOPICS_SERVICE,
    BinaryMessage,
    BridgeError,
    InvalidData,
    canonical_type,
    same_type,
)
from station.transmit import failure_reason, frame_msg, open_transmitter

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


def capability_of(topics: dict[str, str]) -> tuple[Capability, list[str]]:
    """What a vehicle publishing ``topics`` (``{name: type}``, either ROS type spelling) can
    report back, and a named problem for every contract topic missing or of the wrong type."""
    problems: list[str] = []

    def has(topic: str) -> bool:
        if topic not in topics:
            return False
        if not same_type(topics[topic], TOPIC_TYPES[topic]):
            problems.append(
                f"{topic} is a {topics[topic]}, not a {canonical_type(TOPIC_TYPES[topic])}: "
                "it is ignored"
            )
            return False
        return True

    mission, pose, status = has(MISSION_TOPIC), has(POSE_TOPIC), has(STATUS_TOPIC)
    if FRAME_TOPIC in topics:
        has(FRAME_TOPIC)  # a wrong type is named; absent is fine: the console advertises it
    if not mission:
        problems.insert(
            0,
            f"no {MISSION_TOPIC} topic: the vehicle runs no onboard agent; commands are sent "
            "without acknowledgement",
        )
    if not pose:
        problems.append(f"no {POSE_TOPIC} topic: the vehicle's position is not known")
    if not status:
        problems.append(f"no {STATUS_TOPIC} topic: no depth, battery or mode from the vehicle")
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
        self.last_message_s: float | None = None  # time.monotonic() of the last message
        #: What the vehicle can report back, and why not more (named problems).
        self.capability = Capability.UNKNOWN
        self.capability_problems: list[str] = []
        #: Why the link is down (None while connected, or before the first try).
        self.connection_problem: str | None = None

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
    ) -> None:
        super().__init__(target)
        #: The training bridge's secret: the link authenticates first (``auth`` op).
        self.auth_secret = auth_secret
        self.open_timeout_s = open_timeout_s
        self.rosapi_timeout_s = rosapi_timeout_s
        self._conn: ClientConnection | None = None
        self._task: asyncio.Task[None] | None = None
        self._ready = asyncio.Event()
        self._rosapi_id: str | None = None
        self._protocol = ClientProtocol(
            advertise=[FRAME_TOPIC], subscribe=[POSE_TOPIC, STATUS_TOPIC, MISSION_TOPIC]
        )

    @property
    def connected(self) -> bool:
        return self._conn is not None

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
        if self._conn is not None:
            await self._conn.close()
            self._conn = None

    async def _run(self) -> None:
        backoff = 0.2
        while True:
            try:
                async with connect(
                    self.target, open_timeout=self.open_timeout_s, max_size=2**22, proxy=None
                ) as conn:
                    if self.auth_secret is not None:
                        auth = auth_message(
                            self.auth_secret, "nemesys-console", self.target, time.time()
                        )
                        await conn.send(json.dumps(auth))
                    for opening in self._protocol.open_messages():
                        await conn.send(opening)
                    # what the vehicle publishes, asked again on every connection
                    self._set_capability(Capability.UNKNOWN, ["asking /rosapi/topics"])
                    self._rosapi_id, ask = self._protocol.call_service(TOPICS_SERVICE)
                    await conn.send(ask)
                    self._conn = conn
                    self.connection_problem = None
                    backoff = 0.2
                    logger.info("link to %s up", self.target)
                    timer = asyncio.get_running_loop().call_later(
                        self.rosapi_timeout_s, self._rosapi_silent
                    )
                    try:
                        async for message in conn:
                            self._dispatch(message)
                    finally:
                        timer.cancel()
            except asyncio.CancelledError:
                raise
            except (OSError, ConnectionClosed, InvalidURI, TimeoutError) as err:
                self.connection_problem = f"not connected to {self.target}: {failure_reason(err)}"
                logger.warning("link to %s: %s", self.target, failure_reason(err))
            finally:
                if self._conn is not None:
                    self.connection_problem = f"the connection to {self.target} closed"
                self._conn = None
                self._ready.clear()
                self._set_capability(Capability.UNKNOWN, [])
            await asyncio.sleep(backoff)
            backoff = min(backoff * 2, 5.0)

    def _set_capability(self, capability: Capability, problems: list[str]) -> None:
        self.capability = capability
        self.capability_problems = problems
        if self._conn is not None and capability is not Capability.UNKNOWN:
            self._ready.set()

    def _rosapi_silent(self) -> None:
        if self._rosapi_id is None:
            return
        self._rosapi_id = None
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
        self._rosapi_id = None
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
        capability, problems = capability_of(topics)
        self._set_capability(capability, problems)
        logger.info("link to %s: %s", self.target, capability)

    def _dispatch(self, data: str | bytes) -> None:
        try:
            message = decode_server_message(data)
        except BinaryMessage:
            return
        except BridgeError as error:
            logger.warning("link: ignoring %s", error.reason)
            return
        op = message.get("op")
        if op == "service_response" and message.get("id") == self._rosapi_id:
            self._on_topics(message)
            return
        if op != "publish":
            return
        self.last_message_s = time.monotonic()
        topic, msg = message.get("topic"), message.get("msg")
        if not isinstance(msg, dict):
            return
        try:
            if topic == POSE_TOPIC:
                handler, body = self.on_pose, msg
            elif topic in (STATUS_TOPIC, MISSION_TOPIC):
                handler = self.on_status if topic == STATUS_TOPIC else self.on_mission
                body = decode_json_string(msg)
                if topic == MISSION_TOPIC and not self.capability.acknowledges:
                    # an acknowledgement is proof the onboard agent runs
                    self._set_capability(Capability.ACKS_AND_TELEMETRY, [])
            else:
                return
        except InvalidData as error:
            logger.warning("link: ignoring a %s message: %s", topic, error.reason)
            return
        try:
            handler(body)
        except Exception:  # a console bug must not take the link down
            logger.exception("link: handler for %s failed", topic)

    async def transmit(self, frame: Frame) -> str | None:
        conn = self._conn
        if conn is None:
            return "not connected to the vehicle"
        try:
            await conn.send(self._protocol.publish(FRAME_TOPIC, frame_msg(frame)))
        except (OSError, ConnectionClosed) as err:
            return failure_reason(err)
        return None


class ModemLink(Link):
    """An ME modem on a serial port or TCP gateway: one-way, no acknowledgements."""

    def __init__(self, target: str, bitrate_bps: float) -> None:
        super().__init__(target)
        self._tx = open_transmitter(target, bitrate_bps=bitrate_bps)
        self.capability = Capability.NONE
        self.capability_problems = [
            "an ME modem link is one-way: commands go out as repeated copies, with no "
            "acknowledgement and no telemetry"
        ]
        self._lock = asyncio.Lock()

    @property
    def connected(self) -> bool:
        """Until a frame fails to leave (the modem is only opened to send)."""
        return self.connection_problem is None

    async def stop(self) -> None:
        await self._tx.aclose()

    async def transmit(self, frame: Frame) -> str | None:
        async with self._lock:
            result = await self._tx.send_async(frame, wait_ack_s=0.0)
        self.connection_problem = (
            None
            if result.sent
            else f"the last frame did not reach the modem at {self.target}: {result.reason}"
        )
        return None if result.sent else (result.reason or "not sent")


def open_link(target: str, bitrate_bps: float) -> Link:
    """The link for a target: ``ws://`` -> rosbridge, anything else -> an ME modem."""
    if target.startswith(("ws://", "wss://")):
        return RosbridgeLink(target)
    return ModemLink(target, bitrate_bps)
