"""The TCP modem transmitter: an ME modem behind a TCP gateway (``tcp://host:port``), honest
about what left. Import it from :mod:`station.transmit`.

The bytes are the serial wire format (:mod:`station.transmit_serial`): 13 bytes per frame,
one write each, at least one frame's airtime apart, nothing read back.

What counts as sent
-------------------
A copy counts as sent only when the gateway's TCP stack has taken all its bytes and the
gateway had not closed the connection before it:

* **Before each write** the connection is looked at: a pending error, a reset, or the gateway's
  end of file (it closed or half-closed: a gateway that has sent its FIN passes nothing on) closes
  it here, and it is opened once more at once: the copy goes out on the new connection, or fails
  with why the gateway could not be reached. Bytes the gateway sent are read and dropped (a
  modem sends nothing back).
* **After the write** the transmitter waits up to ``drain_timeout_s`` for the send queue to
  empty (``SIOCOUTQ`` on Linux: bytes written and not yet acknowledged by the gateway). A gateway
  that has stopped reading stops acknowledging once its receive buffer is full: the copy fails
  ("gateway not reading") and the connection is reset (``SO_LINGER`` 0), so the bytes still
  queued are discarded here, never delivered later behind the count's back. A reset seen while
  waiting (the gateway closed as the frame arrived) fails the copy too.

What TCP cannot tell (measured on Linux loopback)
-------------------------------------------------
Acknowledged bytes are in the gateway's kernel, not necessarily read by the gateway program. A
gateway that stops reading shows only once its receive buffer is full: 88 frames with the
smallest receive buffer (``SO_RCVBUF`` 2304 bytes: 1144 bytes of 13-byte segments), thousands
with the default; its advertised window does not show 13 bytes (window scaling: 1 KiB steps by
default), and the reset leaves what it had acknowledged readable there. A gateway whose FIN
crosses a frame on its way has acknowledged that frame (a half-closed socket still receives) and
it counts as sent; a gateway that closed completely answers it with a reset, which the wait
sees. Without ``SIOCOUTQ`` (not Linux) a copy counts when the OS took its bytes.

The connection has keep-alive on (5 s idle, 3 probes 2 s apart) so a gateway that vanished
without a word is found by :meth:`TcpTransmitter.check` within about 11 s though nothing is sent.
"""

from __future__ import annotations

import array
import os
import select
import socket
import struct
import sys
import threading
import time
from typing import Final

from codec import DEFAULT_BITRATE_BPS, FRAME_BYTES, Frame, airtime_s
from station.transmit_base import (
    DEFAULT_ACK_TIMEOUT_S,
    LinkCheck,
    ModemTransmitter,
    SendResult,
    _message,
    failure_reason,
    logger,
)

__all__ = [
    "DEFAULT_DRAIN_TIMEOUT_S",
    "DEFAULT_OPEN_TIMEOUT_S",
    "TcpTransmitter",
    "unacknowledged_bytes",
]

DEFAULT_OPEN_TIMEOUT_S: Final = 3.0
#: How long a frame's bytes may wait for the gateway's acknowledgement (s).
DEFAULT_DRAIN_TIMEOUT_S: Final = 2.0
#: The send buffer asked for (bytes; Linux doubles it and keeps at least 4608): small, so a
#: gateway that stops reading is not hidden behind a deep local queue where SIOCOUTQ is missing.
SEND_BUFFER_BYTES: Final = 2048
#: Keep-alive: idle time before the first probe, time between probes (s), probes unanswered.
KEEPALIVE: Final = (5, 2, 3)

_LINUX: Final = sys.platform.startswith("linux")
#: ``SIOCOUTQ`` (= ``TIOCOUTQ`` on Linux): a TCP socket's bytes not yet acknowledged.
_SIOCOUTQ: Final = 0x5411
#: ``tcp_info.tcpi_state`` values (include/net/tcp_states.h).
_TCP_ESTABLISHED: Final = 1
_TCP_CLOSE: Final = 7


class _Gone(Exception):
    """The gateway is not there: ``reason`` as a :class:`SendResult` gives it, and the story."""

    def __init__(self, reason: str, detail: str) -> None:
        super().__init__(detail)
        self.reason = reason
        self.detail = detail


def unacknowledged_bytes(sock: socket.socket) -> int | None:
    """Bytes written to ``sock`` that its peer has not acknowledged (None: cannot tell here)."""
    if not _LINUX:
        return None
    import fcntl

    count = array.array("i", [0])
    fcntl.ioctl(sock.fileno(), _SIOCOUTQ, count)
    return int(count[0])


def _tcp_state(sock: socket.socket) -> int | None:
    if not _LINUX:
        return None
    return sock.getsockopt(socket.IPPROTO_TCP, socket.TCP_INFO, 8)[0]


def _pending_error(sock: socket.socket) -> _Gone | None:
    code = sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
    if not code:
        return None
    error = OSError(code, os.strerror(code))
    return _Gone(failure_reason(error), f"the connection failed: {os.strerror(code)}")


def _peer_gone(sock: socket.socket) -> _Gone | None:
    """Why the gateway at the other end of ``sock`` is gone, or None if it is there: a pending
    error, a reset, or its end of file. What it sent is read and dropped."""
    problem = _pending_error(sock)
    if problem is not None:
        return problem
    dropped = 0
    while True:
        try:
            data = sock.recv(4096, socket.MSG_DONTWAIT)
        except (BlockingIOError, InterruptedError):
            break  # nothing more to read: the gateway is there
        except OSError as exc:
            return _Gone(failure_reason(exc), f"the connection failed: {_message(exc)}")
        if not data:
            return _Gone(
                "connection closed",
                "the gateway closed the connection (end of file): it passes nothing on",
            )
        dropped += len(data)
    if dropped:
        logger.warning("the gateway sent %d bytes (a modem sends nothing back): dropped", dropped)
    return None


class TcpTransmitter(ModemTransmitter):
    """An ME modem behind a TCP gateway (see the module docstring for what counts as sent).
    The connection is opened on the first send or :meth:`check` and kept; one found closed by
    the gateway is opened again once, at once. Thread-safe."""

    transport = "tcp"

    def __init__(
        self,
        host: str,
        port: int,
        *,
        bitrate_bps: float = DEFAULT_BITRATE_BPS,
        open_timeout_s: float = DEFAULT_OPEN_TIMEOUT_S,
        drain_timeout_s: float = DEFAULT_DRAIN_TIMEOUT_S,
        name: str | None = None,
    ) -> None:
        super().__init__(name or f"tcp://{host}:{port}")
        self.host = host
        self.port = port
        self.open_timeout_s = open_timeout_s
        self.drain_timeout_s = drain_timeout_s
        #: The least time between the end of one frame's write and the start of the next.
        self.gap_s = airtime_s(bitrate_bps)
        self.frames_sent = 0
        #: Connections opened (a test reads it; the log says why each was closed).
        self.connections = 0
        self._sock: socket.socket | None = None
        self._next_t = 0.0  # time.monotonic() before which the next frame must not start
        self._lock = threading.Lock()

    @property
    def connected(self) -> bool:
        return self._sock is not None

    # --- the connection -----------------------------------------------------------------

    def _connect(self) -> socket.socket:
        try:
            sock = socket.create_connection((self.host, self.port), timeout=self.open_timeout_s)
        except OSError as exc:
            where = f"{self.host}:{self.port}"
            raise _Gone(failure_reason(exc), f"connecting to {where}: {_message(exc)}") from None
        sock.settimeout(None)  # every operation below says MSG_DONTWAIT or polls itself
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SEND_BUFFER_BYTES)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE, 1)
        if _LINUX:
            idle, interval, count = KEEPALIVE
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPIDLE, idle)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPINTVL, interval)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPCNT, count)
        self._sock = sock
        self.connections += 1
        logger.info("connected to the gateway at %s", self.target)
        return sock

    def _usable(self) -> socket.socket:
        """The open connection with the gateway still there, or a new one (raises _Gone)."""
        sock = self._sock
        if sock is not None:
            gone = _peer_gone(sock)
            if gone is None:
                return sock
            logger.info("%s: %s; connecting again", self.target, gone.detail)
            self._close_sock()
            try:
                return self._connect()
            except _Gone as again:
                raise _Gone(again.reason, f"{gone.detail}; {again.detail}") from None
        return self._connect()

    def _drain(self, sock: socket.socket, written: int = 0) -> _Gone | None:
        """Wait until the gateway has acknowledged every byte written (module docstring);
        ``written``: the frame's bytes just written, to say how much of it the gateway took."""
        deadline = time.monotonic() + self.drain_timeout_s
        pause_s = 0.0005
        while True:
            queued = unacknowledged_bytes(sock)
            if queued is None:
                return None  # cannot tell here: the OS took the bytes
            problem = _pending_error(sock)
            if problem is None and _tcp_state(sock) == _TCP_CLOSE:
                problem = _Gone("connection reset", "the gateway reset the connection")
            if problem is not None:
                problem.detail += " while the frame was on its way"
                return problem
            if queued == 0:
                return None
            remaining_s = deadline - time.monotonic()
            if remaining_s <= 0:
                took = written - queued
                partial = f" (it took {took} of the frame's {written}: a partial frame)"
                return _Gone(
                    "gateway not reading",
                    f"{queued} bytes not acknowledged by the gateway within "
                    f"{self.drain_timeout_s:g} s: it has stopped reading (its buffer is full)"
                    + (partial if 0 < took < written else ""),
                )
            time.sleep(min(pause_s, remaining_s))
            pause_s = min(2 * pause_s, 0.02)

    def _close_sock(self, *, reset: bool = False) -> None:
        """Close the connection; ``reset``: discard what is still queued (RST, not FIN)."""
        sock, self._sock = self._sock, None
        if sock is None:
            return
        try:
            if reset:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
            sock.close()
        except OSError as exc:
            logger.debug("closing %s: %s", self.target, exc)

    # --- the transmitter ------------------------------------------------------------------

    def send(self, frame: Frame, *, wait_ack_s: float = DEFAULT_ACK_TIMEOUT_S) -> SendResult:
        """Write the frame's 13 bytes (``wait_ack_s`` is ignored: the modem acknowledges
        nothing); ``ok`` only when the gateway took them (module docstring)."""
        data = frame.to_bytes()
        with self._lock:
            try:
                sock = self._usable()
            except _Gone as gone:
                return self._failed(gone.reason, gone.detail)
            delay_s = self._next_t - time.monotonic()
            if delay_s > 0:
                time.sleep(delay_s)
            try:
                written = sock.send(data, socket.MSG_DONTWAIT)
            except BlockingIOError:
                written = 0
            except OSError as exc:
                self._close_sock(reset=True)
                detail = f"writing to {self.target}: {_message(exc)}"
                return self._failed(failure_reason(exc), detail)
            if written != len(data):
                self._close_sock(reset=True)
                return self._failed(
                    "gateway not reading",
                    f"the send buffer took {written} of {len(data)} bytes: the gateway has "
                    "stopped reading",
                )
            problem = self._drain(sock, len(data))
            if problem is not None:
                self._close_sock(reset=True)
                return self._failed(problem.reason, problem.detail)
            return self._copy_sent(
                frame, f"the gateway took {FRAME_BYTES} bytes; the modem gives no acknowledgement"
            )

    def check(self) -> LinkCheck:
        """Connect if not connected; pass when the gateway is there, nothing of an earlier
        frame waits for it, and the connection is writable. Nothing is written."""
        with self._lock:
            try:
                sock = self._usable()
            except _Gone as gone:
                return self._check_failed(gone.reason, gone.detail)
            problem = self._drain(sock)
            if problem is not None:
                self._close_sock(reset=True)
                return self._check_failed(problem.reason, problem.detail)
            state = _tcp_state(sock)
            if state is not None and state != _TCP_ESTABLISHED:
                self._close_sock(reset=True)
                return self._check_failed("connection closed", f"TCP state {state}")
            _, writable, _ = select.select([], [sock], [], 0)
            if not writable:
                self._close_sock(reset=True)
                return self._check_failed(
                    "gateway not reading", "the connection is not writable: its buffer is full"
                )
        return self._passed(f"connected to the gateway at {self.host}:{self.port}; writable")

    def close(self) -> None:
        with self._lock:
            self._close_sock()
