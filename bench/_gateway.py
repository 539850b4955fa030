"""A loopback stand-in for an ME modem's TCP gateway, for the recovery benchmark and the tests.

:class:`FrameGateway` listens on 127.0.0.1, accepts every connection (a console reconnects
after a failure or a restart) and decodes what each sends with :class:`codec.FrameReceiver`,
as the vehicle would: the 13-byte frames of ``docs/transmitters.md``. It keeps the wire trace
(:class:`WireFrame`, in arrival order, with the connection each came on) and counts what it
could not decode.
"""

from __future__ import annotations

import socket
import threading
import time
from dataclasses import dataclass
from typing import Any, Final

from codec import FRAME_BITS, Accepted, FrameReceiver

LOOPBACK: Final = "127.0.0.1"
_FRAME_MASK: Final = (1 << FRAME_BITS) - 1
_POLL_S: Final = 0.05


@dataclass(frozen=True)
class WireFrame:
    """One frame the gateway decoded: when it arrived (``time.monotonic()``), on which
    connection (0 = the first), what it says, and the hex of the 100 bits as received."""

    t: float
    connection: int
    pattern: str
    params: dict[str, Any]
    hex: str


class FrameGateway:
    """A TCP listener on 127.0.0.1 that decodes every frame it is sent. Close it when done."""

    def __init__(self) -> None:
        self._sock = socket.create_server((LOOPBACK, 0))
        self._sock.settimeout(_POLL_S)
        self.port: int = self._sock.getsockname()[1]
        self._lock = threading.Lock()
        self._frames: list[WireFrame] = []
        #: Why each undecodable frame was rejected (the receiver's reasons).
        self.rejected: list[str] = []
        #: Connections accepted, and of those, closed by the console.
        self.connections = 0
        self.closed = 0
        self._stop = threading.Event()
        self._threads = [threading.Thread(target=self._accept, daemon=True)]
        self._threads[0].start()

    @property
    def target(self) -> str:
        """The console's ``--target`` for this gateway."""
        return f"tcp://{LOOPBACK}:{self.port}"

    def _accept(self) -> None:
        while not self._stop.is_set():
            try:
                conn, _ = self._sock.accept()
            except TimeoutError:
                continue
            except OSError:
                return  # closed
            with self._lock:
                index = self.connections
                self.connections += 1
            thread = threading.Thread(target=self._serve, args=(conn, index), daemon=True)
            self._threads.append(thread)
            thread.start()

    def _serve(self, conn: socket.socket, index: int) -> None:
        receiver = FrameReceiver()
        stream = bytearray()  # all this connection sent, to read each frame's bits as received
        conn.settimeout(_POLL_S)
        with conn:
            while not self._stop.is_set():
                try:
                    data = conn.recv(4096)
                except TimeoutError:
                    continue
                except OSError:
                    break
                if not data:
                    break
                arrived = time.monotonic()
                stream += data
                for event in receiver.feed_bytes(data):
                    with self._lock:
                        if not isinstance(event, Accepted):
                            self.rejected.append(str(event.error))
                            continue
                        total = 8 * len(stream)
                        value = int.from_bytes(stream, "big")
                        bits = (value >> (total - event.offset - FRAME_BITS)) & _FRAME_MASK
                        cmd = event.decoded.command
                        self._frames.append(
                            WireFrame(
                                arrived, index, cmd.pattern.name, dict(cmd.params), f"{bits:025x}"
                            )
                        )
        with self._lock:
            self.closed += 1

    def trace(self) -> list[WireFrame]:
        """Every frame decoded so far, in arrival order."""
        with self._lock:
            return list(self._frames)

    def count(self, hex_: str | None = None) -> int:
        """Frames decoded so far (of one frame, by its hex)."""
        return sum(hex_ is None or f.hex == hex_ for f in self.trace())

    def frames(self, connection: int) -> list[str]:
        """The hex of every frame decoded on one connection, in order."""
        return [f.hex for f in self.trace() if f.connection == connection]

    def close(self) -> None:
        self._stop.set()
        self._sock.close()
        for thread in self._threads:
            thread.join(2)
