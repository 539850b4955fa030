"""A small fake rosbridge endpoint for transmitter tests: a ``websockets`` server on
127.0.0.1 (port 0) in its own thread and event loop. It records every message a client sends
and answers each frame published on ``/nemesys/frame`` with whatever ``respond`` returns
(complete rosbridge messages; :func:`mission` wraps an acknowledgement). It answers
``/rosapi/subscribers`` as rosapi does: by default the vehicle subscribes to the frame topic."""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from types import TracebackType
from typing import Any, Self

from websockets.asyncio.server import Server, ServerConnection, serve

from rosbridge.protocol import (
    FRAME_TOPIC,
    MISSION_TOPIC,
    decode_uint8_multiarray,
    json_string_msg,
    publish_message,
)
from tests.rosbridge.helpers import LoopThread
from vehicle_contract.contract import VEHICLE_NODE

#: Replies to one published frame: rosbridge messages (dicts) or raw text.
Respond = Callable[[bytes], list[dict[str, Any] | str]]


SUBSCRIBERS_SERVICE = "/rosapi/subscribers"


def mission(ack: dict[str, Any]) -> dict[str, Any]:
    """A ``/nemesys/mission`` publish carrying ``ack`` as a JSON string, as rosbridge sends."""
    return publish_message(MISSION_TOPIC, json_string_msg(ack))


def ack_for(data: bytes, seq: int = 1, outcome: str = "accepted", **fields: Any) -> dict[str, Any]:
    """An acknowledgement of the 13 bytes ``data`` shaped like the onboard agent's."""
    value = int.from_bytes(data, "big") >> 4
    ack: dict[str, Any] = {
        "seq": seq,
        "t_s": 12.5,
        "outcome": outcome,
        "frame_hex": f"{value:025x}",
        "corrected_bits": 0,
        "sync_errors": 0,
        "reason": None if outcome == "accepted" else "crc_mismatch",
        "detail": "circle: replanned, 12 waypoints" if outcome == "accepted" else "CRC-4 failed",
        "field": None,
        "command": {"pattern": "circle", "pattern_id": 3, "params": {"speed": 0.5}},
        "duplicate": False,
        "decode_latency_ms": 0.25,
        "replan_latency_ms": 3.5 if outcome == "accepted" else None,
        "waypoints": 12 if outcome == "accepted" else None,
        "active": None,
    }
    ack.update(fields)
    return ack


def accept_all(data: bytes) -> list[dict[str, Any] | str]:
    return [mission(ack_for(data))]


class FakeRosbridge:
    """``with FakeRosbridge(respond) as fake: ... fake.url ... fake.received``."""

    def __init__(
        self,
        respond: Respond | None = accept_all,
        *,
        close_after: int = 0,
        subscribers: list[str] | None = None,
        rosapi: bool = True,
        subscribers_service: bool = True,
        subscribed_after: int = 0,
    ) -> None:
        self.respond = respond
        #: Close the client's connection after this many frames (0: never).
        self.close_after = close_after
        #: What ``/rosapi/subscribers`` lists for the frame topic (default: the vehicle);
        #: ``[]``: nobody. With ``rosapi`` False no service call is answered; with
        #: ``subscribers_service`` False it fails (result false), as a server without it does.
        self.subscribers = [VEHICLE_NODE] if subscribers is None else subscribers
        self.rosapi = rosapi
        self.subscribers_service = subscribers_service
        #: Answer "nobody" to this many questions on each connection before the list.
        self.subscribed_after = subscribed_after
        self.received: list[dict[str, Any]] = []
        self.connections = 0
        self.frames = 0
        self._loop = LoopThread()
        self._server: Server | None = None
        self.port = 0

    @property
    def url(self) -> str:
        return f"ws://127.0.0.1:{self.port}"

    def __enter__(self) -> Self:
        self._loop.start()
        self.port = self._loop.run(self._start())
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._loop.run(self._stop())
        self._loop.stop()

    async def _start(self) -> int:
        self._server = await serve(self._handler, "127.0.0.1", 0)
        port: int = self._server.sockets[0].getsockname()[1]
        return port

    async def _stop(self) -> None:
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()

    def ops(self) -> list[str]:
        return [m["op"] for m in self.received]

    def published(self) -> list[bytes]:
        """The frames published so far, in order."""
        return [decode_uint8_multiarray(m["msg"]) for m in self.received if _is_frame(m)]

    async def _handler(self, ws: ServerConnection) -> None:
        self.connections += 1
        asked = 0
        async for text in ws:
            message: dict[str, Any] = json.loads(text)
            self.received.append(message)
            if message["op"] == "call_service" and self.rosapi:
                asked += 1
                await ws.send(json.dumps(self._service_answer(message, asked)))
            if not _is_frame(message):
                continue
            self.frames += 1
            data = decode_uint8_multiarray(message["msg"])
            for reply in self.respond(data) if self.respond else []:
                await ws.send(reply if isinstance(reply, str) else json.dumps(reply))
            if self.close_after and self.frames % self.close_after == 0:
                await ws.close()

    def _service_answer(self, request: dict[str, Any], asked: int) -> dict[str, Any]:
        service = request.get("service")
        answer = {"op": "service_response", "id": request.get("id"), "service": service}
        if service != SUBSCRIBERS_SERVICE or not self.subscribers_service:
            return {**answer, "values": f"Service {service} does not exist", "result": False}
        subscribers = self.subscribers if asked > self.subscribed_after else []
        return {**answer, "values": {"subscribers": subscribers}, "result": True}


def _is_frame(message: Mapping[str, object]) -> bool:
    return message["op"] == "publish" and message["topic"] == FRAME_TOPIC
