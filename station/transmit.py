"""Transmitters: hand an encoded frame to the vehicle and report what happened.

One interface, several transports. :meth:`Transmitter.send` takes a :class:`codec.Frame` and
returns a :class:`SendResult`: sent (with the vehicle's acknowledgement when the transport can
get one) or failed with a short reason ("connection refused", "timeout", "port not found", ...).
``send`` never raises for a transport problem.

* :class:`RosbridgeTransmitter`: a rosbridge v2 endpoint (the simulated vehicle, or a real
  vehicle behind a rosbridge). Publishes the frame on ``/nemesys/frame`` and waits for the
  vehicle's acknowledgement on ``/nemesys/mission``.
* :class:`SerialTransmitter`: a real ME transmitter (modem) on a serial port; any URL
  :func:`serial.serial_for_url` opens (``/dev/ttyUSB0``, ``loop://``). The modem gives no
  acknowledgement.
* :class:`TcpTransmitter`: an ME modem behind a TCP gateway; a copy counts only when the
  gateway took its bytes and had not closed (:mod:`station.transmit_tcp`).

The modems (:class:`ModemTransmitter`) can also be checked without sending a frame
(:meth:`ModemTransmitter.check`, a :class:`LinkCheck`).

:func:`open_transmitter` picks one from a target string (``ws://``, ``wss://``,
``serial:///dev/...``, ``tcp://host:port``, ``loop://``).

This module is the public face: import everything from here. The code lives in

* :mod:`station.transmit_base`: :class:`SendResult`, the :class:`Transmitter` interface,
  failure reasons;
* :mod:`station.transmit_serial`: :class:`SerialTransmitter` and the serial/TCP wire format;
* :mod:`station.transmit_tcp`: :class:`TcpTransmitter`, what counts as sent on a TCP gateway;
* :mod:`station.transmit_rosbridge`: :class:`RosbridgeTransmitter` and its wait for the
  vehicle's subscriber;
* :mod:`station.transmit_acks`: what comes back over rosbridge, and how an acknowledgement is
  matched to the sent frame (:func:`ack_match`).

All of them log to the ``station.transmit`` logger. See ``docs/transmitters.md``.
"""

from __future__ import annotations

from urllib.parse import SplitResult, parse_qs, urlsplit

from codec import DEFAULT_BITRATE_BPS
from station.transmit_acks import ACK_SETTLE_S, ack_match
from station.transmit_base import (
    DEFAULT_ACK_TIMEOUT_S,
    AckMatch,
    LinkCheck,
    ModemTransmitter,
    SendResult,
    Transmitter,
    failure_reason,
    frame_msg,
)
from station.transmit_rosbridge import (
    DEFAULT_OPEN_TIMEOUT_S,
    DEFAULT_ROSBRIDGE_URL,
    RosbridgeTransmitter,
)
from station.transmit_serial import (
    DEFAULT_BAUDRATE,
    DEFAULT_WRITE_TIMEOUT_S,
    SerialTransmitter,
)
from station.transmit_tcp import DEFAULT_DRAIN_TIMEOUT_S, TcpTransmitter

__all__ = [
    "ACK_SETTLE_S",
    "DEFAULT_ACK_TIMEOUT_S",
    "DEFAULT_BAUDRATE",
    "DEFAULT_DRAIN_TIMEOUT_S",
    "DEFAULT_OPEN_TIMEOUT_S",
    "DEFAULT_ROSBRIDGE_URL",
    "DEFAULT_WRITE_TIMEOUT_S",
    "TARGET_FORMS",
    "AckMatch",
    "LinkCheck",
    "ModemTransmitter",
    "RosbridgeTransmitter",
    "SendResult",
    "SerialTransmitter",
    "TcpTransmitter",
    "Transmitter",
    "ack_match",
    "failure_reason",
    "frame_msg",
    "open_transmitter",
]

#: The target forms :func:`open_transmitter` accepts.
TARGET_FORMS = (
    "ws://host:port[/path]",
    "wss://host:port[/path]",
    "serial:///dev/ttyUSB0[?baud=115200]",
    "tcp://host:port",
    "loop://",
)


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
    if not (text.isascii() and text.isdigit()) or int(text) <= 0:
        raise _bad_target(
            target, f"baud must be a positive whole number in ASCII digits, got {text!r}"
        )
    return int(text)


def open_transmitter(
    target: str, *, bitrate_bps: float = DEFAULT_BITRATE_BPS, namespace: str = ""
) -> Transmitter:
    """The transmitter for a target string (see :data:`TARGET_FORMS`). Nothing is opened
    until the first send. ``bitrate_bps`` sets the serial inter-frame gap; ``namespace`` is
    the vehicle's ROS namespace (rosbridge targets only).

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
        return RosbridgeTransmitter(text, namespace=namespace)
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
        assert split.hostname is not None and split.port is not None  # _host_port said so
        return TcpTransmitter(split.hostname, split.port, bitrate_bps=bitrate_bps, name=text)
    if scheme == "loop":
        if split.netloc or split.path or split.query:
            raise _bad_target(target, "loop:// takes nothing after it")
        return SerialTransmitter("loop://", bitrate_bps=bitrate_bps)
    raise _bad_target(target, f"unknown scheme {split.scheme + '://'!r}")
