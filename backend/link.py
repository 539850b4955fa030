"""The console's link to its vehicle: one persistent connection per target.

* :class:`RosbridgeLink`: a rosbridge v2 websocket (the simulated vehicle, or a real ROS 2
  vehicle running rosbridge_server): advertises ``/nemesys/frame``, subscribes to pose,
  status and mission, reconnects with backoff, hands every message to the console's callbacks.
* :class:`ModemLink`: an ME transmitter on a serial port or behind a TCP gateway
  (:class:`sim_bridge.transmit.SerialTransmitter`): frames out, nothing back.

The protocol side (the messages, :class:`sim_bridge.rosbridge.ClientProtocol`, and their
decoding) lives in :mod:`sim_bridge.rosbridge`, shared with the station's transmitter; this
module is the transport.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable
from typing import Any

from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed, InvalidURI

from codec import Frame
from sim_bridge.rosbridge import (
    FRAME_TOPIC,
    MISSION_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
    BinaryMessage,
    BridgeError,
    ClientProtocol,
    InvalidData,
    decode_json_string,
    decode_server_message,
)
from sim_bridge.transmit import failure_reason, frame_msg, open_transmitter

logger = logging.getLogger("backend.link")

Handler = Callable[[dict[str, Any]], None]


class Link:
    """What the console needs from a link to a vehicle."""

    #: Whether the vehicle's acknowledgements come back over this link.
    acknowledges = False
    #: Whether poses and status come back over this link.
    telemetry = False

    def __init__(self, target: str) -> None:
        self.target = target
        self.on_pose: Handler = lambda _m: None
        self.on_status: Handler = lambda _m: None
        self.on_mission: Handler = lambda _m: None
        self.last_message_s: float | None = None  # time.monotonic() of the last message

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
    """A persistent rosbridge connection: frames out, pose/status/mission in."""

    acknowledges = True
    telemetry = True

    def __init__(self, target: str, open_timeout_s: float = 3.0) -> None:
        super().__init__(target)
        self.open_timeout_s = open_timeout_s
        self._conn: ClientConnection | None = None
        self._task: asyncio.Task[None] | None = None
        self._ready = asyncio.Event()
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
                    for opening in self._protocol.open_messages():
                        await conn.send(opening)
                    self._conn = conn
                    self._ready.set()
                    backoff = 0.2
                    logger.info("link to %s up", self.target)
                    async for message in conn:
                        self._dispatch(message)
            except asyncio.CancelledError:
                raise
            except (OSError, ConnectionClosed, InvalidURI, TimeoutError) as err:
                logger.warning("link to %s: %s", self.target, failure_reason(err))
            finally:
                self._conn = None
                self._ready.clear()
            await asyncio.sleep(backoff)
            backoff = min(backoff * 2, 5.0)

    def _dispatch(self, data: str | bytes) -> None:
        try:
            message = decode_server_message(data)
        except BinaryMessage:
            return
        except BridgeError as error:
            logger.warning("link: ignoring %s", error.reason)
            return
        if message.get("op") != "publish":
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
        self._lock = asyncio.Lock()

    @property
    def connected(self) -> bool:
        return True

    async def stop(self) -> None:
        await self._tx.aclose()

    async def transmit(self, frame: Frame) -> str | None:
        async with self._lock:
            result = await self._tx.send_async(frame, wait_ack_s=0.0)
        return None if result.sent else (result.reason or "not sent")


def open_link(target: str, bitrate_bps: float) -> Link:
    """The link for a target: ``ws://`` -> rosbridge, anything else -> an ME modem."""
    if target.startswith(("ws://", "wss://")):
        return RosbridgeLink(target)
    return ModemLink(target, bitrate_bps)
