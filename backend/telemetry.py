"""Live telemetry fan-out to the page's websockets: latest value wins, events in order.

Each client gets the newest pose/status at most ``rate_hz`` times a second (never a backlog:
a slow client just sees fewer, newer values) and every event (command state changes, vehicle
echo changes) in order, through a bounded queue; a client that cannot keep up with events is
disconnected rather than allowed to grow memory.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import time
from typing import Any, Protocol


class Sender(Protocol):
    async def send_text(self, data: str) -> None: ...


def heading_roll_from_quaternion(q: dict[str, float]) -> tuple[float, float]:
    """(heading_deg in [0, 360), roll_deg) from a NED body quaternion with pitch 0."""
    x, y, z, w = q.get("x", 0.0), q.get("y", 0.0), q.get("z", 0.0), q.get("w", 1.0)
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    return math.degrees(yaw) % 360.0, math.degrees(roll)


def pose_from_message(msg: dict[str, Any]) -> dict[str, float]:
    """A PoseStamped message (NED, ``map_ned``) as a flat pose dict."""
    pose = msg.get("pose", {})
    pos = pose.get("position", {})
    heading, roll = heading_roll_from_quaternion(pose.get("orientation", {}))
    stamp = msg.get("header", {}).get("stamp", {})
    t_s = float(stamp.get("sec", 0)) + float(stamp.get("nanosec", 0)) * 1e-9
    return {
        "t_s": t_s,
        "x_m": float(pos.get("x", 0.0)),
        "y_m": float(pos.get("y", 0.0)),
        "z_m": float(pos.get("z", 0.0)),
        "heading_deg": heading,
        "roll_deg": roll,
    }


class _Client:
    __slots__ = ("events", "sender", "sent_version")

    def __init__(self, sender: Sender, max_events: int) -> None:
        self.sender = sender
        self.events: asyncio.Queue[str] = asyncio.Queue(max_events)
        self.sent_version = -1


class TelemetryHub:
    """Latest pose and status, and the connected page clients."""

    def __init__(self, rate_hz: float = 10.0, max_events: int = 1000) -> None:
        self.period_s = 1.0 / rate_hz
        self.max_events = max_events
        self.pose: dict[str, float] | None = None
        self.status: dict[str, Any] | None = None
        self.last_message_s: float | None = None  # monotonic
        self._version = 0
        self._clients: set[_Client] = set()

    @property
    def client_count(self) -> int:
        return len(self._clients)

    def age_s(self) -> float | None:
        """Seconds since the vehicle was last heard from (None: never)."""
        if self.last_message_s is None:
            return None
        return time.monotonic() - self.last_message_s

    def set_pose(self, pose: dict[str, float]) -> None:
        self.pose = pose
        self._touch()

    def set_status(self, status: dict[str, Any]) -> None:
        self.status = status
        self._touch()

    def _touch(self) -> None:
        self.last_message_s = time.monotonic()
        self._version += 1

    def telemetry(self) -> dict[str, Any]:
        return {
            "type": "telemetry",
            "pose": self.pose,
            "status": self.status,
            "age_s": self.age_s(),
        }

    def publish(self, event: dict[str, Any]) -> None:
        """Queue an event for every client (in order); a client too far behind is dropped."""
        text = json.dumps(event)
        for client in list(self._clients):
            try:
                client.events.put_nowait(text)
            except asyncio.QueueFull:
                self._clients.discard(client)

    async def serve(self, sender: Sender) -> None:
        """Push telemetry and events to one client until it fails or is dropped."""
        client = _Client(sender, self.max_events)
        self._clients.add(client)
        try:
            while client in self._clients:
                with contextlib.suppress(TimeoutError):
                    text = await asyncio.wait_for(client.events.get(), self.period_s)
                    await sender.send_text(text)
                    while not client.events.empty():
                        await sender.send_text(client.events.get_nowait())
                if client.sent_version != self._version:
                    client.sent_version = self._version
                    await sender.send_text(json.dumps(self.telemetry()))
        finally:
            self._clients.discard(client)
