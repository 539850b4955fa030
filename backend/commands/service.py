"""The command service: the one way a frame leaves the console.

Every path that transmits (the REST send, the ``/ws`` send, Surface from the button, the
shortcut, the API or ``/ws``, a retry, a mission script's step, a training scenario) calls
:meth:`CommandService.send`, :meth:`CommandService.retry` or :meth:`CommandService.surface`;
``nemesys send`` runs the same policy (:func:`decide`) in its own process. One policy:

* the checks (:class:`Assessment`): the dictionary's ranges and snapping (the codec refuses
  what it cannot carry, naming the field), the depth rating and the depth and speed limits,
  the vehicle profile (top speed, endurance against the battery now), the geofence and the
  ME link's reach; the rate limit (not for Surface);
* a **hard** violation is refused on every path (:class:`LimitRefused`, 422); a **soft** one
  needs an explicit override on every path (:class:`OverrideNeeded`, 409), and an override is
  written into the record: who gave it and for which violations;
* the record is written to the mission log before the first copy leaves; a log that cannot
  be written refuses the send (:class:`backend.mission_log.store.LogWriteError`, 503 on every
  path), and nothing is transmitted;
* a retry is a new command: a new record, created now, naming the one it retries
  (``retry_of``), checked as any other send from where the vehicle is now.

Surface is never refused by the checks: it is the way out.

**A fleet** (``NEMESYS_VEHICLES``): every request names its vehicle (``vehicle``), never an
implicit one: a request without it, or naming no vehicle of the fleet, is refused
(:class:`VehicleRefused`, 422, naming the vehicles); ``"all"`` only for Surface (one frame to
address 0, one record per vehicle). The checks are that vehicle's (where it is, what it flies)
and its frame carries its address. Without a fleet, ``vehicle`` is absent or the single
vehicle's name, and everything is as it always was.

**The gate** (:class:`SendGate`, given to the service): consulted once for every command
after the checks, before anything is written: on a mission log several consoles share, only
the console in control of the vehicle sends (:class:`backend.control.gate.ControlGate`:
others get 409 naming who is; Surface passes from any console), and none while the log's
database is out of reach (503).

**The relay** (:class:`Relay`, given to the service of a console without a transmitter,
``NEMESYS_TARGET=relay``): after the checks, the gate and the watchers' ``admit``, the command
goes to the shared log's outbox instead of the manager, and the service returns the record
the console holding the transmitter made of it, or raises its refusal
(:mod:`backend.relay.shore`). That console takes the row through its own service
(:class:`Relayed` in the request): its own checks, its gate judging the console the command
came from, a record whose ``origin`` is ``relay:<console>`` and whose operator is the one who
asked (:mod:`backend.relay.ship`).

**Watchers** (:class:`SendWatcher`, :meth:`CommandService.watch`) are told of every command
the service hands to the manager, whatever the path: ``admit`` just before the record is
written (it may refuse), ``sent`` once it is written and its delivery begun, before its first
copy can leave (the manager starts the delivery as a task, which runs only once the caller
yields; :meth:`CommandService.send` calls the watchers before it does). The console's
mission script run watches: any command that is not a step of the running script ends the
run, so a newer command or Surface is never undone by a later step
(:mod:`backend.scripts.guard`; this package does not know it).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol

from backend.commands.checks import SendViolation
from backend.commands.lifecycle import RETRYABLE
from backend.commands.manager import CommandManager
from backend.commands.policy import Accepted, Assessment, decide, key
from backend.commands.refusals import (
    LimitRefused,
    NotRetryableCommand,
    OverrideNeeded,
    SendRefused,
    UnknownCommand,
    VehicleRefused,
    check_vehicle,
    refusal_detail,
)
from backend.commands.vehicles import ALL_VEHICLES
from backend.mission_log.records import CommandRecord, command_record
from codec import Encoded, encode_frame

logger = logging.getLogger("backend.commands.service")

#: The ways a frame can leave the console, as the record's ``origin`` names them.
Origin = Literal["api", "ws", "surface", "retry", "script", "scenario", "cli"]
ORIGINS: tuple[Origin, ...] = ("api", "ws", "surface", "retry", "script", "scenario", "cli")


@dataclass(frozen=True)
class Relayed:
    """A command another console (one without a transmitter) checked and wrote to the shared
    log's outbox: row ``outbox_id``, from ``console``, asked by ``operator``."""

    console: str
    operator: str
    outbox_id: int

    @property
    def origin(self) -> str:
        """The record's ``origin``."""
        return f"relay:{self.console}"


@dataclass(frozen=True)
class SendRequest:
    """What a path asks the service to send.

    Attributes:
        pattern, params: the command as the operator wrote it (the codec checks and snaps).
        origin: the path it came by (written into the record).
        override: the operator accepts the soft violations.
        copies: the operator's number of copies (None: chosen from the link).
        kind: the record's kind (``script`` for a script's step).
        retry_of: the command this one retries.
        vehicle: the fleet's vehicle it is for (``"all"``: a Surface to every vehicle); None
            without a fleet (the single vehicle's name is taken too).
        relayed: taken from another console's outbox row (None: asked of this console).
        accepted: relayed, the soft violations its operator accepted there (an override
            covers those only: :func:`decide`).
    """

    pattern: str
    params: Mapping[str, Any]
    origin: Origin
    override: bool = False
    copies: int | None = None
    kind: Literal["command", "script"] = "command"
    retry_of: int | None = None
    vehicle: str | None = None
    relayed: Relayed | None = None
    accepted: Accepted | None = None


@dataclass(frozen=True)
class SendOutcome:
    """The record as written (queued, or a Surface joined), and what the operator overrode;
    ``records``: every record it wrote (a Surface to all: one per vehicle, ``record`` the
    first)."""

    record: CommandRecord
    overridden: tuple[SendViolation, ...] = field(default=())
    records: tuple[CommandRecord, ...] = field(default=())

    def __post_init__(self) -> None:
        if not self.records:  # one record: itself
            object.__setattr__(self, "records", (self.record,))


class Assessor(Protocol):
    """The checks of a send (the console's): ``vehicle``, a fleet's, is given only there;
    the frame it returns carries that vehicle's address."""

    def __call__(
        self, pattern: str, params: Mapping[str, Any], vehicle: str | None = None
    ) -> Assessment: ...


class SendWatcher(Protocol):
    """Told of every command the service hands to the manager (see the module's docstring).
    Both calls run on the event loop, with no wait between them and the record's writing."""

    def admit(self, request: SendRequest) -> None:
        """Just before the record is written, after the checks: raise a
        :class:`SendRefused` to refuse the send (nothing is written or transmitted)."""

    def sent(self, request: SendRequest, outcome: SendOutcome) -> None:
        """The record is written (or a Surface joined the one on its way) and its delivery
        begun; no copy of it has left yet."""


class SendGate(Protocol):
    """Who may send now (see the module's docstring)."""

    def check(self, request: SendRequest) -> None:
        """Raise a :class:`SendRefused` (or ``LogWriteError``) to refuse ``request``."""


class Relay(Protocol):
    """Where a console without a transmitter hands its checked commands (see the module's
    docstring)."""

    async def relay(self, request: SendRequest, accepted: Accepted) -> tuple[CommandRecord, ...]:
        """The records the console with the transmitter made of ``request`` (one; a fleet's
        Surface to all: one per vehicle) (raise a :class:`SendRefused` with its refusal);
        ``accepted``: the soft violations this console's checks found and its operator
        overrode."""
        ...


class CommandService:
    """The one checked path to the vehicle (see the module's docstring)."""

    def __init__(
        self,
        manager: CommandManager,
        assess: Assessor,
        operator: str,
        gate: SendGate | None = None,
        relay: Relay | None = None,
    ) -> None:
        self.manager = manager
        self.assess = assess
        self.operator = operator
        self.gate = gate
        self.relay = relay
        self._watchers: list[SendWatcher] = []

    def watch(self, watcher: SendWatcher) -> None:
        """Tell ``watcher`` of every command from now on (in the order they were added)."""
        self._watchers.append(watcher)

    async def send(self, request: SendRequest) -> SendOutcome:
        """Check ``request`` and hand it to the manager (written first, then transmitted).

        Raises:
            codec.EncodeError / planner.PlanError: a value the frame cannot carry, named.
            LimitRefused / OverrideNeeded: the policy (:func:`decide`).
            RateLimited: too many transmissions in the last minute (never Surface).
            LogWriteError: the mission log cannot be written (or, the gate: its database is
                out of reach); nothing was transmitted.
            SendRefused: the gate's (another console in control: 409).
        """
        vehicle = self.vehicle_of(request.vehicle, surface=request.pattern == "surface")
        if request.pattern == "surface":
            return await self._surface(request, vehicle)
        if vehicle is None:
            assessment = self.assess(request.pattern, dict(request.params))
        else:
            assessment = self.assess(request.pattern, dict(request.params), vehicle)
        overridden = decide(assessment, request.override, request.accepted)
        return await self._submit(
            request, assessment.enc, request.kind, request.copies, overridden, vehicle
        )

    async def surface(
        self, origin: Origin = "surface", retry_of: int | None = None, vehicle: str | None = None
    ) -> SendOutcome:
        """Surface (of a fleet's ``vehicle``, or ``"all"``): never refused by the checks
        (pressed while another Surface to it is on its way, it joins that one).

        Raises:
            VehicleRefused: a fleet's Surface that names no vehicle of it, nor all.
        """
        request = SendRequest("surface", {}, origin, retry_of=retry_of, vehicle=vehicle)
        return await self._surface(request, self.vehicle_of(vehicle, surface=True))

    async def _surface(self, request: SendRequest, vehicle: str | None) -> SendOutcome:
        address = self._address(vehicle)
        enc = encode_frame("surface", {}, address=address)
        return await self._submit(request, enc, "surface", None, (), vehicle)

    def vehicle_of(self, name: str | None, *, surface: bool = False) -> str | None:
        """The vehicle a request names, checked (:func:`check_vehicle`).

        Raises:
            VehicleRefused: naming what is allowed.
        """
        cm = self.manager
        return check_vehicle(name, list(cm.vehicles) if cm.fleet else [], surface=surface)

    def _address(self, vehicle: str | None) -> int | None:
        """The frame address of a checked vehicle (None: the single vehicle's, unaddressed)."""
        if vehicle is None:
            return None
        if vehicle == ALL_VEHICLES:
            return 0
        return self.manager.vehicles[vehicle].address

    async def _submit(
        self,
        request: SendRequest,
        enc: Encoded,
        kind: str,
        copies: int | None,
        overridden: Sequence[SendViolation],
        vehicle: str | None = None,
    ) -> SendOutcome:
        """The watchers' ``admit``, the manager's record and delivery, the watchers' ``sent``:
        no ``await`` that yields between them (the manager's ``submit`` does not), so the
        watchers hear of the command before its first copy can leave (relayed: once the other
        console made its record)."""
        if self.gate is not None:
            self.gate.check(request)
        for watcher in self._watchers:
            watcher.admit(request)
        if self.relay is not None:
            accepted = frozenset(key(v) for v in overridden)
            made = await self.relay.relay(request, accepted)
            outcome = SendOutcome(made[0], tuple(overridden), made)
        else:
            relayed = request.relayed
            rows = await self.manager.submit_all(
                enc,
                kind=kind,
                copies=copies,
                origin=request.origin if relayed is None else relayed.origin,
                retry_of=request.retry_of,
                overrides=self._overrides(overridden, relayed),
                operator=None if relayed is None else relayed.operator,
                vehicle=vehicle,
            )
            records = tuple(command_record(row) for row in rows)
            outcome = SendOutcome(records[0], tuple(overridden), records)
        for watcher in self._watchers:
            try:
                watcher.sent(request, outcome)
            except Exception:  # the command is on its way: its sender gets its record
                logger.exception("a watcher failed on command %s", outcome.record.id)
        return outcome

    async def retry(
        self,
        command_id: int,
        *,
        override: bool = False,
        copies: int | None = None,
        vehicle: str | None = None,
    ) -> SendOutcome:
        """A new command with the values of ``command_id`` (a retryable record), checked as
        any other send from where the vehicle is now (a fleet's: ``vehicle``, named as every
        send names it; it may be another than the record's).

        Raises:
            UnknownCommand: no such record. NotRetryableCommand: not in a retryable state.
            The errors of :meth:`send`.
        """
        row = self.manager.log.command(command_id)
        if row is None:
            raise UnknownCommand(f"no command {command_id}")
        old = command_record(row)
        if old.state not in RETRYABLE:
            raise NotRetryableCommand(
                f"command {command_id} is {old.state}; only "
                f"{', '.join(sorted(RETRYABLE))} commands can be retried"
            )
        kind: Literal["command", "script"] = "command"
        return await self.send(
            SendRequest(
                old.pattern,
                old.params,
                "retry",
                override=override,
                copies=copies,
                kind=kind,
                retry_of=command_id,
                vehicle=vehicle,
            )
        )

    def _overrides(
        self, overridden: Sequence[SendViolation], relayed: Relayed | None
    ) -> dict[str, Any] | None:
        if not overridden:
            return None
        return {
            "by": self.operator if relayed is None else relayed.operator,
            "violations": [
                {"check": v.check, "param": v.param, "message": v.message} for v in overridden
            ],
        }


__all__ = [
    "ORIGINS",
    "Accepted",
    "Assessment",
    "CommandService",
    "LimitRefused",
    "NotRetryableCommand",
    "Origin",
    "OverrideNeeded",
    "Relay",
    "Relayed",
    "SendGate",
    "SendOutcome",
    "SendRefused",
    "SendRequest",
    "SendWatcher",
    "UnknownCommand",
    "VehicleRefused",
    "check_vehicle",
    "decide",
    "refusal_detail",
]
