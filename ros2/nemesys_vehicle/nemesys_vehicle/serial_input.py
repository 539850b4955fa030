"""The serial ME receiver: non-blocking reads of its raw byte stream.

The node polls :meth:`SerialByteSource.read_available` on a timer (``serial_poll_hz``) and hands
the bytes to :meth:`nemesys_vehicle.core.VehicleCore.on_serial_bytes`: everything runs in the
node's executor thread, so the core needs no locks. The port is anything
:func:`serial.serial_for_url` opens (a UART, a pty, ``socket://host:port`` for a TCP gateway),
opened on the first read, as the station's :class:`station.transmit.SerialTransmitter` does;
after an error it is closed and opened again ``reopen_after_s`` later.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable

import serial

#: Most bytes taken per poll (an ME link carries about 100 bit/s: a poll never comes close).
MAX_READ_BYTES = 4096


def _no_log(_: str) -> None:
    return None


class SerialByteSource:
    """A serial port read without blocking. Not thread-safe (one poller)."""

    def __init__(
        self,
        url: str,
        baudrate: int = 115_200,
        *,
        reopen_after_s: float = 1.0,
        log: Callable[[str], None] = _no_log,
        info: Callable[[str], None] = _no_log,
    ) -> None:
        """``log``: where errors are reported; ``info``: where the port's opening is."""
        self.url = url
        self.baudrate = baudrate
        self.reopen_after_s = reopen_after_s
        self.log = log
        self.info = info
        self.bytes_read = 0
        self.errors = 0
        self._port: serial.SerialBase | None = None
        self._retry_at = 0.0  # time.monotonic() before which no reopen is tried

    @property
    def is_open(self) -> bool:
        return self._port is not None

    def open(self) -> None:
        """Open the port now. Raises ``serial.SerialException`` (or ``OSError``,
        ``ValueError`` for a bad URL)."""
        if self._port is None:
            # timeout=0: read() returns what is there at once
            self._port = serial.serial_for_url(self.url, baudrate=self.baudrate, timeout=0)
            self.info(f"opened {self.url} at {self.baudrate} baud")

    def read_available(self, max_bytes: int = MAX_READ_BYTES) -> bytes:
        """The bytes received since the last call (``b""`` when none, or while the port is
        down: errors are logged and the port is reopened later)."""
        if self._port is None:
            if time.monotonic() < self._retry_at:
                return b""
            try:
                self.open()
            except (serial.SerialException, OSError, ValueError) as exc:
                self._failed(f"cannot open {self.url}: {exc}")
                return b""
        port = self._port
        assert port is not None
        try:
            data = bytes(port.read(max_bytes))
        except (serial.SerialException, OSError) as exc:
            self._failed(f"reading {self.url}: {exc}")
            return b""
        self.bytes_read += len(data)
        return data

    def close(self) -> None:
        port, self._port = self._port, None
        if port is not None:
            with contextlib.suppress(serial.SerialException, OSError):
                port.close()

    def _failed(self, message: str) -> None:
        self.errors += 1
        self.log(f"{message}; retrying in {self.reopen_after_s:g} s")
        self.close()
        self._retry_at = time.monotonic() + self.reopen_after_s
