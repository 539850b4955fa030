"""A small Foxglove WebSocket protocol client for the live view's tests, on the third-party
``websockets`` library: the handshake, ``serverInfo``, ``advertise``, ``subscribe`` and the
binary message-data and time frames (the protocol's spec, foxglove/ws-protocol docs/spec.md).
The interop test (``test_interop.py``) uses Foxglove's own client from npm instead."""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from websockets.asyncio.client import ClientConnection, connect

#: The subprotocol names the Foxglove app offers (foxglove-sdk 0.30 speaks the second).
SUBPROTOCOLS = ("foxglove.websocket.v1", "foxglove.sdk.v1")
MESSAGE_DATA, TIME = 0x01, 0x02


@dataclass
class Received:
    """A message-data frame: its topic, log time (ns) and payload."""

    topic: str
    log_time: int
    data: bytes


@dataclass
class Session:
    """One connection: what the server said, and what arrived since."""

    ws: ClientConnection
    server_info: dict[str, Any]
    channels: dict[str, dict[str, Any]]  # by topic
    subscribed: dict[int, str] = field(default_factory=dict)  # subscription id -> topic
    received: list[Received] = field(default_factory=list)
    times: list[int] = field(default_factory=list)
    texts: list[dict[str, Any]] = field(default_factory=list)

    async def subscribe(self, *topics: str) -> None:
        subs = []
        for topic in topics:
            sub = len(self.subscribed)
            self.subscribed[sub] = topic
            subs.append({"id": sub, "channelId": self.channels[topic]["id"]})
        await self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))

    async def until(
        self, done: Callable[[Session], bool], timeout_s: float = 10.0, what: str = ""
    ) -> None:
        """Read frames until ``done(self)``; fail at the deadline."""
        deadline = time.monotonic() + timeout_s
        while not done(self):
            left = deadline - time.monotonic()
            if left <= 0:
                topics = sorted({r.topic for r in self.received})
                raise AssertionError(f"timed out waiting for {what or done}; got {topics}")
            try:
                frame = await asyncio.wait_for(self.ws.recv(), left)
            except TimeoutError:
                continue
            self._take(frame)

    def on(self, topic: str) -> list[Received]:
        return [r for r in self.received if r.topic == topic]

    def _take(self, frame: str | bytes) -> None:
        if isinstance(frame, str):
            self.texts.append(json.loads(frame))
        elif frame[0] == MESSAGE_DATA:
            sub = int.from_bytes(frame[1:5], "little")
            log_time = int.from_bytes(frame[5:13], "little")
            self.received.append(Received(self.subscribed[sub], log_time, frame[13:]))
        elif frame[0] == TIME:
            self.times.append(int.from_bytes(frame[1:9], "little"))


async def open_session(port: int, host: str = "127.0.0.1") -> Session:
    """Connect, and read ``serverInfo`` and the first ``advertise``."""
    ws = await connect(f"ws://{host}:{port}", subprotocols=list(SUBPROTOCOLS))  # type: ignore[arg-type]
    info = json.loads(await asyncio.wait_for(ws.recv(), 5.0))
    advertised = json.loads(await asyncio.wait_for(ws.recv(), 5.0))
    assert info["op"] == "serverInfo" and advertised["op"] == "advertise", (info, advertised)
    channels = {c["topic"]: c for c in advertised["channels"]}
    return Session(ws, info, channels)


__all__ = ["SUBPROTOCOLS", "Received", "Session", "open_session"]
