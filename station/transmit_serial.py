"""The serial transmitter: a real ME transmitter (modem) on a serial port, and the wire format
it shares with a TCP gateway (:mod:`station.transmit_tcp`). Import it from
:mod:`station.transmit`.

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
"""

from __future__ import annotations

import threading
import time

import serial

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

DEFAULT_BAUDRATE = 115_200
DEFAULT_WRITE_TIMEOUT_S = 2.0


class SerialTransmitter(ModemTransmitter):
    """A real ME transmitter on a serial port (see the wire format in the module docstring).
    ``url`` is anything :func:`serial.serial_for_url` opens. The port is
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
    def connected(self) -> bool:
        return self._port is not None

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
            return self._copy_sent(
                frame, f"wrote {FRAME_BYTES} bytes; the modem gives no acknowledgement"
            )

    def check(self) -> LinkCheck:
        """Open the port if it is not open and ask it how many bytes wait to go out (a device
        that went away, e.g. a USB adapter pulled out, fails here). Nothing is written. A serial
        port cannot tell whether a modem is at the other end (no flow control, no carrier)."""
        with self._lock:
            try:
                port = self._ensure_open()
                # pyserial's ports have it (TIOCOUTQ on a tty), its base class does not
                waiting = getattr(port, "out_waiting", None)
            except (serial.SerialException, OSError, ValueError) as exc:
                self._close_port()
                return self._check_failed(failure_reason(exc), _message(exc))
        queue = "" if waiting is None else f"; {waiting} bytes waiting to go out"
        return self._passed(f"{self.url} is open{queue}")

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
