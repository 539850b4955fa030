"""Live telemetry fan-out to the page's websockets: latest value wins, events in order.

Each client gets the newest pose/status at most ``rate_hz`` times a second (never a backlog:
a slow client just sees fewer, newer values) and every event (command state changes, vehicle
echo changes) in order, through a bounded queue; a client that cannot keep up with events is
disconnected rather than allowed to grow memory.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections import deque
from typing import Any, Protocol

from backend.messages import News, TelemetryMessage, message_json


class Sender(Protocol):
    async def send_text(self, data: str) -> None: ...


#: Numbers of a pose, each ``None`` when the vehicle sent none (null, NaN, missing).
POSE_KEYS = ("t_s", "x_m", "y_m", "z_m", "heading_deg", "roll_deg")
#: Numbers of the vehicle's status the console reads.
STATUS_NUMBERS = ("t_s", "depth_m", "heading_deg", "speed_mps", "battery_pct", "x_m", "y_m")

Pose = dict[str, float | None]


def number(value: object) -> float | None:
    """A finite number, or ``None``: rosbridge_server sends NaN and infinity as ``null``, and
    a field may be missing or of another type. Booleans are not numbers."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    out = float(value)
    return out if math.isfinite(out) else None


def _dict(value: object) -> dict[str, Any]:
    return value if isinstance(value, dict) else {}


def heading_roll_from_quaternion(q: dict[str, Any]) -> tuple[float | None, float | None]:
    """(heading_deg in [0, 360), roll_deg) from a NED body quaternion with pitch 0; both
    ``None`` when a component is not a number."""
    x, y, z, w = (number(q.get(k)) for k in ("x", "y", "z", "w"))
    if x is None or y is None or z is None or w is None:
        return None, None
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    return math.degrees(yaw) % 360.0, math.degrees(roll)


def pose_from_message(msg: dict[str, Any]) -> Pose:
    """A PoseStamped message (NED, ``map_ned``) as a flat pose dict; a number the vehicle
    did not send (null, NaN, missing) is ``None``. ``t_s`` is the vehicle's ROS time."""
    pose = _dict(msg.get("pose"))
    pos = _dict(pose.get("position"))
    heading, roll = heading_roll_from_quaternion(_dict(pose.get("orientation")))
    stamp = _dict(_dict(msg.get("header")).get("stamp"))
    sec, nanosec = number(stamp.get("sec")), number(stamp.get("nanosec"))
    return {
        "t_s": None if sec is None else sec + (nanosec or 0.0) * 1e-9,
        "x_m": number(pos.get("x")),
        "y_m": number(pos.get("y")),
        "z_m": number(pos.get("z")),
        "heading_deg": heading,
        "roll_deg": roll,
    }


def status_from_message(msg: dict[str, Any]) -> tuple[dict[str, Any], int]:
    """The vehicle's status with every number it should hold (:data:`STATUS_NUMBERS`) made a
    finite float or ``None``, and how many were unknown (null, NaN or missing)."""
    status = dict(msg)
    unknown = 0
    for key in STATUS_NUMBERS:
        status[key] = number(msg.get(key))
        unknown += status[key] is None
    return status, unknown


def unknown_count(pose: Pose) -> int:
    return sum(pose[k] is None for k in POSE_KEYS)


def position_known(pose: Pose | None) -> bool:
    return pose is not None and all(pose[k] is not None for k in ("x_m", "y_m", "z_m"))


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
        self.pose: Pose | None = None
        #: The last pose whose position was known (for previews and joins).
        self.known_pose: Pose | None = None
        self.status: dict[str, Any] | None = None
        self.last_message_s: float | None = None  # monotonic arrival time
        #: Telemetry numbers that came unknown (null / NaN / missing) since the dive began,
        #: and the arrival times of the recent ones.
        self.unknown_values = 0
        self._unknown_at: deque[tuple[float, int]] = deque(maxlen=1000)
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

    def set_pose(self, pose: Pose) -> None:
        self.pose = pose
        if position_known(pose):
            self.known_pose = pose
        self._count_unknown(unknown_count(pose))
        self._touch()

    def set_status(self, msg: dict[str, Any]) -> None:
        """A status message as the vehicle sent it (numbers may be null)."""
        self.status, unknown = status_from_message(msg)
        self._count_unknown(unknown)
        self._touch()

    def reset(self) -> None:
        """A new dive: no pose, no counts."""
        self.pose = self.known_pose = None
        self.unknown_values = 0
        self._unknown_at.clear()

    def _count_unknown(self, n: int) -> None:
        if n:
            self.unknown_values += n
            self._unknown_at.append((time.monotonic(), n))

    def unknown_recent(self, window_s: float) -> int:
        """Unknown telemetry numbers that arrived in the last ``window_s``."""
        since = time.monotonic() - window_s
        return sum(n for at, n in self._unknown_at if at >= since)

    def _touch(self) -> None:
        self.last_message_s = time.monotonic()
        self._version += 1

    def telemetry(self) -> TelemetryMessage:
        return TelemetryMessage.model_validate(
            {"pose": self.pose, "status": self.status, "age_s": self.age_s()}
        )

    def publish(self, event: News) -> None:
        """Queue an event for every client (in order), serialised once; a client too far
        behind is dropped."""
        text = message_json(event)
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
                    await sender.send_text(message_json(self.telemetry()))
        finally:
            self._clients.discard(client)
