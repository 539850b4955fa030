"""What comes back over rosbridge, for :mod:`station.transmit_rosbridge`: server messages,
the vehicle's acknowledgements, and how one is matched to the sent frame. :func:`ack_match` is
public (import it from :mod:`station.transmit`); the rest serves the rosbridge transmitter.

Acknowledgement matching
------------------------
Acknowledgements already waiting on the connection are discarded before the publish. After it,
the first mission message whose ``frame_hex`` is the sent frame is the acknowledgement
("exact"); so is one whose codeword is within the BCH correction radius (``CODE.t`` = 2 bits)
of the sent codeword, differences in the fixed preamble, delimiter and guard bits not counting
("near": the channel flipped bits). Any other new acknowledgement is kept as a fallback: if no
exact or near one follows within ``settle_s`` (0.5 s) of it, or before the timeout, the first
such acknowledgement is returned ("first": matched by order, e.g. the vehicle slipped bits and
reports what it received). No acknowledgement within ``wait_ack_s`` of the publish: failed,
reason "timeout" (``sent_t`` is set, the frame did go out).
"""

from __future__ import annotations

import asyncio
import logging
import time
from typing import Any

from websockets.asyncio.client import ClientConnection as AsyncConnection
from websockets.exceptions import ConnectionClosed

from codec import CODE, FRAME_BYTES, DecodeError, Frame, parse_frame
from rosbridge.client import decode_json_string, decode_server_message
from rosbridge.protocol import MISSION_TOPIC, BinaryMessage, BridgeError, InvalidData
from station.transmit_base import AckMatch, logger

#: After a new acknowledgement that is not for the sent frame, how long to wait for one that is.
ACK_SETTLE_S = 0.5


def _frame_value(text: object) -> int | None:
    """The 100-bit value of an acknowledgement's ``frame_hex`` (25 hex digits, or the 26 of the
    13 packed bytes); None if it is not one."""
    if not isinstance(text, str):
        return None
    try:
        if len(text.strip()) == 2 * FRAME_BYTES:
            return parse_frame(bytes.fromhex(text))
        return parse_frame(text)
    except (DecodeError, ValueError):
        return None


def ack_match(frame: Frame, ack: dict[str, Any]) -> AckMatch | None:
    """How ``ack`` matches ``frame``: ``"exact"`` if its ``frame_hex`` is the frame, ``"near"``
    if its codeword is within the BCH correction radius of the frame's, else None."""
    value = _frame_value(ack.get("frame_hex"))
    if value is None:
        return None
    if value == frame.value:
        return "exact"
    if (Frame(value).codeword ^ frame.codeword).bit_count() <= CODE.t:
        return "near"
    return None


class _AckMatcher:
    """Applies the matching rule to the acknowledgements that arrive after a publish."""

    def __init__(self, frame: Frame, wait_s: float, settle_s: float) -> None:
        self.frame = frame
        self.settle_s = settle_s
        self.deadline = time.monotonic() + wait_s
        self.ack: dict[str, Any] | None = None
        self.match: AckMatch | None = None
        self._first_until: float | None = None

    def offer(self, ack: dict[str, Any]) -> bool:
        """Take one new acknowledgement; True when the search is over."""
        match = ack_match(self.frame, ack)
        if match is not None:
            self.ack, self.match = ack, match
            return True
        if self._first_until is None:
            logger.info("acknowledgement seq=%s is not for frame %s", ack.get("seq"), self.frame)
            self.ack, self.match = ack, "first"
            self._first_until = min(self.deadline, time.monotonic() + self.settle_s)
        return False

    def remaining_s(self) -> float:
        until = self.deadline if self._first_until is None else self._first_until
        return until - time.monotonic()


def _server_message(data: str | bytes) -> dict[str, Any] | None:
    """One received message as an object, or None (logged) if it is not one, or a ``status``."""
    try:
        message = decode_server_message(data)
    except BinaryMessage as error:
        logger.debug("ignoring %s", error.reason)
        return None
    except BridgeError as error:
        logger.warning("ignoring %s", error.reason)
        return None
    if message.get("op") == "status":
        level = logging.WARNING if message.get("level") in ("error", "warning") else logging.INFO
        logger.log(level, "rosbridge status: %s", message.get("msg", message))
        return None
    return message


def _mission_of(data: str | bytes) -> dict[str, Any] | None:
    """The acknowledgement in one received message, or None (logged) if it holds none."""
    message = _server_message(data)
    return None if message is None else _mission_in(message)


def _mission_in(message: dict[str, Any]) -> dict[str, Any] | None:
    """The acknowledgement in a server message, or None (logged) if it holds none."""
    op, topic = message.get("op"), message.get("topic")
    if op != "publish" or topic != MISSION_TOPIC:
        logger.debug("ignoring %s on %s", op, topic)
        return None
    try:
        return decode_json_string(message.get("msg"))
    except InvalidData as error:
        logger.warning("ignoring a mission message: %s", error.reason)
        return None


class _AsyncLink:
    """An asyncio connection with a reader task that queues acknowledgements (None: closed)
    and service responses."""

    def __init__(self, conn: AsyncConnection) -> None:
        self.conn = conn
        self.loop = asyncio.get_running_loop()
        self.acks: asyncio.Queue[dict[str, Any] | None] = asyncio.Queue()
        self.responses: asyncio.Queue[dict[str, Any]] = asyncio.Queue()
        self.closed = False
        self.reader = asyncio.create_task(self._read())

    def abort_threadsafe(self) -> None:
        """Cancel the reader and abort the connection from outside its event loop."""
        if not self.loop.is_closed():
            self.loop.call_soon_threadsafe(self.reader.cancel)
            self.loop.call_soon_threadsafe(self.conn.transport.abort)

    async def _read(self) -> None:
        try:
            async for data in self.conn:
                message = _server_message(data)
                if message is None:
                    continue
                if message.get("op") == "service_response":
                    self.responses.put_nowait(message)
                elif (ack := _mission_in(message)) is not None:
                    self.acks.put_nowait(ack)
        except ConnectionClosed:
            pass
        finally:
            self.closed = True
            self.acks.put_nowait(None)

    def drain(self) -> None:
        """Discard acknowledgements that arrived before now."""
        while not self.acks.empty():
            ack = self.acks.get_nowait()
            if ack is None:
                self.closed = True
            else:
                logger.debug("discarding earlier acknowledgement seq=%s", ack.get("seq"))
