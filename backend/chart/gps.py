"""The optional surface GPS (NMEA 0183) and the station: where the ME transmitter is.

The ``gps`` setting names the source: ``udp://127.0.0.1:10110`` (NMEA datagrams, as chart
plotters and ``gpsd``'s ``gpspipe``/OpenCPN forward them; bound to the address given, loopback
by default) or ``serial:///dev/ttyUSB1?baud=4800`` (a GPS receiver on a serial port, read by
pyserial in a thread). Sentences are parsed by pynmea2; ``GGA`` and ``RMC`` give fixes, other
sentence types are counted and ignored. A bad sentence (no checksum or a wrong one, garbage,
a position that is not one) and a sentence without a fix are counted, the last problem kept;
nothing raises into the console. The latest fix wins; its age runs from its arrival (the
monotonic clock), not from the sentence's own time stamp (a receiver's clock can be wrong or
absent).

The station (:func:`station_of`): the transmitter's position is the GPS fix, else the
``station_lat_deg``/``station_lon_deg`` settings, else the datum (the NED origin).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal
from urllib.parse import parse_qs, urlsplit

import pynmea2

from backend.chart.geo import Datum, geodetic_to_ned

logger = logging.getLogger("backend.chart.gps")

#: The forms the ``gps`` setting takes.
GPS_FORMS = (
    '"" (no GPS)',
    "udp://HOST:PORT (e.g. udp://127.0.0.1:10110)",
    "serial:///dev/DEVICE?baud=4800",
)
DEFAULT_BAUD = 4800
#: Wait before opening a serial port again after it failed (s).
SERIAL_RETRY_S = 2.0
#: Longest NMEA sentence kept in an error message (characters).
_SHOWN = 82


@dataclass(frozen=True)
class GpsSource:
    """A parsed ``gps`` setting: ``udp`` (host, port) or ``serial`` (device, baud)."""

    kind: Literal["udp", "serial"]
    host: str = ""
    port: int = 0
    device: str = ""
    baud: int = DEFAULT_BAUD

    def __str__(self) -> str:
        if self.kind == "udp":
            return f"udp://{self.host}:{self.port}"
        return f"serial://{self.device}?baud={self.baud}"


def _bad(value: str, problem: str) -> ValueError:
    return ValueError(f"gps {value!r}: {problem}; allowed: {', '.join(GPS_FORMS)}")


def parse_gps(value: str) -> GpsSource | None:
    """The ``gps`` setting: None for ``""``.

    Raises:
        ValueError: naming the problem and the allowed forms.
    """
    text = value.strip()
    if not text:
        return None
    if "://" not in text:
        raise _bad(value, "no scheme")
    split = urlsplit(text)
    scheme = split.scheme.lower()
    if scheme == "udp":
        try:
            port = split.port
        except ValueError:
            raise _bad(value, "the port must be a number from 1 to 65535") from None
        if not split.hostname:
            raise _bad(value, "no host (udp://127.0.0.1:10110 listens on loopback)")
        if not port:
            raise _bad(value, "no port (NMEA over UDP is usually 10110)")
        if split.path not in ("", "/") or split.query:
            raise _bad(value, "a udp source is only host:port")
        return GpsSource("udp", host=split.hostname, port=port)
    if scheme == "serial":
        if split.netloc or not split.path or split.path == "/":
            raise _bad(value, "the device path must be absolute: serial:///dev/ttyUSB1")
        options = parse_qs(split.query, keep_blank_values=True)
        unknown = sorted(set(options) - {"baud"})
        if unknown:
            raise _bad(value, f"unknown option {unknown[0]!r} (only baud=)")
        baud_text = options.get("baud", [str(DEFAULT_BAUD)])[-1]
        if not (baud_text.isascii() and baud_text.isdigit()) or int(baud_text) <= 0:
            raise _bad(
                value, f"baud must be a positive whole number in ASCII digits, got {baud_text!r}"
            )
        return GpsSource("serial", device=split.path, baud=int(baud_text))
    raise _bad(value, f"unknown scheme {scheme!r}")


@dataclass(frozen=True)
class GpsFix:
    """A position fix: WGS84 degrees, GGA's fix quality (1 GPS, 2 DGPS, 4 RTK, ...; None from
    an RMC), the sentence type, and its arrival on the monotonic clock (s)."""

    lat_deg: float
    lon_deg: float
    quality: int | None
    sentence: str
    received_s: float

    def age_s(self) -> float:
        return time.monotonic() - self.received_s


class GpsReader:
    """Reads one NMEA source; :attr:`fix` is the latest fix, ``on_fix`` is called with each."""

    def __init__(self, source: GpsSource, on_fix: Callable[[GpsFix], None] | None = None) -> None:
        self.source = source
        self.on_fix = on_fix
        self.fix: GpsFix | None = None
        self.sentences = 0  # lines received
        self.fixes = 0
        self.no_fix = 0  # GGA quality 0, RMC status V
        self.errors = 0  # checksum, unparsable, not a position
        self.last_error: str | None = None
        self._transport: asyncio.DatagramTransport | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._partial = ""
        #: The serial port is open (the thread reads it); UDP: bound.
        self.open = False

    @property
    def port(self) -> int | None:
        """The UDP port actually bound (when the setting asked for port 0, tests)."""
        if self._transport is None:
            return None
        port: int = self._transport.get_extra_info("sockname")[1]
        return port

    # --- input ---------------------------------------------------------------------------

    def feed(self, data: str) -> None:
        """Text received: complete lines are parsed, a trailing partial one kept."""
        text = self._partial + data
        lines = text.replace("\r", "\n").split("\n")
        self._partial = lines.pop()[-1024:]
        for line in lines:
            if line.strip():
                self.feed_line(line)

    def feed_line(self, line: str) -> None:
        """One NMEA sentence; never raises."""
        self.sentences += 1
        text = line.strip()
        try:
            # checksum required: a line cut short by a noisy port would be a wrong position
            msg = pynmea2.parse(text, check=True)
        except Exception as err:  # ParseError, and whatever an odd sentence raises in it
            self._error(f"{_reason(err)}: {text[:_SHOWN]!r}")
            return
        kind = getattr(msg, "sentence_type", None)  # a query or proprietary one has none
        if kind not in ("GGA", "RMC"):
            return  # GSV, VTG, ...: valid, not a position
        if (kind == "GGA" and not _int(getattr(msg, "gps_qual", None))) or (
            kind == "RMC" and getattr(msg, "status", "") != "A"
        ):
            self.no_fix += 1
            return
        try:
            position = Datum(float(msg.latitude), float(msg.longitude))
        except Exception as err:  # an empty or mangled field: ValueError, TypeError, ...
            self._error(f"no position in {kind}: {err}: {text[:_SHOWN]!r}")
            return
        quality = _int(getattr(msg, "gps_qual", None)) if kind == "GGA" else None
        fix = GpsFix(position.lat_deg, position.lon_deg, quality, kind, time.monotonic())
        self.fix = fix
        self.fixes += 1
        if self.on_fix is not None:
            try:
                self.on_fix(fix)
            except Exception:  # a consumer's fault must not stop the GPS
                logger.exception("GPS fix handler failed")

    def _error(self, text: str) -> None:
        self.errors += 1
        self.last_error = text

    # --- lifecycle -----------------------------------------------------------------------

    async def start(self) -> None:
        """Start listening (UDP) or reading (serial, in a thread).

        Raises:
            OSError: the UDP address cannot be bound (the message names it).
        """
        loop = asyncio.get_running_loop()
        if self.source.kind == "udp":
            reader = self

            class _Protocol(asyncio.DatagramProtocol):
                def datagram_received(self, data: bytes, addr: object) -> None:
                    reader.feed(data.decode("ascii", "replace") + "\n")

            try:
                transport, _ = await loop.create_datagram_endpoint(
                    _Protocol, local_addr=(self.source.host, self.source.port)
                )
            except OSError as err:
                raise OSError(f"gps {self.source}: cannot listen: {err}") from err
            self._transport = transport
            self.open = True
        else:
            self._thread = threading.Thread(
                target=self._read_serial, args=(loop,), name="gps serial", daemon=True
            )
            self._thread.start()

    async def stop(self) -> None:
        if self._transport is not None:
            self._transport.close()
            self._transport = None
        self.open = False
        self._stop.set()
        if self._thread is not None:
            await asyncio.to_thread(self._thread.join, 5.0)
            self._thread = None

    def _read_serial(self, loop: asyncio.AbstractEventLoop) -> None:
        import serial

        while not self._stop.is_set():
            try:
                with serial.Serial(self.source.device, self.source.baud, timeout=0.5) as port:
                    self.open = True  # pyserial flushed the input on opening
                    while not self._stop.is_set():
                        raw = port.readline()
                        if raw:
                            text = raw.decode("ascii", "replace")
                            with contextlib.suppress(RuntimeError):  # the loop closed
                                loop.call_soon_threadsafe(self.feed, text)
            except (OSError, serial.SerialException) as err:
                self.open = False
                text = f"gps {self.source}: {err}"
                with contextlib.suppress(RuntimeError):
                    loop.call_soon_threadsafe(self._error, text)
                self._stop.wait(SERIAL_RETRY_S)

    def doc(self) -> dict[str, object]:
        """What the chart shows of the GPS."""
        fix = self.fix
        return {
            "configured": True,
            "source": str(self.source)
            if self.port is None
            else f"udp://{self.source.host}:{self.port}",
            "fix": fix is not None,
            "quality": None if fix is None else fix.quality,
            "sentences": self.sentences,
            "no_fix": self.no_fix,
            "errors": self.errors,
            "last_error": self.last_error,
            "age_s": None if fix is None else fix.age_s(),
        }


def _reason(err: Exception) -> str:
    if isinstance(err, pynmea2.ChecksumError):
        missing = err.args and "missing" in str(err.args[0])
        return "no checksum" if missing else "bad checksum"
    if isinstance(err, pynmea2.ParseError):
        return str(err.args[0]) if err.args else "unparsable"
    return f"unparsable ({type(err).__name__}: {err})"


def _int(value: object) -> int | None:
    if isinstance(value, int):
        return value
    if isinstance(value, str) and value.isascii() and value.strip().isdigit():
        return int(value)
    return None


# --- the station ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Station:
    """The ME transmitter: lat/lon (deg; None when neither the GPS, the settings nor a datum
    say), NED position (m from the datum; None when only lat/lon is known and there is no
    datum), where it came from, and the GPS fix's age (s)."""

    lat_deg: float | None
    lon_deg: float | None
    x_m: float | None
    y_m: float | None
    source: Literal["gps", "settings", "datum"]
    age_s: float | None = None

    def as_dict(self) -> dict[str, object]:
        return {
            "lat_deg": self.lat_deg,
            "lon_deg": self.lon_deg,
            "x_m": self.x_m,
            "y_m": self.y_m,
            "source": self.source,
            "age_s": self.age_s,
        }


def station_of(
    datum: Datum | None,
    fix: GpsFix | None,
    lat_deg: float | None = None,
    lon_deg: float | None = None,
) -> Station:
    """The transmitter's position: the GPS ``fix``, else the settings' ``lat_deg``/``lon_deg``,
    else the datum (the NED origin, also when its lat/lon is unknown)."""
    source: Literal["gps", "settings"]
    if fix is not None:
        lat, lon, source, age = fix.lat_deg, fix.lon_deg, "gps", fix.age_s()
    elif lat_deg is not None and lon_deg is not None:
        lat, lon, source, age = lat_deg, lon_deg, "settings", None
    elif datum is None:
        return Station(None, None, 0.0, 0.0, "datum")
    else:
        return Station(datum.lat_deg, datum.lon_deg, 0.0, 0.0, "datum")
    if datum is None:
        return Station(lat, lon, None, None, source, age)
    x, y = geodetic_to_ned(datum, lat, lon)
    return Station(lat, lon, x, y, source, age)
