"""Transmitters: hand an encoded frame to the vehicle and report what happened.

One interface, several transports. :meth:`Transmitter.send` takes a :class:`codec.Frame` and
returns a :class:`SendResult`: sent (with the vehicle's acknowledgement when the transport can
get one) or failed with a short reason ("connection refused", "timeout", "port not found", ...).
``send`` never raises for a transport problem.

* :class:`RosbridgeTransmitter`: a rosbridge v2 endpoint (the simulated vehicle, or a real
  vehicle behind a rosbridge). Publishes the frame on ``/nemesys/frame`` and waits for the
  vehicle's acknowledgement on ``/nemesys/mission``.
* :class:`SerialTransmitter`: a real ME transmitter (modem) on a serial port, or behind a TCP
  gateway; any URL :func:`serial.serial_for_url` opens (``/dev/ttyUSB0``, ``socket://h:p``,
  ``loop://``). The modem gives no acknowledgement.

:func:`open_transmitter` picks one from a target string (``ws://``, ``wss://``,
``serial:///dev/...``, ``tcp://host:port``, ``loop://``).

Serial and TCP wire format
--------------------------
Each frame is written as exactly :data:`codec.FRAME_BYTES` = 13 bytes,
:meth:`codec.Frame.to_bytes`: the 100 frame bits, first bit on the link = most significant bit
of byte 0, then 4 zero padding bits (the low nibble of byte 12). Nothing else is written: no
length prefix, no checksum, no delimiter, no newline; the frame carries its own preamble and
delimiter for synchronisation. The 13 bytes of a frame go out in one ``write`` call, followed
by a flush (``tcdrain`` on a serial port). The modem is expected to clock out the first 100 bits
at the link rate (36 kb/s by default), drop the 4 padding bits, and send nothing back (no echo,
no acknowledgement: the transmitter never reads). Between two frames the station waits at least
one frame's airtime (100 bits at ``bitrate_bps``, 2.78 ms at 36 kb/s) after the previous flush,
so the modem never has to queue. Serial settings: ``baudrate`` (default 115200), 8N1, no flow
control. See ``docs/transmitters.md``.

Rosbridge acknowledgement matching
----------------------------------
Acknowledgements already waiting on the connection are discarded before the publish. After it,
the first mission message whose ``frame_hex`` is the sent frame is the acknowledgement
("exact"); so is one whose codeword is within the BCH correction radius (``CODE.t`` = 2 bits)
of the sent codeword, differences in the fixed preamble, delimiter and guard bits not counting
("near": the channel flipped bits). Any other new acknowledgement is kept as a fallback: if no
exact or near one follows within ``settle_s`` (0.5 s) of it, or before the timeout, the first
such acknowledgement is returned ("first": matched by order, e.g. the vehicle slipped bits and
reports what it received). No acknowledgement within ``wait_ack_s`` of the publish: failed,
reason "timeout" (``sent_t`` is set, the frame did go out).

Rosbridge: waiting for the vehicle's subscriber
-----------------------------------------------
On a new connection the transmitter advertises ``/nemesys/frame`` and, before its first
publish, waits until the vehicle subscribes to it (:mod:`sim_bridge.subscriber_wait`): a real
rosbridge_server creates a new publisher for the advertisement, and a vehicle subscriber not
yet matched to it would miss a frame published at once. It asks ``/rosapi/subscribers`` and
publishes as soon as a subscriber is listed; if rosapi cannot tell, it publishes
``subscriber_wait_s`` (1 s) after advertising; if rosapi says nobody subscribes for that long,
it publishes anyway and the result's ``warning`` says the frame may be lost. Whatever the wait
found is added to ``detail`` when no acknowledgement came back. A kept connection does not
wait again.
"""

from __future__ import annotations

import abc
import asyncio
import contextlib
import errno
import logging
import socket
import threading
import time
from dataclasses import asdict, dataclass
from types import TracebackType
from typing import Any, ClassVar, Literal, Self
from urllib.parse import SplitResult, parse_qs, urlsplit

import serial
from websockets.asyncio.client import ClientConnection as AsyncConnection
from websockets.asyncio.client import connect as async_connect
from websockets.exceptions import (
    ConnectionClosed,
    InvalidHandshake,
    InvalidStatus,
    InvalidURI,
    WebSocketException,
)
from websockets.protocol import State
from websockets.sync.client import ClientConnection as SyncConnection
from websockets.sync.client import connect as sync_connect

from codec import (
    CODE,
    DEFAULT_BITRATE_BPS,
    FRAME_BYTES,
    DecodeError,
    Frame,
    airtime_s,
    parse_frame,
)
from sim_bridge.rosbridge import (
    FRAME_TOPIC,
    MISSION_TOPIC,
    BinaryMessage,
    BridgeError,
    InvalidData,
)
from sim_bridge.rosbridge_client import ClientProtocol, decode_json_string, decode_server_message
from sim_bridge.subscriber_wait import DEFAULT_SUBSCRIBER_WAIT_S, SubscriberWait

logger = logging.getLogger(__name__)
logger.addHandler(logging.NullHandler())  # a library: the application configures output

DEFAULT_ROSBRIDGE_URL = "ws://127.0.0.1:9090"

#: How long ``send`` waits for an acknowledgement by default (s).
DEFAULT_ACK_TIMEOUT_S = 5.0
#: After a new acknowledgement that is not for the sent frame, how long to wait for one that is.
ACK_SETTLE_S = 0.5
DEFAULT_OPEN_TIMEOUT_S = 5.0
DEFAULT_BAUDRATE = 115_200
DEFAULT_WRITE_TIMEOUT_S = 2.0

#: The target forms :func:`open_transmitter` accepts.
TARGET_FORMS = (
    "ws://host:port[/path]",
    "wss://host:port[/path]",
    "serial:///dev/ttyUSB0[?baud=115200]",
    "tcp://host:port",
    "loop://",
)

AckMatch = Literal["exact", "near", "first"]


@dataclass(frozen=True, slots=True)
class SendResult:
    """What became of one frame.

    ``ok`` is True when the frame went out and, if an acknowledgement was awaited, one came
    back. It says nothing about whether the vehicle *accepted* the command: see
    :attr:`accepted`. On failure ``reason`` is a short phrase ("connection refused", "timeout",
    "port not found", ...) and ``detail`` the longer story.
    """

    ok: bool
    transport: str
    target: str
    reason: str | None = None
    #: Wall-clock time (``time.time()``) the frame was handed to the transport; None if never.
    sent_t: float | None = None
    #: The vehicle's acknowledgement (mission message) when the transport gets one.
    ack: dict[str, Any] | None = None
    #: How ``ack`` was matched to the frame (see the module docstring).
    ack_match: AckMatch | None = None
    detail: str = ""
    #: Something the caller should be told although the frame went out (e.g. no subscriber).
    warning: str | None = None

    @property
    def sent(self) -> bool:
        """The frame left the station (even if no acknowledgement came back)."""
        return self.sent_t is not None

    @property
    def accepted(self) -> bool | None:
        """The vehicle's verdict: True accepted, False rejected, None no acknowledgement."""
        if self.ack is None:
            return None
        return self.ack.get("outcome") == "accepted"

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


class Transmitter(abc.ABC):
    """Sends frames to the vehicle. Use as a (sync or async) context manager, or call close."""

    transport: ClassVar[str]

    def __init__(self, target: str) -> None:
        self.target = target

    @abc.abstractmethod
    def send(self, frame: Frame, *, wait_ack_s: float = DEFAULT_ACK_TIMEOUT_S) -> SendResult:
        """Transmit ``frame``; wait up to ``wait_ack_s`` for an acknowledgement when the
        transport gives one (0: don't wait). Never raises for a transport failure."""

    async def send_async(
        self, frame: Frame, *, wait_ack_s: float = DEFAULT_ACK_TIMEOUT_S
    ) -> SendResult:
        """:meth:`send` without blocking the event loop (a worker thread unless overridden)."""
        return await asyncio.to_thread(self.send, frame, wait_ack_s=wait_ack_s)

    @abc.abstractmethod
    def close(self) -> None:
        """Release the connection or port. Sending again reopens it."""

    async def aclose(self) -> None:
        await asyncio.to_thread(self.close)

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    async def __aenter__(self) -> Self:
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        await self.aclose()

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.target!r})"

    def _failed(
        self,
        reason: str,
        detail: str,
        sent_t: float | None = None,
        warning: str | None = None,
    ) -> SendResult:
        # INFO: the caller gets the failure in the result and decides how loud to be
        logger.info("%s %s: %s (%s)", self.transport, self.target, reason, detail)
        return SendResult(
            ok=False,
            transport=self.transport,
            target=self.target,
            reason=reason,
            sent_t=sent_t,
            detail=detail,
            warning=warning,
        )


# --- failure reasons ----------------------------------------------------------------------

_ERRNO_REASONS = {
    errno.ENOENT: "port not found",
    errno.ENODEV: "port not found",
    errno.ENXIO: "port not found",
    errno.EACCES: "permission denied",
    errno.EPERM: "permission denied",
    errno.EBUSY: "port busy",
    errno.ENOTTY: "not a serial port",
    errno.ECONNREFUSED: "connection refused",
    errno.ECONNRESET: "connection reset",
    errno.EPIPE: "connection closed",
    errno.ETIMEDOUT: "timeout",
    errno.EHOSTUNREACH: "host unreachable",
    errno.ENETUNREACH: "network unreachable",
}


def failure_reason(exc: BaseException, default: str = "error") -> str:
    """A short reason for a transport exception, looking through its chained causes."""
    seen: BaseException | None = exc
    for _ in range(5):
        if seen is None:
            break
        if isinstance(seen, InvalidURI):
            return "bad url"
        if isinstance(seen, InvalidStatus):
            return f"handshake failed (HTTP {seen.response.status_code})"
        if isinstance(seen, InvalidHandshake):
            return "handshake failed"
        if isinstance(seen, ConnectionClosed):
            return "connection closed"
        if isinstance(seen, serial.SerialTimeoutException):
            return "write timeout"
        if isinstance(seen, socket.gaierror):
            return "host not found"
        if isinstance(seen, TimeoutError):
            return "timeout"
        code = getattr(seen, "errno", None)
        if code is None and seen.args and isinstance(seen.args[0], int):
            code = seen.args[0]  # termios.error carries (errno, message) without .errno
        if isinstance(code, int) and code in _ERRNO_REASONS:
            return _ERRNO_REASONS[code]
        seen = seen.__cause__ or seen.__context__
    return default


def _message(exc: BaseException) -> str:
    """An exception's text without the ``[Errno n]`` prefix."""
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    return str(exc) or type(exc).__name__


# --- serial and TCP -----------------------------------------------------------------------


class SerialTransmitter(Transmitter):
    """A real ME transmitter on a serial port or behind a TCP gateway (see the wire format in
    the module docstring). ``url`` is anything :func:`serial.serial_for_url` opens. The port is
    opened on the first send and kept open; after a write error it is closed and reopened on the
    next send. Thread-safe."""

    transport = "serial"

    def __init__(
        self,
        url: str,
        *,
        baudrate: int = DEFAULT_BAUDRATE,
        bitrate_bps: float = DEFAULT_BITRATE_BPS,
        write_timeout_s: float = DEFAULT_WRITE_TIMEOUT_S,
        name: str | None = None,
    ) -> None:
        super().__init__(name or url)
        self.url = url
        self.baudrate = baudrate
        self.write_timeout_s = write_timeout_s
        #: The least time between the end of one frame's write and the start of the next.
        self.gap_s = airtime_s(bitrate_bps)
        self.frames_sent = 0
        self._port: serial.SerialBase | None = None
        self._next_t = 0.0  # time.monotonic() before which the next frame must not start
        self._lock = threading.Lock()

    @property
    def port(self) -> serial.SerialBase | None:
        """The open port (None before the first send or after close): diagnostics and tests."""
        return self._port

    def open(self) -> None:
        """Open the port now rather than on the first send. Raises ``serial.SerialException``."""
        with self._lock:
            self._ensure_open()

    def _ensure_open(self) -> serial.SerialBase:
        if self._port is None:
            port = serial.serial_for_url(
                self.url, baudrate=self.baudrate, write_timeout=self.write_timeout_s
            )
            self._port = port
            logger.info("opened %s at %d baud", self.url, self.baudrate)
        return self._port

    def send(self, frame: Frame, *, wait_ack_s: float = DEFAULT_ACK_TIMEOUT_S) -> SendResult:
        """Write the frame's 13 bytes. ``wait_ack_s`` is ignored: the modem acknowledges
        nothing, so a write that completes is ``ok`` with ``ack`` None."""
        data = frame.to_bytes()
        with self._lock:
            try:
                port = self._ensure_open()
            except (serial.SerialException, OSError, ValueError) as exc:
                return self._failed(failure_reason(exc), _message(exc))
            delay_s = self._next_t - time.monotonic()
            if delay_s > 0:
                time.sleep(delay_s)
            try:
                written = port.write(data)
                port.flush()
            except (serial.SerialException, OSError) as exc:
                self._close_port()
                return self._failed(failure_reason(exc), f"writing to {self.url}: {_message(exc)}")
            if written is not None and written != len(data):
                self._close_port()
                return self._failed(
                    "short write", f"wrote {written} of {len(data)} bytes to {self.url}"
                )
            sent_t = time.time()
            self._next_t = time.monotonic() + self.gap_s
            self.frames_sent += 1
        logger.info("wrote frame %s to %s", frame.hex, self.target)
        return SendResult(
            ok=True,
            transport=self.transport,
            target=self.target,
            sent_t=sent_t,
            detail=f"wrote {FRAME_BYTES} bytes; the modem gives no acknowledgement",
        )

    def _close_port(self) -> None:
        port, self._port = self._port, None
        if port is not None:
            try:
                port.close()
            except (serial.SerialException, OSError) as exc:
                logger.debug("closing %s: %s", self.url, exc)

    def close(self) -> None:
        with self._lock:
            self._close_port()


# --- rosbridge ----------------------------------------------------------------------------


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


def frame_msg(frame: Frame) -> dict[str, Any]:
    """The ``std_msgs/UInt8MultiArray`` a station publishes for ``frame``: its 13 bytes as
    ``{"data": [13 ints]}`` (no layout, as roslibpy users write it)."""
    return {"data": list(frame.to_bytes())}


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


def _log_wait(wait: SubscriberWait | None, url: str) -> None:
    if wait is None:
        return
    if wait.present:
        logger.info("%s: %s has subscribers %s", url, wait.topic, ", ".join(wait.subscribers or []))
    elif wait.warning is not None:
        logger.warning("%s: %s", url, wait.warning)
    else:
        logger.info("%s: %s", url, wait.note)


class RosbridgeTransmitter(Transmitter):
    """Publishes frames to a rosbridge v2 endpoint and waits for the vehicle's acknowledgement.

    On connecting it advertises :data:`FRAME_TOPIC` (``std_msgs/UInt8MultiArray``) and
    subscribes to :data:`MISSION_TOPIC` (``std_msgs/String`` whose ``data`` is a JSON object);
    each frame is published as ``{"data": [13 ints]}``. The connection is opened on the first
    send and kept; a connection found closed is reopened once. ``send`` (sync, thread-safe) and
    ``send_async`` (asyncio) each keep their own connection. Acknowledgements are matched as the
    module docstring says.
    """

    transport = "rosbridge"

    def __init__(
        self,
        url: str = DEFAULT_ROSBRIDGE_URL,
        *,
        open_timeout_s: float = DEFAULT_OPEN_TIMEOUT_S,
        settle_s: float = ACK_SETTLE_S,
        subscriber_wait_s: float = DEFAULT_SUBSCRIBER_WAIT_S,
    ) -> None:
        super().__init__(url)
        self.url = url
        self.open_timeout_s = open_timeout_s
        self.settle_s = settle_s
        #: On a new connection, the most the first publish waits for the vehicle's subscriber
        #: (0: not at all; see the module docstring).
        self.subscriber_wait_s = subscriber_wait_s
        #: What the wait on the newest connection found, until a send reports it.
        self._wait: SubscriberWait | None = None
        self._protocol = ClientProtocol(advertise=[FRAME_TOPIC], subscribe=[MISSION_TOPIC])
        self._conn: SyncConnection | None = None
        self._lock = threading.Lock()
        self._link: _AsyncLink | None = None
        self._alock: asyncio.Lock | None = None
        self._alock_loop: asyncio.AbstractEventLoop | None = None

    @property
    def connected(self) -> bool:
        """The sync connection is open."""
        return self._conn is not None and self._conn.state is State.OPEN

    # sync ---------------------------------------------------------------------------------

    def _connect(self) -> SyncConnection:
        conn = sync_connect(
            self.url, open_timeout=self.open_timeout_s, close_timeout=1.0, proxy=None
        )
        try:
            for message in self._protocol.open_messages():
                conn.send(message)
            self._wait = self._await_subscriber(conn)
        except BaseException:
            conn.close()
            raise
        logger.info("connected to %s", self.url)
        return conn

    def _new_wait(self) -> SubscriberWait | None:
        if self.subscriber_wait_s <= 0:
            return None
        return SubscriberWait(self._protocol, FRAME_TOPIC, self.subscriber_wait_s, time.monotonic())

    def _await_subscriber(self, conn: SyncConnection) -> SubscriberWait | None:
        """Block until the frame topic has a subscriber or the bound (module docstring);
        acknowledgements arriving meanwhile are old ones and are dropped."""
        wait = self._new_wait()
        while wait is not None and not wait.done(time.monotonic()):
            if (ask := wait.ask(time.monotonic())) is not None:
                conn.send(ask)
            try:
                data = conn.recv(timeout=wait.timeout_s(time.monotonic()))
            except TimeoutError:
                continue
            message = _server_message(data)
            if message is not None and not wait.offer(message, time.monotonic()):
                logger.debug("while waiting for a subscriber, ignoring %s", message.get("op"))
        _log_wait(wait, self.url)
        return wait

    def _drain(self, conn: SyncConnection) -> None:
        while True:
            try:
                data = conn.recv(timeout=0)
            except TimeoutError:
                return
            ack = _mission_of(data)
            if ack is not None:
                logger.debug("discarding earlier acknowledgement seq=%s", ack.get("seq"))

    def _ready(self) -> SyncConnection:
        if self._conn is not None:
            try:
                self._drain(self._conn)
                if self._conn.state is State.OPEN:
                    return self._conn
            except ConnectionClosed:
                pass
            logger.info("connection to %s was closed; reconnecting", self.url)
            self._drop()
        self._conn = self._connect()
        return self._conn

    def _publish(self, frame: Frame) -> SyncConnection:
        """Publish on a ready connection; if a kept connection turns out closed (the frame was
        not written), publish once more on a new one."""
        message = self._protocol.publish(FRAME_TOPIC, frame_msg(frame))
        reused = self._conn is not None
        conn = self._ready()
        try:
            conn.send(message)
        except ConnectionClosed:
            if not reused:
                raise
            logger.info("connection to %s was closed; reconnecting", self.url)
            self._drop()
            conn = self._ready()
            conn.send(message)
        return conn

    def _drop(self) -> None:
        conn, self._conn = self._conn, None
        if conn is not None:
            conn.close()

    def send(self, frame: Frame, *, wait_ack_s: float = DEFAULT_ACK_TIMEOUT_S) -> SendResult:
        with self._lock:
            try:
                return self._send(frame, wait_ack_s)
            except Exception as exc:  # send reports, never raises
                logger.exception("sending to %s", self.url)
                self._drop()
                return self._failed("internal error", f"{type(exc).__name__}: {exc}")

    def _send(self, frame: Frame, wait_ack_s: float) -> SendResult:
        try:
            conn = self._publish(frame)
        except (OSError, WebSocketException) as exc:
            self._drop()
            return self._failed(failure_reason(exc), f"{self.url}: {_message(exc)}")
        wait, self._wait = self._wait, None
        sent_t = time.time()
        logger.info("published frame %s to %s", frame.hex, self.url)
        matcher = _AckMatcher(frame, wait_ack_s, self.settle_s)  # expired at once if not waiting
        closed = False
        try:
            while (remaining_s := matcher.remaining_s()) > 0:
                try:
                    data = conn.recv(timeout=remaining_s)
                except TimeoutError:
                    break
                ack = _mission_of(data)
                if ack is not None and matcher.offer(ack):
                    break
        except (OSError, WebSocketException) as exc:
            logger.info("connection to %s lost while waiting: %s", self.url, exc)
            self._drop()
            closed = True
        return self._outcome(matcher, sent_t, wait_ack_s, closed, wait)

    def _outcome(
        self,
        matcher: _AckMatcher,
        sent_t: float,
        wait_ack_s: float,
        closed: bool,
        wait: SubscriberWait | None = None,
    ) -> SendResult:
        warning = wait.warning if wait is not None else None
        note = f"; {wait.note}" if wait is not None and wait.note else ""
        if wait_ack_s <= 0:
            return SendResult(
                ok=True,
                transport=self.transport,
                target=self.target,
                sent_t=sent_t,
                detail=f"published; not waiting for an acknowledgement{note}",
                warning=warning,
            )
        if matcher.ack is None:
            if closed:
                return self._failed(
                    "connection closed",
                    f"{self.url} closed the connection after the frame was published, "
                    f"before an acknowledgement{note}",
                    sent_t,
                    warning,
                )
            return self._failed(
                "timeout",
                f"frame published, no acknowledgement within {wait_ack_s:g} s{note}",
                sent_t,
                warning,
            )
        detail = {
            "exact": "acknowledged",
            "near": "acknowledged (the frame arrived with bit errors)",
            "first": "acknowledged by order: the acknowledgement's frame_hex is not the sent "
            "frame's (bit slip, or another station's frame)",
        }[matcher.match or "first"]
        return SendResult(
            ok=True,
            transport=self.transport,
            target=self.target,
            sent_t=sent_t,
            ack=matcher.ack,
            ack_match=matcher.match,
            detail=detail,
            warning=warning,
        )

    def close(self) -> None:
        """Close the sync connection (unsubscribing and unadvertising first). An async
        connection is aborted; from async code prefer :meth:`aclose`."""
        with self._lock:
            conn, self._conn = self._conn, None
            if conn is not None:
                try:
                    for message in self._protocol.close_messages():
                        conn.send(message)
                except (OSError, WebSocketException) as exc:
                    logger.debug("closing %s: %s", self.url, exc)
                conn.close()
        link, self._link = self._link, None
        if link is not None:
            link.abort_threadsafe()

    # async --------------------------------------------------------------------------------

    def _async_lock(self) -> asyncio.Lock:
        loop = asyncio.get_running_loop()
        if self._alock is None or self._alock_loop is not loop:
            self._alock, self._alock_loop = asyncio.Lock(), loop
        return self._alock

    async def _async_ready(self) -> _AsyncLink:
        link = self._link
        if link is not None:
            if link.loop is asyncio.get_running_loop():
                link.drain()
                if not link.closed and link.conn.state is State.OPEN:
                    return link
                logger.info("connection to %s was closed; reconnecting", self.url)
            await self._async_drop()
        conn = await async_connect(
            self.url, open_timeout=self.open_timeout_s, close_timeout=1.0, proxy=None
        )
        try:
            for message in self._protocol.open_messages():
                await conn.send(message)
        except BaseException:
            await conn.close()
            raise
        logger.info("connected to %s", self.url)
        self._link = _AsyncLink(conn)
        self._wait = await self._async_await_subscriber(self._link)
        return self._link

    async def _async_await_subscriber(self, link: _AsyncLink) -> SubscriberWait | None:
        """:meth:`_await_subscriber` on the async connection."""
        wait = self._new_wait()
        while wait is not None and not wait.done(time.monotonic()):
            if (ask := wait.ask(time.monotonic())) is not None:
                await link.conn.send(ask)
            try:
                message = await asyncio.wait_for(
                    link.responses.get(), wait.timeout_s(time.monotonic())
                )
            except TimeoutError:
                continue
            wait.offer(message, time.monotonic())
        link.drain()
        _log_wait(wait, self.url)
        return wait

    async def _async_publish(self, frame: Frame) -> _AsyncLink:
        """As :meth:`_publish`, on the async connection."""
        message = self._protocol.publish(FRAME_TOPIC, frame_msg(frame))
        reused = self._link is not None
        link = await self._async_ready()
        try:
            await link.conn.send(message)
        except ConnectionClosed:
            if not reused:
                raise
            logger.info("connection to %s was closed; reconnecting", self.url)
            await self._async_drop()
            link = await self._async_ready()
            await link.conn.send(message)
        return link

    async def _async_drop(self, *, polite: bool = False) -> None:
        link, self._link = self._link, None
        if link is None:
            return
        if link.loop is not asyncio.get_running_loop():  # opened under another event loop
            link.abort_threadsafe()
            return
        if polite and not link.closed:
            try:
                for message in self._protocol.close_messages():
                    await link.conn.send(message)
            except (OSError, WebSocketException) as exc:
                logger.debug("closing %s: %s", self.url, exc)
        await link.conn.close()
        link.reader.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await link.reader

    async def send_async(
        self, frame: Frame, *, wait_ack_s: float = DEFAULT_ACK_TIMEOUT_S
    ) -> SendResult:
        """:meth:`send` on the running event loop (its own connection)."""
        async with self._async_lock():
            try:
                return await self._send_async(frame, wait_ack_s)
            except Exception as exc:  # send reports, never raises
                logger.exception("sending to %s", self.url)
                await self._async_drop()
                return self._failed("internal error", f"{type(exc).__name__}: {exc}")

    async def _send_async(self, frame: Frame, wait_ack_s: float) -> SendResult:
        try:
            link = await self._async_publish(frame)
        except (OSError, WebSocketException) as exc:
            await self._async_drop()
            return self._failed(failure_reason(exc), f"{self.url}: {_message(exc)}")
        wait, self._wait = self._wait, None
        sent_t = time.time()
        logger.info("published frame %s to %s", frame.hex, self.url)
        matcher = _AckMatcher(frame, wait_ack_s, self.settle_s)  # expired at once if not waiting
        closed = False
        while (remaining_s := matcher.remaining_s()) > 0:
            try:
                ack = await asyncio.wait_for(link.acks.get(), remaining_s)
            except TimeoutError:
                break
            if ack is None:
                logger.info("connection to %s lost while waiting", self.url)
                await self._async_drop()
                closed = True
                break
            if matcher.offer(ack):
                break
        return self._outcome(matcher, sent_t, wait_ack_s, closed, wait)

    async def aclose(self) -> None:
        """Close both connections, unsubscribing and unadvertising first."""
        await self._async_drop(polite=True)
        await asyncio.to_thread(self.close)


# --- targets ------------------------------------------------------------------------------


def _bad_target(target: str, problem: str) -> ValueError:
    return ValueError(
        f"bad transmitter target {target!r}: {problem}; expected one of {', '.join(TARGET_FORMS)}"
    )


def _host_port(target: str, split: SplitResult, *, port_required: bool) -> None:
    if not split.hostname:
        raise _bad_target(target, "no host")
    try:
        port = split.port
    except ValueError:
        raise _bad_target(target, "the port must be a number from 1 to 65535") from None
    if port is None and port_required:
        raise _bad_target(target, "no port")
    if port == 0:
        raise _bad_target(target, "the port must be a number from 1 to 65535")


def _serial_baud(target: str, query: str) -> int:
    try:
        options = parse_qs(query, keep_blank_values=True, strict_parsing=bool(query))
    except ValueError:
        raise _bad_target(target, f"cannot parse the options {query!r}") from None
    unknown = sorted(set(options) - {"baud"})
    if unknown:
        raise _bad_target(target, f"unknown option {unknown[0]!r} (only baud=)")
    if "baud" not in options:
        return DEFAULT_BAUDRATE
    text = options["baud"][-1]
    if not text.isdigit() or int(text) <= 0:
        raise _bad_target(target, f"baud must be a positive whole number, got {text!r}")
    return int(text)


def open_transmitter(target: str, *, bitrate_bps: float = DEFAULT_BITRATE_BPS) -> Transmitter:
    """The transmitter for a target string (see :data:`TARGET_FORMS`). Nothing is opened
    until the first send. ``bitrate_bps`` sets the serial inter-frame gap.

    Raises:
        ValueError: the target is malformed or of an unknown kind (the message says which
            part and lists the accepted forms).
    """
    text = target.strip()
    if not text:
        raise _bad_target(target, "empty")
    if "://" not in text:
        hint = f" (a device path? write serial://{text})" if text.startswith("/dev/") else ""
        raise _bad_target(target, f"no scheme{hint}")
    try:
        split = urlsplit(text)
    except ValueError as exc:
        raise _bad_target(target, str(exc)) from None
    scheme = split.scheme.lower()
    if scheme in ("ws", "wss"):
        _host_port(target, split, port_required=False)
        return RosbridgeTransmitter(text)
    if scheme == "serial":
        if split.netloc:
            raise _bad_target(
                target, "the device path must be absolute: serial:///dev/ttyUSB0 (three slashes)"
            )
        if not split.path or split.path == "/":
            raise _bad_target(target, "no device path")
        baud = _serial_baud(target, split.query)
        return SerialTransmitter(split.path, baudrate=baud, bitrate_bps=bitrate_bps, name=text)
    if scheme == "tcp":
        _host_port(target, split, port_required=True)
        if split.path not in ("", "/") or split.query:
            raise _bad_target(target, "a tcp target is only host:port")
        url = f"socket://{split.netloc}"
        return SerialTransmitter(url, bitrate_bps=bitrate_bps, name=text)
    if scheme == "loop":
        if split.netloc or split.path or split.query:
            raise _bad_target(target, "loop:// takes nothing after it")
        return SerialTransmitter("loop://", bitrate_bps=bitrate_bps)
    raise _bad_target(target, f"unknown scheme {split.scheme + '://'!r}")
