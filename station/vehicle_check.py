"""``nemesys vehicle-check``: a running vehicle against the vehicle contract.

Connects to the vehicle's rosbridge websocket as the console does (:mod:`station.link`, through
the same client: :mod:`rosbridge.transport`),
subscribes to pose, status and mission, and checks, one row each (pass, fail or skipped, and
why):

* the ROS graph, by the rule the console uses (:mod:`station.vehicle_graph`): each contract
  topic with its type (either ROS spelling) and the node at the vehicle's end of it (its
  publisher, or the frame topic's subscriber) other than rosbridge's own node, which
  publishes and subscribes for its clients; and whether the onboard agent runs;
* the pose rate over the window against the contract's minimum, its ``frame_id``, and its age
  by arrival (the stamp's offset from this computer's clock is information only: the vehicle
  keeps ROS time);
* the status rate, and every status message against the status schema;
* the acknowledgement path, harmlessly, on any vehicle (a fresh one too): it sends a
  deliberately malformed frame (:data:`~station.vehicle_report.PROBE_FRAME`: synchronisable,
  its codeword beyond correction) and expects it acknowledged ``rejected``, reason
  ``uncorrectable``, its round trip within the contract's ack deadline
  (:data:`~vehicle_contract.contract.ACK_DEADLINE_S`; one that comes later, up to the timeout,
  is named late), the active command unchanged. A vehicle that takes
  its frames over its own ME receiver (no frame subscriber but rosbridge's: "receiver-only")
  is probed through the modem path (``modem``: an ME modem target, ``tcp://host:port`` or
  ``serial:///dev/...``), its acknowledgement still read over rosbridge; without one the row
  fails saying so;
* the duplicate rule, when the vehicle runs a command: it waits for the next status, re-sends
  at once the command that status reports as ``active`` (unless a value would snap: that would
  be another command) and expects an acknowledgement with ``duplicate: true`` (not replanned);
* every acknowledgement against the ack schema.

A vehicle under a ROS namespace (``namespace``: its topics ``/<it>/nemesys/...``, its node
``/<it>/nemesys_vehicle``) is checked on those names; its nodes are found by the topics they
publish and subscribe, whatever they are called.

Those are the only frames the check sends. What each answer means is
:mod:`station.vehicle_report`: a measured rate passes at
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
from rosbridge.protocol import InvalidData
from rosbridge.transport import RosbridgeClient
from station.transmit import Transmitter, ack_match, failure_reason, frame_msg, open_transmitter
from station.vehicle_graph import GraphUnknown, VehicleGraph, read_graph, verdict_of
from station.vehicle_report import (
    PROBE_FRAME,
    Ack,
    Check,
    Report,
    ack_schema_check,
    graph_checks,
    malformed_probe_check,
    pose_checks,
    probe_frame,
    status_checks,
)
from vehicle_contract.contract import ACK_DEADLINE_S
from vehicle_contract.names import TopicNames, topic_names

#: How long to wait for each answer (rosapi, the probe's acknowledgement) by default (s).
DEFAULT_TIMEOUT_S: Final = 3.0
#: How long rates are measured over by default (s).
DEFAULT_WINDOW_S: Final = 3.0
#: The frame topic is advertised at least this long before the probe is published (s): a new
#: rosbridge publisher needs time to be matched with the vehicle's subscriber.
ADVERTISE_SETTLE_S: Final = 1.0
#: Not known (the status did not say): distinct from the vehicle's ``null``.
_UNKNOWN: Final[Any] = ...


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


def open_modem(target: str) -> Transmitter:
    """The ME modem a receiver-only vehicle is probed through.

    Raises:
        ValueError: not an ME modem target (the message lists the forms).
    """
    if target.strip().lower().startswith(("ws://", "wss://")):
        raise ValueError(
            f"--modem takes an ME modem (tcp://host:port, serial:///dev/...), not a rosbridge "
            f"URL: {target!r}"
        )
    return open_transmitter(target)


def modem_problem(target: str) -> str | None:
    """Why ``target`` is not an ME modem to probe through (None when it is one)."""
    try:
        open_modem(target).close()  # nothing is opened before a send
    except ValueError as err:
        return str(err)
    return None


async def check_vehicle(
    url: str,
    *,
    timeout_s: float = DEFAULT_TIMEOUT_S,
    window_s: float = DEFAULT_WINDOW_S,
    modem: str | None = None,
    namespace: str = "",
) -> Report:
    """Run every check against the vehicle at ``url`` (see the module doc); with ``modem``
    the frames go through that ME modem and the acknowledgements come back over rosbridge;
    ``namespace``: the vehicle's ROS namespace ("" for none).

    Raises:
        ValueError: ``url`` is not a ws:// or wss:// URL, ``modem`` not a modem target, or
            ``namespace`` not a ROS namespace.
    """
    problem = url_problem(url)
    if problem is not None:
        raise ValueError(problem)
    names = topic_names(namespace)
    tx = open_modem(modem) if modem is not None else None
    listen = ClientProtocol(advertise=[], subscribe=[names.pose, names.status, names.mission])
    try:
        try:
            client = await RosbridgeClient.connect(url, listen, open_timeout_s=timeout_s)
        except (OSError, WebSocketException, TimeoutError) as err:
            return Report(url, [Check("connect", "fail", f"{failure_reason(err)}: {url}")])
        session = _Session(client, timeout_s, window_s, tx, names)
        session.checks.append(Check("connect", "pass", f"a rosbridge websocket at {url}"))
        try:
            await session.run()
        except ConnectionClosed:
            session.checks.append(Check("connection", "fail", "the vehicle closed the connection"))
        finally:
            await session.close()
        return Report(url, session.checks)
    finally:
        if tx is not None:
            await tx.aclose()


@dataclass
class _Record:
    """What arrived while the check listened (arrivals on ``time.monotonic()``)."""

    poses: list[tuple[float, float, dict[str, Any]]] = field(default_factory=list)
    statuses: list[tuple[float, dict[str, Any] | None, str | None]] = field(default_factory=list)
    acks: list[Ack] = field(default_factory=list)


class _Session:
    """One connection to the vehicle (subscribed to pose, status and mission by its protocol)
    and everything it received. ``modem``: frames go through it instead of the frame topic."""

    def __init__(
        self,
        client: RosbridgeClient,
        timeout_s: float,
        window_s: float,
        modem: Transmitter | None = None,
        names: TopicNames | None = None,
    ) -> None:
        self.client = client
        self.timeout_s = timeout_s
        self.window_s = window_s
        self.modem = modem
        #: The contract's topics on this vehicle (under its namespace, if any).
        self.names = names = names or topic_names()
        self.talk = ClientProtocol(advertise=[names.frame], subscribe=[])
        self.record = _Record()
        self.checks: list[Check] = []
        self._ack_arrived = asyncio.Event()
        self._status_arrived = asyncio.Event()
        self._advertised_s: float | None = None
        client.handlers.update(
            {
                names.pose: self._pose,
                names.status: lambda msg: self._json(names.status, msg),
                names.mission: lambda msg: self._json(names.mission, msg),
            }
        )
        client.on_close = self._closed

    @property
    def closed(self) -> bool:
        return self.client.closed

    @property
    def path(self) -> str:
        """How a frame goes to the vehicle, in words."""
        if self.modem is None:
            return f"published on {self.names.frame}"
        return f"sent through the modem path ({self.modem.target})"

    async def close(self) -> None:
        closing = self.client.protocol.close_messages()
        if self._advertised_s is not None:
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
        if name == self.names.status:
            self.record.statuses.append((now, body, problem))
            self._status_arrived.set()
        else:
            self.record.acks.append(Ack(now, body, problem))
            self._ack_arrived.set()

    # --- the checks --------------------------------------------------------------------------

    async def run(self) -> None:
        """Every check after ``connect``, appended to :attr:`checks` as it is made."""
        began = time.monotonic()
        await self.client.open()
        graph = await read_graph(self.client, self.timeout_s, names=self.names.by_topic())
        modem = self.modem.target if self.modem else None
        self.checks += graph_checks(graph, modem=modem, names=self.names.by_topic())
        if self.modem is None:
            await self.client.send(*self.talk.open_messages())
            self._advertised_s = time.monotonic()
        await asyncio.sleep(max(0.0, began + self.window_s - time.monotonic()))
        window_s = time.monotonic() - began
        self.checks += pose_checks(self.record.poses, window_s)
        self.checks += status_checks(self.record.statuses, window_s)
        self.checks.append(await self._probe(graph))
        self.checks.append(await self._duplicate())
        self.checks.append(ack_schema_check(self.record.acks))

    async def _send(self, frame: Frame) -> str | None:
        """Send one frame the configured way; None when it left, else why not."""
        if self.modem is None:
            settled_s = (self._advertised_s or 0.0) + ADVERTISE_SETTLE_S
            await asyncio.sleep(max(0.0, settled_s - time.monotonic()))
            await self.client.send(self.talk.publish(self.names.frame, frame_msg(frame)))
            return None
        result = await self.modem.send_async(frame, wait_ack_s=0.0)
        return None if result.sent else f"the modem did not take it: {result.reason}"

    async def _probe(self, graph: VehicleGraph | GraphUnknown) -> Check:
        """The malformed frame (module doc); sent unless the graph shows nobody to answer."""
        name = "ack path (probe)"
        if isinstance(graph, VehicleGraph):
            verdict = verdict_of(graph, frames_over_rosbridge=self.modem is None)
            if not verdict.agent:
                return Check(name, "skipped", "no onboard agent to answer it; nothing was sent")
            if not verdict.frames and self.modem is None:
                why = (
                    f"receiver-only: frames cannot be probed over rosbridge (no node but "
                    f"rosbridge's own subscribes to {self.names.frame}); check through the modem "
                    "path: nemesys vehicle-check URL --modem tcp://HOST:PORT; nothing was sent"
                )
                return Check(name, "fail", why)
        statuses = [body for _, body, _ in self.record.statuses if body is not None]
        active = statuses[-1].get("active", _UNKNOWN) if statuses else _UNKNOWN
        start = len(self.record.acks)
        problem = await self._send(PROBE_FRAME)
        sent_s = time.monotonic()
        if problem is not None:
            return Check(name, "fail", f"a malformed frame {self.path}: {problem}")
        waited_s = max(self.timeout_s, ACK_DEADLINE_S)  # never less than the deadline
        ack = await self._ack_for(PROBE_FRAME, start, waited_s)
        return malformed_probe_check(
            ack, sent_s=sent_s, waited_s=waited_s, path=self.path, active=active
        )

    async def _next_status(self) -> None:
        """Wait for one more status (at most the timeout): the duplicate repeats the command
        the vehicle runs now, not one it ran a status period ago (an operator may retask it)."""
        self._status_arrived.clear()
        if not self.closed:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._status_arrived.wait(), self.timeout_s)

    async def _duplicate(self) -> Check:
        name = "ack path (duplicate)"
        if self.record.statuses:
            await self._next_status()
        # from here to the send nothing is awaited: the command is the newest status's
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
        what = f"re-sent the active command ({enc.command.describe()}) {self.path}"
        problem = await self._send(enc.frame)
        sent_s = time.monotonic()
        if problem is not None:
            return Check(name, "fail", f"{what}: {problem}")
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

    async def _ack_for(self, frame: Frame, start: int, wait_s: float | None = None) -> Ack | None:
        """The first acknowledgement from index ``start`` on that answers ``frame``, within
        ``wait_s`` (default the timeout)."""
        deadline = time.monotonic() + (self.timeout_s if wait_s is None else wait_s)
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
