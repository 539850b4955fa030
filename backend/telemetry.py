"""Live telemetry fan-out to the page's websockets: latest value wins, events in order.

Each client gets the newest pose/status at most ``rate_hz`` times a second (never a backlog:
a slow client just sees fewer, newer values) and every event (command state changes, vehicle
echo changes) in order, through a bounded queue; a client that cannot keep up with events is
disconnected rather than allowed to grow memory.

A fleet (``NEMESYS_VEHICLES``) has a hub per vehicle holding its pose and status (``vehicle``:
its name, in its telemetry), and the console's hub serves every page: their telemetry as
:attr:`TelemetryHub.feeds` (each serialised once per change, latest value wins) and the events,
which are published on it alone. A page gets its changed vehicles' telemetry in one
``fleet_telemetry`` message a period, not one message per vehicle: the texts already
serialised, joined (the whole fleet's, the common case, joined once for every page).
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections import deque
from collections.abc import Callable, Iterable
from typing import Any, Protocol

from backend.messages import News, TelemetryMessage, message_json
from vehicle_contract.messages import (
    PoseFields,
    position_known,
    status_from_message,
    unknown_count,
)


class Sender(Protocol):
    async def send_text(self, data: str) -> None: ...


#: A pose as the vehicle sent it (:func:`vehicle_contract.messages.pose_from_message`).
Pose = PoseFields


class _Client:
    __slots__ = ("events", "feed_versions", "sender", "sent_version")

    def __init__(self, sender: Sender, max_events: int) -> None:
        self.sender = sender
        self.events: asyncio.Queue[str] = asyncio.Queue(max_events)
        self.sent_version = -1
        #: The version of each feed's telemetry sent last (by the feed's place in the list).
        self.feed_versions: list[int] = []


class TelemetryHub:
    """Latest pose and status, and the connected page clients."""

    def __init__(
        self, rate_hz: float = 10.0, max_events: int = 1000, vehicle: str | None = None
    ) -> None:
        """``vehicle``: a fleet's vehicle whose pose and status this hub holds (named in its
        telemetry); None: the single vehicle's, or the console's hub of a fleet."""
        self.period_s = 1.0 / rate_hz
        self.vehicle = vehicle
        #: The fleet's vehicles' hubs, whose telemetry this hub's pages get (then this hub
        #: holds no vehicle's pose and status, and sends no telemetry of its own).
        self.feeds: list[TelemetryHub] = []
        self.max_events = max_events
        self.pose: Pose | None = None
        #: The last pose whose position was known (for previews and joins).
        self.known_pose: Pose | None = None
        self.status: dict[str, Any] | None = None
        #: Monotonic arrival times of ``known_pose`` and ``status`` (None: none yet).
        self.known_pose_s: float | None = None
        self.status_s: float | None = None
        #: The dive the console records into (None: none yet), named in every telemetry.
        self.dive: int | None = None
        #: The last status's ``recent_acks`` (the vehicle contract: its acknowledgements of
        #: the last 30 s), kept apart from :attr:`status`.
        self.recent_acks: list[Any] = []
        self.last_message_s: float | None = None  # monotonic arrival time
        #: The console whose track points in the shared mission log the pose and status were
        #: read from (a console without a transmitter: :mod:`backend.relay.telemetry`), named
        #: in every telemetry; None: heard over this console's own link.
        self.relayed_via: str | None = None
        #: Telemetry numbers that came unknown (null / NaN / missing) since the dive began,
        #: and the arrival times of the recent ones.
        self.unknown_values = 0
        self._unknown_at: deque[tuple[float, int]] = deque(maxlen=1000)
        self._version = 0
        #: The telemetry message of :attr:`_version`, serialised once for every page, and the
        #: monotonic time it was (its ``age_s`` is as of then).
        self._telemetry_json: tuple[int, float, str] | None = None
        #: The whole fleet's ``fleet_telemetry`` text, the feeds' versions it holds and the
        #: monotonic time it was joined (the pages that want every vehicle share it).
        self._fleet_json: tuple[tuple[int, ...], float, str] | None = None
        self._clients: set[_Client] = set()
        #: Called with every event published, before the pages get it (the belief listens).
        self.observers: list[Callable[[News], None]] = []

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
            self.known_pose, self.known_pose_s = pose, time.monotonic()
        self._count_unknown(unknown_count(pose))
        self._touch()

    def set_status(self, msg: dict[str, Any]) -> None:
        """A status message as the vehicle sent it (numbers may be null). Its
        ``recent_acks`` (the vehicle's last acknowledgements, for a console that reconnected)
        are kept apart in :attr:`recent_acks`, not sent on to the pages with the status."""
        self.status, unknown = status_from_message(msg)
        self.status_s = time.monotonic()
        recent = self.status.pop("recent_acks", None)
        self.recent_acks = recent if isinstance(recent, list) else []
        self._count_unknown(unknown)
        self._touch()

    def set_relayed(
        self, pose: Pose | None, status: dict[str, Any], age_s: float, via: str
    ) -> None:
        """A pose (None: the point held no position) and status that console ``via`` heard
        ``age_s`` ago and wrote into the shared mission log: kept with arrival times that long
        ago, so the telemetry's age, its staleness and the belief's fixes are the vehicle's
        true ones, never the time this console read them. Unknown numbers are not counted:
        the track does not keep every number a status holds (nor a pose's roll)."""
        at = time.monotonic() - max(age_s, 0.0)
        self.relayed_via = via
        if pose is not None:
            self.pose = pose
            if position_known(pose):
                self.known_pose, self.known_pose_s = pose, at
        self.status, self.status_s = status, at
        self.last_message_s = at
        self._version += 1

    def reset(self) -> None:
        """A new dive: no pose, no counts."""
        self.pose = self.known_pose = self.known_pose_s = None
        self.recent_acks = []
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
        named: dict[str, Any] = {} if self.vehicle is None else {"vehicle": self.vehicle}
        if self.relayed_via is not None:
            named["relayed_via"] = self.relayed_via
        return TelemetryMessage.model_validate(
            {
                "pose": self.pose,
                "status": self.status,
                "age_s": self.age_s(),
                "dive": self.dive,
                **named,
            }
        )

    def telemetry_json(self) -> str:
        """:meth:`telemetry` as the pages get it, serialised once per change of the pose or
        status however many pages there are. Its ``age_s`` is as of that serialisation, so it
        is reused only within one period (a page that joins later gets a fresh age)."""
        now = time.monotonic()
        cached = self._telemetry_json
        if cached is None or cached[0] != self._version or now - cached[1] > self.period_s:
            cached = self._telemetry_json = (self._version, now, message_json(self.telemetry()))
        return cached[2]

    def publish(self, event: News) -> None:
        """Queue an event for every client (in order), serialised once; a client too far
        behind is dropped."""
        for observer in self.observers:
            observer(event)
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
                    # asyncio.timeout: wait_for (3.11) can swallow a cancel at its timeout
                    async with asyncio.timeout(self.period_s):
                        text = await client.events.get()
                    await sender.send_text(text)
                    while not client.events.empty():
                        await sender.send_text(client.events.get_nowait())
                if not self.feeds and client.sent_version != self._version:
                    client.sent_version = self._version
                    await sender.send_text(self.telemetry_json())
                await self._send_feeds(client)
        finally:
            self._clients.discard(client)

    async def _send_feeds(self, client: _Client) -> None:
        """The fleet vehicles' telemetry that changed since this client last got it, in one
        ``fleet_telemetry`` message (none when nothing changed)."""
        sent = client.feed_versions
        sent.extend([-1] * (len(self.feeds) - len(sent)))
        versions = [feed._version for feed in self.feeds]
        changed = [i for i, v in enumerate(versions) if sent[i] != v]
        if not changed:
            return
        client.feed_versions = versions
        if len(changed) == len(self.feeds):
            text = self.fleet_json(tuple(versions))
        else:
            text = _fleet_text(self.feeds[i].telemetry_json() for i in changed)
        await client.sender.send_text(text)

    def fleet_json(self, versions: tuple[int, ...]) -> str:
        """Every fleet vehicle's telemetry at ``versions`` in one ``fleet_telemetry`` text,
        joined once for all the pages that want it (again after a period: fresh ages)."""
        now = time.monotonic()
        cached = self._fleet_json
        if cached is None or cached[0] != versions or now - cached[1] > self.period_s:
            text = _fleet_text(feed.telemetry_json() for feed in self.feeds)
            cached = self._fleet_json = (versions, now, text)
        return cached[2]


#: A ``fleet_telemetry`` message around its vehicles' ``telemetry`` texts
#: (:class:`backend.messages.FleetTelemetryMessage`; a test checks the two agree).
_FLEET_HEAD = '{"type":"fleet_telemetry","telemetry":['
_FLEET_TAIL = "]}"


def _fleet_text(parts: Iterable[str]) -> str:
    return _FLEET_HEAD + ",".join(parts) + _FLEET_TAIL
