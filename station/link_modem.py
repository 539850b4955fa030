"""The console's links through an ME modem, and :func:`open_link` (the link for the settings).

* :class:`ModemLink`: an ME modem on a serial port or behind a TCP gateway
  (:class:`station.transmit.ModemTransmitter`): frames out, nothing back. A background watch
  keeps the modem open and checked (:meth:`ModemTransmitter.check`: no frame is sent), so the
  link's health follows the modem: a gateway that went away and came back is seen without a
  command, and :meth:`ModemLink.test` checks it on demand.
* :class:`HybridLink`: frames over the modem, telemetry and the vehicle's acknowledgements over
  a rosbridge (a vehicle whose frames come by its own ME receiver, the reference node's
  ``frame_input: serial``). Its capability is the rosbridge's while that is connected: a
  command ends ``acknowledged`` by the acknowledgement that comes back over rosbridge; with the
  rosbridge down the link is one-way (copies, ``sent``) and says why.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from typing import Any, Final, NoReturn
from urllib.parse import urlsplit

from codec import Frame
from station.link import Capability, Link, RosbridgeLink
from station.transmit import LinkCheck, ModemTransmitter, open_transmitter

logger = logging.getLogger("station.link")

#: While the modem passes its checks, how often it is checked again (s).
PROBE_S: Final = 1.0
#: After a failed check the next comes this soon, doubling up to MAX_BACKOFF_S (s).
BACKOFF_S: Final = 0.2
MAX_BACKOFF_S: Final = 5.0
#: How long :meth:`ModemLink.start` waits for the first check (s).
FIRST_CHECK_S: Final = 1.0
#: The forms ``telemetry`` (``NEMESYS_TELEMETRY``) takes.
TELEMETRY_FORMS: Final = ("ws://host:port[/path]", "wss://host:port[/path]")

ONE_WAY = (
    "an ME modem link is one-way: commands go out as repeated copies, with no acknowledgement "
    "and no telemetry"
)


def parse_telemetry(url: str) -> str:
    """``url`` checked as a rosbridge to take telemetry and acknowledgements from.

    Raises:
        ValueError: the problem, and the forms allowed.
    """

    def bad(problem: str) -> NoReturn:
        raise ValueError(
            f"bad telemetry url {url!r}: {problem}; expected one of {', '.join(TELEMETRY_FORMS)}"
        )

    text = url.strip()
    if "://" not in text:
        bad("no scheme")
    try:
        split = urlsplit(text)
        port = split.port
    except ValueError:
        bad("the port must be a number from 1 to 65535")
    if split.scheme.lower() not in ("ws", "wss"):
        bad(f"the scheme must be ws:// or wss://, not {split.scheme + '://'!r}")
    if not split.hostname:
        bad("no host")
    if port == 0:
        bad("the port must be a number from 1 to 65535")
    return text


class ModemLink(Link):
    """An ME modem on a serial port or TCP gateway: one-way, no acknowledgements.

    ``connected`` is what the last check or frame found. The watch (from :meth:`start`) checks
    the modem at once, then every ``probe_s`` while it passes, else again after a back-off
    (``backoff_s`` doubling to ``max_backoff_s``); a frame that did not leave wakes it at once,
    and is named among the problems until one leaves.
    """

    def __init__(
        self,
        target: str,
        bitrate_bps: float,
        *,
        probe_s: float = PROBE_S,
        backoff_s: float = BACKOFF_S,
        max_backoff_s: float = MAX_BACKOFF_S,
    ) -> None:
        super().__init__(target)
        tx = open_transmitter(target, bitrate_bps=bitrate_bps)
        if not isinstance(tx, ModemTransmitter):
            raise ValueError(f"{target!r} is not an ME modem (serial://, tcp:// or loop://)")
        self.transmitter = tx
        self.probe_s = probe_s
        self.backoff_s = backoff_s
        self.max_backoff_s = max_backoff_s
        self._capability = Capability.NONE
        self._capability_problems = [ONE_WAY]
        self.connection_problem = f"connecting to the modem at {target}"
        self._connected = False
        #: Why the last frame did not leave (None once one has).
        self.last_failure: str | None = None
        self._lock = asyncio.Lock()  # a check and a frame never overlap
        self._wake = asyncio.Event()
        self._checked = asyncio.Event()  # set by the first check
        self._task: asyncio.Task[None] | None = None

    @property
    def connected(self) -> bool:
        return self._connected

    @property
    def capability_problems(self) -> list[str]:
        failed = [] if self.last_failure is None else [self.last_failure]
        return [*self._capability_problems, *failed]

    @capability_problems.setter
    def capability_problems(self, value: list[str]) -> None:
        self._capability_problems = value

    async def start(self) -> None:
        """Start the watch; return once its first check is done (the link says at once what
        it found), or after :data:`FIRST_CHECK_S` (a slow name lookup or connect goes on in the
        background)."""
        self._task = asyncio.create_task(self._watch(), name=f"modem watch {self.target}")
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(self._checked.wait(), FIRST_CHECK_S)

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
            self._task = None
        await self.transmitter.aclose()

    async def _watch(self) -> None:
        backoff_s = self.backoff_s
        while True:
            await self._check()
            if self._connected:
                backoff_s, wait_s = self.backoff_s, self.probe_s
            else:
                wait_s, backoff_s = backoff_s, min(2 * backoff_s, self.max_backoff_s)
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._wake.wait(), wait_s)
            self._wake.clear()

    async def _check(self) -> LinkCheck:
        async with self._lock:
            check = await self.transmitter.check_async()
        was = self._connected
        self._connected = check.ok
        self._checked.set()
        if check.ok:
            self.connection_problem = None
            if not was:
                logger.info("modem at %s: %s", self.target, check.detail)
        else:
            self.connection_problem = (
                f"the modem at {self.target} cannot be reached: {check.reason} ({check.detail})"
            )
        return check

    async def transmit(self, frame: Frame) -> str | None:
        async with self._lock:
            result = await self.transmitter.send_async(frame, wait_ack_s=0.0)
        if result.sent:
            self._connected, self.connection_problem, self.last_failure = True, None, None
            return None
        reason = result.reason or "not sent"
        self.last_failure = (
            f"the last frame did not reach the modem at {self.target}: {reason} ({result.detail})"
        )
        self._connected = self.transmitter.connected
        if not self._connected:
            self.connection_problem = self.last_failure
        self._wake.set()  # the watch tries again now, then with its back-off
        return reason

    async def test(self) -> list[LinkCheck]:
        """Open the modem if it is not open and check that a frame could leave now; no frame
        is sent (:meth:`station.transmit.ModemTransmitter.check`)."""
        return [await self._check()]


class HybridLink(ModemLink):
    """Frames over an ME modem (``target``), telemetry and acknowledgements over a rosbridge
    (``telemetry``) that carries no frames. The capability is the rosbridge's while it is
    connected (acknowledgements come over it), else one-way (:attr:`Capability.NONE`, naming
    why): the console's delivery rules follow it, command by command."""

    def __init__(
        self,
        target: str,
        bitrate_bps: float,
        telemetry: str,
        *,
        namespace: str = "",
        probe_s: float = PROBE_S,
        backoff_s: float = BACKOFF_S,
        max_backoff_s: float = MAX_BACKOFF_S,
    ) -> None:
        super().__init__(
            target,
            bitrate_bps,
            probe_s=probe_s,
            backoff_s=backoff_s,
            max_backoff_s=max_backoff_s,
        )
        self.telemetry_link = RosbridgeLink(
            parse_telemetry(telemetry), namespace=namespace, frames=False
        )
        # what it hears goes to this link's handlers, as the console sets them (later)
        tel = self.telemetry_link
        tel.on_pose, tel.on_status, tel.on_mission = self._pose, self._status, self._mission
        tel.on_datum = self._datum

    def _pose(self, msg: dict[str, Any]) -> None:
        self.on_pose(msg)

    def _status(self, msg: dict[str, Any]) -> None:
        self.on_status(msg)

    def _mission(self, msg: dict[str, Any]) -> None:
        self.on_mission(msg)

    def _datum(self, msg: dict[str, Any]) -> None:
        self.on_datum(msg)

    @property
    def telemetry_target(self) -> str:
        return self.telemetry_link.target

    @property
    def capability(self) -> Capability:
        tel = self.telemetry_link
        return tel.capability if tel.connected else Capability.NONE

    @capability.setter
    def capability(self, value: Capability) -> NoReturn:
        raise AttributeError("a hybrid link's capability is its telemetry link's")

    @property
    def capability_problems(self) -> list[str]:
        tel = self.telemetry_link
        if tel.connected:
            problems = list(tel.capability_problems)
        else:
            why = tel.connection_problem or f"not connected to {tel.target}"
            problems = [
                f"no telemetry: {why}; commands go out over the modem as one-way copies "
                "(no acknowledgement) until it is back"
            ]
        failed = [] if self.last_failure is None else [self.last_failure]
        return [*problems, *failed]

    @capability_problems.setter
    def capability_problems(self, value: list[str]) -> None:
        self._capability_problems = value  # the modem's own (one-way) words, unused here

    async def start(self) -> None:
        await super().start()
        await self.telemetry_link.start()

    async def stop(self) -> None:
        await self.telemetry_link.stop()
        await super().stop()

    async def test(self) -> list[LinkCheck]:
        """The modem's check and the telemetry link's state; no frame is sent."""
        modem = await super().test()
        tel = [
            LinkCheck("telemetry", c.target, c.ok, c.reason, c.detail)
            for c in await self.telemetry_link.test()
        ]
        return [*modem, *tel]


def open_link(
    target: str, bitrate_bps: float, telemetry: str | None = None, namespace: str = ""
) -> Link:
    """The link for a target: ``ws://`` -> rosbridge, anything else -> an ME modem; with
    ``telemetry`` (``ws://``) the hybrid link. ``namespace``: the vehicle's ROS namespace (its
    topics under ``/<namespace>/nemesys/...``) on whichever rosbridge the link reads.

    Raises:
        ValueError: ``telemetry`` with a rosbridge target, or a malformed ``telemetry``.
    """
    if target.startswith(("ws://", "wss://")):
        if telemetry:
            raise ValueError(
                "telemetry is for an ME modem target (serial://, tcp://, loop://): a rosbridge "
                f"target ({target}) carries telemetry and acknowledgements itself"
            )
        return RosbridgeLink(target, namespace=namespace)
    if telemetry:
        return HybridLink(target, bitrate_bps, telemetry, namespace=namespace)
    return ModemLink(target, bitrate_bps)
