"""The transmitter interface: :class:`SendResult`, :class:`Transmitter`, failure reasons.

Everything the transports share (:mod:`station.transmit_serial`,
:mod:`station.transmit_rosbridge`); import it from :mod:`station.transmit`.
"""

from __future__ import annotations

import abc
import asyncio
import errno
import logging
import socket
import time
from dataclasses import asdict, dataclass
from types import TracebackType
from typing import Any, ClassVar, Literal, Self

import serial
from websockets.exceptions import (
    ConnectionClosed,
    InvalidHandshake,
    InvalidStatus,
    InvalidURI,
)

from codec import Frame

#: The one logger of the transmit modules, named for the public module (as before the split).
logger = logging.getLogger("station.transmit")
logger.addHandler(logging.NullHandler())  # a library: the application configures output

#: How long ``send`` waits for an acknowledgement by default (s).
DEFAULT_ACK_TIMEOUT_S = 5.0

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
    #: How ``ack`` was matched to the frame (see :mod:`station.transmit_acks`).
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


@dataclass(frozen=True, slots=True)
class LinkCheck:
    """A test of one path to the vehicle that sends nothing: could a frame leave now?

    ``what`` names the path ("modem", "rosbridge", "telemetry"); on failure ``reason`` is a
    short phrase as :attr:`SendResult.reason`, and ``detail`` the longer story either way.
    """

    what: str
    target: str
    ok: bool
    reason: str | None = None
    detail: str = ""


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


class ModemTransmitter(Transmitter):
    """An ME modem (a serial port, a TCP gateway): frames out, nothing back, so what it can
    say is what the OS took. The connection is kept between frames; :meth:`check` opens it
    when it is not open and tells whether a frame could leave now, without sending one."""

    #: Seconds kept between the end of one frame and the next (set by each modem).
    gap_s: float
    #: Frames the transport took since this transmitter was made.
    frames_sent: int
    #: The monotonic time (s) before which the next frame waits.
    _next_t: float

    @property
    @abc.abstractmethod
    def connected(self) -> bool:
        """The port or connection is open (a failed write or check closes it)."""

    @abc.abstractmethod
    def check(self) -> LinkCheck:
        """Open the port or connection if it is not open and check that a frame could be
        written now (the peer is still there, nothing of an earlier frame is stuck); nothing
        is written. Kept open when it passes, closed when it does not. Blocking,
        thread-safe, never raises for a transport problem."""

    async def check_async(self) -> LinkCheck:
        """:meth:`check` without blocking the event loop."""
        return await asyncio.to_thread(self.check)

    def _passed(self, detail: str) -> LinkCheck:
        return LinkCheck("modem", self.target, True, None, detail)

    def _copy_sent(self, frame: Frame, detail: str) -> SendResult:
        """A copy the transport took (``detail``: how far it went), counted and logged: the
        one place a modem's copy becomes sent. Called with the transmitter's lock held."""
        sent_t = time.time()
        self._next_t = time.monotonic() + self.gap_s
        self.frames_sent += 1
        logger.info("wrote frame %s to %s", frame.hex, self.target)
        return SendResult(
            ok=True, transport=self.transport, target=self.target, sent_t=sent_t, detail=detail
        )

    def _check_failed(self, reason: str, detail: str) -> LinkCheck:
        logger.info("%s %s: check failed: %s (%s)", self.transport, self.target, reason, detail)
        return LinkCheck("modem", self.target, False, reason, detail)


# --- failure reasons ----------------------------------------------------------------------

_ERRNO_REASONS = {
    errno.ENOENT: "port not found",
    errno.ENODEV: "port not found",
    errno.ENXIO: "port not found",
    errno.EACCES: "permission denied",
    errno.EPERM: "permission denied",
    errno.EBUSY: "port busy",
    errno.ENOTTY: "not a serial port",
    errno.EIO: "i/o error",
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


def frame_msg(frame: Frame) -> dict[str, Any]:
    """The ``std_msgs/UInt8MultiArray`` a station publishes for ``frame``: its 13 bytes as
    ``{"data": [13 ints]}`` (no layout, as roslibpy users write it)."""
    return {"data": list(frame.to_bytes())}
