"""``nemesys vehicle-check``: a running vehicle against the vehicle contract.

Connects to the vehicle's rosbridge websocket as the console does (:mod:`station.link`, through
the same client: :mod:`rosbridge.transport`),
subscribes to pose, status and mission, and checks, one row each (pass, fail or skipped, and
why):

* the topics ``/rosapi/topics`` lists, each contract topic with its type (either ROS spelling),
  asked before this check advertises anything, and a subscriber on the frame topic
  (``/rosapi/subscribers``);
* the pose rate over the window against the contract's minimum, its ``frame_id``, and its age
  by arrival (the stamp's offset from this computer's clock is information only: the vehicle
  keeps ROS time);
* the status rate, and every status message against the status schema;
* the acknowledgement path, safely: it waits for the next status, re-sends at once the command
  that status reports as ``active`` (unless a value would snap: that would be another command)
  and expects an acknowledgement with ``duplicate: true`` (the onboard agent does not replan a
  repeat of its active command), then checks the acknowledgement against the ack schema. That
  frame is the only one the check sends; with no active command it sends nothing.

What each answer means is :mod:`station.vehicle_report`: a measured rate passes at
:data:`~station.vehicle_report.RATE_TOLERANCE` of the minimum (timer jitter over a short
window). The check passes when no row failed.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from dataclasses import dataclass, field
from typing import Any, Final
from urllib.parse import urlsplit

from websockets.exceptions import ConnectionClosed, WebSocketException

from codec import Frame
from rosbridge.client import ClientProtocol, decode_json_string
from rosbridge.protocol import TOPICS_SERVICE, InvalidData
from rosbridge.subscriber_wait import SUBSCRIBERS_SERVICE
from rosbridge.transport import RosbridgeClient
from station.transmit import ack_match, failure_reason, frame_msg
from station.vehicle_report import (
    Ack,
    Check,
    Report,
    ack_schema_check,
    pose_checks,
    probe_frame,
    status_checks,
    subscriber_check,
    topic_checks,
)
from vehicle_contract.contract import (
    FRAME_TOPIC,
    MISSION_TOPIC,
    POSE_TOPIC,
    STATUS_TOPIC,
)

#: How long to wait for each answer (rosapi, the probe's acknowledgement) by default (s).
DEFAULT_TIMEOUT_S: Final = 3.0
#: How long rates are measured over by default (s).
DEFAULT_WINDOW_S: Final = 3.0
#: The frame topic is advertised at least this long before the probe is published (s): a new
#: rosbridge publisher needs time to be matched with the vehicle's subscriber.
ADVERTISE_SETTLE_S: Final = 1.0


def url_problem(url: str) -> str | None:
    """Why ``url`` is not a rosbridge websocket URL (None when it is one)."""
    try:
        split = urlsplit(url)
        split.port  # noqa: B018 (raises for a bad port)
    except ValueError as err:
        return f"bad URL {url!r}: {err}"
    if split.scheme not in ("ws", "wss"):
        return f"the URL must be ws://host:port or wss://host:port, got {url!r}"
    if not split.hostname:
        return f"no host in {url!r}"
    return None


async def check_vehicle(
    url: str, *, timeout_s: float = DEFAULT_TIMEOUT_S, window_s: float = DEFAULT_WINDOW_S
) -> Report:
    """Run every check against the vehicle at ``url`` (see the module doc).

    Raises:
        ValueError: ``url`` is not a ws:// or wss:// URL.
    """
    problem = url_problem(url)
    if problem is not None:
        raise ValueError(problem)
    listen = ClientProtocol(advertise=[], subscribe=[POSE_TOPIC, STATUS_TOPIC, MISSION_TOPIC])
    try:
        client = await RosbridgeClient.connect(url, listen, open_timeout_s=timeout_s)
    except (OSError, WebSocketException, TimeoutError) as err:
        return Report(url, [Check("connect", "fail", f"{failure_reason(err)}: {url}")])
    session = _Session(client, timeout_s, window_s)
    session.checks.append(Check("connect", "pass", f"a rosbridge websocket at {url}"))
    try:
        await session.run()
    except ConnectionClosed:
        session.checks.append(Check("connection", "fail", "the vehicle closed the connection"))
    finally:
        await session.close()
    return Report(url, session.checks)


@dataclass
class _Record:
    """What arrived while the check listened (arrivals on ``time.monotonic()``)."""

    poses: list[tuple[float, float, dict[str, Any]]] = field(default_factory=list)
    statuses: list[tuple[float, dict[str, Any] | None, str | None]] = field(default_factory=list)
    acks: list[Ack] = field(default_factory=list)


class _Session:
    """One connection to the vehicle (subscribed to pose, status and mission by its protocol)
    and everything it received."""

    def __init__(self, client: RosbridgeClient, timeout_s: float, window_s: float) -> None:
        self.client = client
        self.timeout_s = timeout_s
        self.window_s = window_s
        self.talk = ClientProtocol(advertise=[FRAME_TOPIC], subscribe=[])
        self.record = _Record()
        self.checks: list[Check] = []
        self._ack_arrived = asyncio.Event()
        self._status_arrived = asyncio.Event()
        self._advertised = False
        client.handlers.update(
            {
                POSE_TOPIC: self._pose,
                STATUS_TOPIC: lambda msg: self._json(STATUS_TOPIC, msg),
                MISSION_TOPIC: lambda msg: self._json(MISSION_TOPIC, msg),
            }
        )
        client.on_close = self._closed

    @property
    def closed(self) -> bool:
        return self.client.closed

    async def close(self) -> None:
        closing = self.client.protocol.close_messages()
        if self._advertised:
            closing += self.talk.close_messages()
        await self.client.close(*closing)

    # --- receiving (called by the client, on the event loop) --------------------------------

    def _closed(self) -> None:
        self._ack_arrived.set()
        self._status_arrived.set()

    def _pose(self, msg: object) -> None:
        if isinstance(msg, dict):
            self.record.poses.append((time.monotonic(), time.time(), msg))

    def _json(self, name: str, msg: object) -> None:
        now = time.monotonic()
        try:
            body: dict[str, Any] | None = decode_json_string(msg)
            problem = None
        except InvalidData as error:
            body, problem = None, error.reason
        if name == STATUS_TOPIC:
            self.record.statuses.append((now, body, problem))
            self._status_arrived.set()
        else:
            self.record.acks.append(Ack(now, body, problem))
            self._ack_arrived.set()

    async def _call(
        self, service: str, args: dict[str, Any] | None = None
    ) -> dict[str, Any] | None:
        """A service's answer, or None when none came within the timeout."""
        return await self.client.call_service(service, args, timeout_s=self.timeout_s)

    # --- the checks --------------------------------------------------------------------------

    async def run(self) -> None:
        """Every check after ``connect``, appended to :attr:`checks` as it is made."""
        began = time.monotonic()
        await self.client.open()
        # asked before this check advertises the frame topic: the listing is the vehicle's
        topics, subscribers = await asyncio.gather(
            self._call(TOPICS_SERVICE), self._call(SUBSCRIBERS_SERVICE, {"topic": FRAME_TOPIC})
        )
        self.checks += topic_checks(topics, self.timeout_s)
        self.checks.append(subscriber_check(subscribers, self.timeout_s))
        await self.client.send(*self.talk.open_messages())
        self._advertised, advertised = True, time.monotonic()
        await asyncio.sleep(max(0.0, began + self.window_s - time.monotonic()))
        window_s = time.monotonic() - began
        self.checks += pose_checks(self.record.poses, window_s)
        self.checks += status_checks(self.record.statuses, window_s)
        self.checks.append(await self._probe(advertised))
        self.checks.append(ack_schema_check(self.record.acks))

    async def _next_status(self) -> None:
        """Wait for one more status (at most the timeout): the probe repeats the command the
        vehicle runs now, not one it ran a status period ago (an operator may retask it)."""
        self._status_arrived.clear()
        if not self.closed:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._status_arrived.wait(), self.timeout_s)

    async def _probe(self, advertised_s: float) -> Check:
        name = "ack path (probe)"
        if self.record.statuses:
            await asyncio.sleep(max(0.0, advertised_s + ADVERTISE_SETTLE_S - time.monotonic()))
            await self._next_status()
        # from here to the publish nothing is awaited: the command is the newest status's
        statuses = [body for _, body, _ in self.record.statuses if body is not None]
        if not statuses:
            return Check(
                name, "skipped", "no status: the active command is unknown; nothing was sent"
            )
        status = statuses[-1]
        if "active" not in status:
            why = "the status has no 'active' field (optional in the contract); nothing was sent"
            return Check(name, "skipped", why)
        if status["active"] is None:
            return Check(name, "skipped", "the vehicle reports no active command; nothing was sent")
        enc, problem = probe_frame(status["active"])
        if enc is None:
            why = f"the active command cannot be re-sent unchanged: {problem}; nothing was sent"
            return Check(name, "fail", why)
        start = len(self.record.acks)
        await self.client.send(self.talk.publish(FRAME_TOPIC, frame_msg(enc.frame)))
        sent_s = time.monotonic()
        what = f"re-sent the active command ({enc.command.describe()})"
        ack = await self._ack_for(enc.frame, start)
        if ack is None:
            return Check(name, "fail", f"{what}: no acknowledgement within {self.timeout_s:g} s")
        took = f"in {ack.arrival_s - sent_s:.2f} s"
        body = ack.ack or {}
        if body.get("outcome") != "accepted":
            why = f"rejected {took}: {body.get('reason')}: {body.get('detail')}"
            return Check(name, "fail", f"{what}: {why}")
        if body.get("duplicate") is not True:
            why = "accepted but not as a duplicate: the vehicle replanned a repeat of its command"
            return Check(name, "fail", f"{what}: {why}")
        return Check(name, "pass", f"{what}: a duplicate {took}, not replanned")

    async def _ack_for(self, frame: Frame, start: int) -> Ack | None:
        """The first acknowledgement from index ``start`` on that answers ``frame``."""
        deadline = time.monotonic() + self.timeout_s
        seen = start
        while True:
            for ack in self.record.acks[seen:]:
                seen += 1
                if ack.ack is not None and ack_match(frame, ack.ack) is not None:
                    return ack
            remaining_s = deadline - time.monotonic()
            if remaining_s <= 0 or self.closed:
                return None
            self._ack_arrived.clear()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._ack_arrived.wait(), remaining_s)
