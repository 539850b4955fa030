"""Loopback TCP gateways that misbehave as real ones do, for the honest modem's tests.

:class:`Gateway` listens on 127.0.0.1 and does with every connection what its ``behaviour``
says:

* ``"read"``: reads everything (a working gateway);
* ``"close"``: reads one frame (13 bytes) and closes the connection; ``"half_close"``: reads
  one frame, shuts its sending side (FIN) and reads nothing more (a half-closed socket still
  takes bytes into its buffer). Either way it keeps listening unless ``one_connection``;
* ``"never_read"``: accepts and never reads, with the smallest receive buffer
  (``SO_RCVBUF`` on the listening socket, so the window it advertises is small from the
  start): the buffer fills, then the station's bytes stop being acknowledged.

:meth:`Gateway.stop` makes it go away (listener and connections closed) and
:meth:`Gateway.restart` brings it back on the same port. ``received`` counts the bytes that
reached the gateway (read by it, or for ``never_read`` waiting in its buffer), per connection;
``on_frame`` is called with every whole frame read (13 bytes, or ``frame_bytes``: 14 for
addressed frames; a modem passing it on). Waits are
on conditions (:meth:`wait_for`), never fixed sleeps.
"""

from __future__ import annotations

import array
import fcntl
import socket
import termios
import threading
from collections.abc import Callable
from typing import Final, Literal

from codec import FRAME_BYTES

LOOPBACK: Final = "127.0.0.1"
Behaviour = Literal["read", "close", "half_close", "never_read"]
_POLL_S: Final = 0.05


class Gateway:
    """A TCP gateway double on 127.0.0.1 (see the module docstring). Close it when done."""

    def __init__(
        self,
        behaviour: Behaviour = "read",
        *,
        one_connection: bool = False,
        on_frame: Callable[[bytes], None] | None = None,
        frame_bytes: int = FRAME_BYTES,
    ) -> None:
        self.behaviour = behaviour
        #: Bytes of a frame on this gateway's wire: 13, or 14 for a fleet's addressed frames.
        self.frame_bytes = frame_bytes
        self.one_connection = one_connection
        self.on_frame = on_frame
        self._cond = threading.Condition()
        #: Bytes that reached the gateway, per connection (index: order of acceptance).
        self.received: list[int] = []
        #: Connections the gateway closed (or half-closed) itself, and that the station closed.
        self.closed_by_gateway = 0
        self.closed_by_station = 0
        self._conns: list[socket.socket] = []
        self._threads: list[threading.Thread] = []
        self._stop = threading.Event()
        self.port = 0
        self._listener = self._listen()

    @property
    def target(self) -> str:
        return f"tcp://{LOOPBACK}:{self.port}"

    @property
    def connections(self) -> int:
        with self._cond:
            return len(self.received)

    def total(self) -> int:
        """Every byte that reached the gateway (for ``never_read``: waiting in its buffers)."""
        with self._cond:
            conns = list(self._conns)
            counted = sum(self.received)
        if self.behaviour != "never_read":
            return counted
        waiting = 0
        for conn in conns:
            count = array.array("i", [0])
            try:
                fcntl.ioctl(conn.fileno(), termios.FIONREAD, count)
            except OSError:
                continue
            waiting += count[0]
        return waiting

    def frames(self) -> int:
        """Whole frames that reached the gateway."""
        return self.total() // self.frame_bytes

    def wait_for(self, what: str, check: Callable[[], bool], timeout_s: float = 10.0) -> None:
        with self._cond:
            if not self._cond.wait_for(check, timeout_s):
                raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")

    # --- going away and coming back ---------------------------------------------------------

    def _listen(self) -> socket.socket:
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        if self.behaviour == "never_read":
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1)  # the kernel's least
        sock.bind((LOOPBACK, self.port))
        sock.listen()
        sock.settimeout(_POLL_S)
        self.port = sock.getsockname()[1]
        self._stop.clear()
        thread = threading.Thread(target=self._accept, args=(sock,), daemon=True)
        self._threads.append(thread)
        thread.start()
        return sock

    def stop(self) -> None:
        """Go away: stop listening and close every connection (the station sees its end of
        file, then connection refused)."""
        self._stop.set()
        self._listener.close()
        for thread in self._threads:  # none accepts or reads any more
            thread.join(2.0)
        self._threads = []
        with self._cond:
            conns, self._conns = self._conns, []
        for conn in conns:
            conn.close()

    def restart(self) -> None:
        """Come back on the same port."""
        self._listener = self._listen()

    def close(self) -> None:
        self.stop()

    # --- serving ----------------------------------------------------------------------------

    def _accept(self, listener: socket.socket) -> None:
        while not self._stop.is_set():
            try:
                conn, _ = listener.accept()
            except TimeoutError:
                continue
            except OSError:
                return  # stopped
            conn.settimeout(_POLL_S)
            with self._cond:
                index = len(self.received)
                self.received.append(0)
                self._conns.append(conn)
                self._cond.notify_all()
            if self.one_connection:
                listener.close()
            if self.behaviour != "never_read":
                thread = threading.Thread(target=self._serve, args=(conn, index), daemon=True)
                self._threads.append(thread)
                thread.start()
            if self.one_connection:
                return

    def _serve(self, conn: socket.socket, index: int) -> None:
        pending = bytearray()
        size = self.frame_bytes
        # "close" and "half_close" read exactly one frame: never a byte of the next
        limit = size if self.behaviour in ("close", "half_close") else 4096
        while not self._stop.is_set():
            try:
                data = conn.recv(limit - len(pending) if limit == size else limit)
            except TimeoutError:
                continue
            except OSError:
                return
            if not data:
                with self._cond:
                    self.closed_by_station += 1
                    self._cond.notify_all()
                conn.close()
                return
            pending += data
            with self._cond:
                self.received[index] += len(data)
                self._cond.notify_all()
            while len(pending) >= size:
                frame, pending = bytes(pending[:size]), pending[size:]
                if self.on_frame is not None:
                    self.on_frame(frame)
            if limit == size and self.received[index] >= size:
                if self.behaviour == "half_close":
                    conn.shutdown(socket.SHUT_WR)  # FIN; what comes next waits unread
                else:
                    conn.close()
                with self._cond:
                    self.closed_by_gateway += 1
                    self._cond.notify_all()
                return
