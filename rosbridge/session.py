"""One client's rosbridge session, sans-IO: what the real ROS 2 ``rosbridge_server`` does with
each message a client sends, and how it paces and splits what it sends back.

Feed :meth:`ClientSession.receive` every text the client sends; each message taken from it
gives an :class:`Outcome`: replies for that client (``service_response``), a
:class:`Publication` (a client's message on a topic, the frame for the vehicle included),
and the lines the real server would write to its log (:class:`LogLine`). As in the ROS 2
server, a client never gets an error message back: errors are only logged.

Outgoing, :meth:`ClientSession.deliver` passes a topic's message through that client's
subscription (``throttle_rate``, ``queue_length``) and :meth:`ClientSession.poll` releases
queued ones when due; every outgoing text is split into ``fragment`` ops when longer than
the client's ``fragment_size`` (set by any message that carries one). A subscription with
``compression`` ``cbor`` or ``cbor-raw`` gets binary CBOR frames instead
(:mod:`rosbridge.compression`).
"""

from __future__ import annotations

import uuid
from collections.abc import Mapping
from typing import Any, Final

from rosbridge.auth import AuthGate
from rosbridge.compression import EncodeError, cbor_publish, cbor_raw_publish
from rosbridge.convert import extract, populate
from rosbridge.errors import (
    BinaryMessage,
    BridgeError,
    FragmentError,
    InvalidName,
    JsonObject,
    MessageId,
    OversizedMessage,
    ServiceError,
    UnknownOp,
    UnsupportedOp,
)
from rosbridge.flow import NOTHING, Defragmenter, IncomingBuffer, Subscription
from rosbridge.graph import Graph, expand_name
from rosbridge.messages import (
    Advertise,
    CallService,
    Fragment,
    LogLine,
    Outcome,
    Publication,
    Publish,
    Request,
    Subscribe,
    Unadvertise,
    Unimplemented,
    Unsubscribe,
    id_key,
    op_name,
    op_of,
    parse_object,
)
from rosbridge.rosapi import call_service
from rosbridge.wire import (
    LOG_ERROR,
    LOG_INFO,
    LOG_WARN,
    binary_frame,
    fragments,
    publish_message,
    service_response,
    wire_json,
)

#: Default limit on one incoming message, UTF-8 bytes (tornado's, as the real server has it).
DEFAULT_MAX_MESSAGE_BYTES: Final = 10 * 1024 * 1024
#: The real server's default ``max_message_size``: longer outgoing messages are fragmented.
DEFAULT_FRAGMENT_SIZE: Final = 10_000_000
#: The real server's ``fragment_timeout``: an incomplete incoming message is forgotten after.
DEFAULT_FRAGMENT_TIMEOUT_S: Final = 600.0


class ClientSession:
    """The rosbridge state of one client: advertisements, subscriptions, fragment size,
    incoming fragments. ``graph`` is shared by all sessions of a server. Never raises for
    the client's input."""

    def __init__(
        self,
        max_message_bytes: int = DEFAULT_MAX_MESSAGE_BYTES,
        graph: Graph | None = None,
        client_id: str | None = None,
        fragment_size: object = DEFAULT_FRAGMENT_SIZE,
        fragment_timeout_s: float = DEFAULT_FRAGMENT_TIMEOUT_S,
        auth: AuthGate | None = None,
    ) -> None:
        if max_message_bytes <= 0:
            raise ValueError("max_message_bytes must be positive")
        self.max_message_bytes = max_message_bytes
        self.graph = graph if graph is not None else Graph()
        self.client_id = client_id or str(uuid.uuid4())
        #: Outgoing texts longer than this are fragmented (any message may set it).
        self.fragment_size = fragment_size
        self._buffer = IncomingBuffer()
        self._subs: dict[str, Subscription] = {}
        self._adverts: dict[str, tuple[str, str, set[Any]]] = {}  # raw -> expanded, type, ids
        self._published: set[str] = set()
        self._latched: set[str] = set()
        self._defragmenter = Defragmenter(max_message_bytes, fragment_timeout_s)
        self._logs: list[LogLine] = []
        #: The training bridge's gate: a client publishes only after ``auth``.
        self.auth = auth

    # -- state -------------------------------------------------------------------------------

    @property
    def advertised(self) -> Mapping[str, str]:
        """Topics (as the client named them) this client advertised, with their type."""
        return {raw: kind for raw, (_, kind, _) in self._adverts.items()}

    @property
    def subscriptions(self) -> Mapping[str, frozenset[MessageId]]:
        """Topics (as the client named them) this client subscribes to, with the ids."""
        return {raw: frozenset(sub.options) for raw, sub in self._subs.items()}

    def is_subscribed(self, topic: str) -> bool:
        """True when a subscription of this client delivers ``topic`` (absolute name)."""
        return any(sub.expanded == topic for sub in self._subs.values())

    def drain_logs(self) -> list[LogLine]:
        """Log lines from :meth:`deliver`, :meth:`poll` and :meth:`encode` since last asked."""
        logs, self._logs = self._logs, []
        return logs

    # -- input -------------------------------------------------------------------------------

    def receive(self, text: str) -> list[Outcome]:
        """Handle one text the client sent: zero, one or several messages."""
        size = len(text)
        if size * 4 > self.max_message_bytes:
            size = len(text.encode("utf-8", "surrogatepass"))
        if size > self.max_message_bytes:
            error = OversizedMessage(
                f"message of {size} bytes exceeds the limit of {self.max_message_bytes}"
            )
            return [self._fail(None, error)]
        self._buffer.add(text)
        outcomes: list[Outcome] = []
        if self._buffer.overflowed:
            text_error = OversizedMessage("unparsed leftover text too long: discarded")
            outcomes.append(self._fail(None, text_error))
        while True:
            value = self._buffer.take()
            if value is NOTHING:
                break
            if self.auth is not None and isinstance(value, dict) and value.get("op") == "auth":
                problem = self.auth.take(value)
                if problem is not None:
                    outcomes.append(self._fail(None, BridgeError(problem, value.get("id"))))
                if not self._buffer.more():
                    break
                continue
            try:
                op_of(value, text)
            except UnknownOp as error:
                # The real server drops the message and stops: a leftover waits for more text.
                outcomes.append(self._fail(None, error))
                break
            assert isinstance(value, dict)
            if "fragment_size" in value:
                self.fragment_size = value["fragment_size"]
            try:
                request = parse_object(value, text)
            except BridgeError as error:
                outcomes.append(self._fail(None, error))
            else:
                outcomes.extend(self.handle(request))
            if not self._buffer.more():
                break
        return outcomes

    def receive_text(self, text: str) -> Outcome:
        """:meth:`receive` for one message: its outcome (or an empty one)."""
        outcomes = self.receive(text)
        return outcomes[-1] if outcomes else Outcome()

    def receive_binary(self, data: bytes) -> list[Outcome]:
        """A binary frame: UTF-8 JSON as if it were text (as the real server takes it);
        anything else makes the real server drop the connection (``close``)."""
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as exc:
            error = BinaryMessage(f"binary frame of {len(data)} bytes is not UTF-8: {exc}")
            return [Outcome(error=error, logs=(LogLine(LOG_ERROR, error.reason),), close=True)]
        return self.receive(text)

    def handle(self, request: Request) -> list[Outcome]:
        """Act on one parsed request."""
        try:
            match request:
                case Advertise():
                    return [self._advertise(request)]
                case Unadvertise():
                    return [self._unadvertise(request)]
                case Publish():
                    return [self._publish(request)]
                case Subscribe():
                    return [self._subscribe(request)]
                case Unsubscribe():
                    return [self._unsubscribe(request)]
                case CallService():
                    return [self._call_service(request)]
                case Fragment():
                    return self._fragment(request)
                case Unimplemented():
                    raise UnsupportedOp(
                        f"{request.op} is not implemented by the NemeSys simulator", request.id
                    )
        except BridgeError as error:
            return [self._fail(request, error)]
        raise TypeError(f"not a request: {request!r}")  # pragma: no cover - exhaustive match

    # -- op handlers -------------------------------------------------------------------------

    def _advertise(self, request: Advertise) -> Outcome:
        expanded, kind = self.graph.add_publisher(self.client_id, request.topic, request.type)
        _, _, ids = self._adverts.setdefault(request.topic, (expanded, kind, set()))
        ids.add(id_key(request.id))
        if request.latch:
            self._latched.add(expanded)
        return Outcome(request)

    def _unadvertise(self, request: Unadvertise) -> Outcome:
        entry = self._adverts.get(request.topic)
        if entry is None:
            return Outcome(request)
        expanded, _, ids = entry
        if request.id is None:
            ids.clear()
        else:
            ids.discard(id_key(request.id))
        if not ids:
            del self._adverts[request.topic]
            self._published.discard(expanded)
            self._latched.discard(expanded)
            self.graph.remove_publisher(self.client_id, expanded)
        return Outcome(request)

    def _publish(self, request: Publish) -> Outcome:
        refusal = self.auth.refusal(request.topic) if self.auth is not None else None
        if refusal is not None:
            raise BridgeError(refusal, request.id)
        expanded, kind = self.graph.add_publisher(self.client_id, request.topic, None)
        self._published.add(expanded)
        message = populate(kind, request.msg, self.graph.ros_time())
        msg = extract(kind, message)
        if request.latch or expanded in self._latched:
            self.graph.latched[expanded] = msg
        frame = bytes(message["data"]) if expanded in self.graph.frame_topics else None
        return Outcome(request, publication=Publication(expanded, kind, msg, frame))

    def _subscribe(self, request: Subscribe) -> Outcome:
        sub = self._subs.get(request.topic)
        if sub is None:
            expanded, kind = self.graph.add_subscriber(self.client_id, request.topic, request.type)
            sub = Subscription(expanded, kind)
        elif request.type is not None:
            self.graph.add_subscriber(self.client_id, request.topic, request.type)
        before = dict(sub.options)
        sub.options[id_key(request.id)] = (
            request.throttle_rate,
            request.queue_length,
            request.compression,
        )
        try:
            sub.update()
        except ValueError as exc:
            sub.options = before
            if not before and not self.is_subscribed(sub.expanded):
                self.graph.remove_subscriber(self.client_id, sub.expanded)
            raise BridgeError(str(exc), request.id) from None
        self._subs[request.topic] = sub
        logs = [LogLine(LOG_INFO, f"Subscribed to {request.topic}")]
        if request.compression == "png":
            logs.append(
                LogLine(
                    LOG_WARN,
                    "compression 'png' is not implemented by the NemeSys simulator: JSON is sent",
                    request.id,
                )
            )
        texts: list[str | bytes] = []
        latched = self.graph.latched.get(sub.expanded)
        if latched is not None:
            texts = self._through(request.topic, sub, latched)
        return Outcome(request, texts=tuple(texts), logs=tuple(logs))

    def _unsubscribe(self, request: Unsubscribe) -> Outcome:
        sub = self._subs.get(request.topic)
        if sub is None:
            return Outcome(request)
        if request.id is None:
            sub.options.clear()
        else:
            sub.options.pop(id_key(request.id), None)
        if sub.options:
            sub.update()
        else:
            del self._subs[request.topic]
            if not self.is_subscribed(sub.expanded):
                self.graph.remove_subscriber(self.client_id, sub.expanded)
        return Outcome(request, logs=(LogLine(LOG_INFO, f"Unsubscribed from {request.topic}"),))

    def _call_service(self, request: CallService) -> Outcome:
        service, cid = request.service, request.id
        if cid is None and "#" in service:  # the deprecated /service#id form
            cid = service[service.find("#") + 1 :]
        name = service.split("#", 1)[0]
        try:
            values = call_service(self.graph, expand_name(name, "service"), request.args)
        except (ServiceError, InvalidName) as exc:
            kind = {
                InvalidName: "InvalidServiceNameException",
                ServiceError: "InvalidServiceException"
                if exc.reason.endswith("does not exist")
                else "ServiceException",
            }[type(exc)]
            log = LogLine(LOG_ERROR, f"call_service {kind}: {exc.reason}", cid)
            reply = service_response(service, exc.reason, False, cid)
            return Outcome(request, replies=(reply,), error=exc, logs=(log,))
        return Outcome(request, replies=(service_response(service, values, True, cid),))

    def _fragment(self, request: Fragment) -> list[Outcome]:
        text, warnings = self._defragmenter.add(request, self.graph.clock())
        logs = tuple(LogLine(LOG_WARN, warning) for warning in warnings)
        if text is None:
            return [Outcome(request, logs=logs)]
        return [Outcome(request, logs=logs), *self.receive(text)]

    # -- output ------------------------------------------------------------------------------

    def encode(self, message: JsonObject) -> tuple[str, ...]:
        """A server -> client message as the texts to send (fragments when too long).
        Raises :class:`FragmentError` where the real server's send fails."""
        return fragments(wire_json(message), self.fragment_size, message.get("id"))

    def deliver(self, topic: str, msg: JsonObject) -> list[str | bytes]:
        """What to send now for a message on ``topic`` (absolute name), through every
        subscription of this client that delivers it: texts, or binary frames (CBOR)."""
        out: list[str | bytes] = []
        for raw, sub in self._subs.items():
            if sub.expanded == topic:
                out.extend(self._through(raw, sub, msg))
        return out

    def _through(self, raw: str, sub: Subscription, msg: JsonObject) -> list[str | bytes]:
        return self._send(raw, sub, sub.handler.handle(msg, self.graph.clock()))

    def poll(self) -> list[str | bytes]:
        """Queued messages (``queue_length``) that are due now."""
        now = self.graph.clock()
        out: list[str | bytes] = []
        for raw, sub in self._subs.items():
            out.extend(self._send(raw, sub, sub.handler.poll(now)))
        return out

    def _send(self, raw: str, sub: Subscription, msgs: list[JsonObject]) -> list[str | bytes]:
        """Messages a subscription released, encoded as its ``compression`` asks: JSON text
        (fragmented past ``fragment_size``) or one CBOR binary frame each. One that cannot be
        sent is logged as the real server logs a failed subscribe callback."""
        out: list[str | bytes] = []
        for msg in msgs:
            try:
                if sub.compression == "cbor-raw":
                    data = cbor_raw_publish(raw, sub.type, msg, self.graph.ros_time())
                    out.append(binary_frame(data, self.fragment_size))
                elif sub.compression == "cbor":
                    data = cbor_publish(raw, sub.type, msg)
                    out.append(binary_frame(data, self.fragment_size))
                else:
                    text = wire_json(publish_message(raw, msg))
                    out.extend(fragments(text, self.fragment_size))
            except (FragmentError, EncodeError) as error:
                self._logs.append(
                    LogLine(LOG_ERROR, f"Exception calling subscribe callback: {error.reason}")
                )
        return out

    def close(self) -> None:
        """The client left: the bridge drops its subscriptions and publishers."""
        for sub in self._subs.values():
            self.graph.remove_subscriber(self.client_id, sub.expanded)
        for expanded in {e for e, _, _ in self._adverts.values()} | self._published:
            self.graph.remove_publisher(self.client_id, expanded)
        self._subs.clear()
        self._adverts.clear()
        self._published.clear()

    def _fail(self, request: Request | None, error: BridgeError) -> Outcome:
        op = op_name(request) if request is not None else None
        reason = error.reason
        if op is not None and not reason.startswith(f"{op}:"):
            reason = f"{op}: {reason}"
        op_id = request.id if request is not None else error.op_id
        return Outcome(request, error=error, logs=(LogLine(LOG_ERROR, reason, op_id),))
