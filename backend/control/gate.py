"""The send gate: only the console in control of a vehicle sends to it, and none while its
mission log is out of reach.

The command service consults it once, in its check step, for every frame whatever its path
(:meth:`backend.commands.service.CommandService._submit`):

* **Surface is always let through** from any console (its operator's token was checked on
  the way in), as DUNE takes an abort from anyone; its record names the console it came from
  (``console``) and, on the other consoles, it supersedes their commands still going out
  (:mod:`backend.control.sync`). Its record must still be written before it leaves: a log out
  of reach refuses it with 503 there.
* any other command while the log's database is out of reach (the listener lost it:
  :mod:`backend.control.sync`) is refused with 503 naming the cause
  (:class:`backend.mission_log.store.LogWriteError`, as a write that fails), nothing sent;
* on a log shared by consoles (PostgreSQL), a console not in control of the vehicle gets
  :class:`NotInControl` (409) naming who is (console and operator) or that nobody is; on a
  SQLite log the one console is always in control.

A relayed command (:class:`backend.commands.service.Relayed`: checked by a console without a
transmitter, taken from the outbox by this one) is judged as the console it came from: that
console must be in control of the vehicle, not this one; a relayed Surface passes as any.
"""

from __future__ import annotations

from typing import Protocol

from backend.commands.health import MissionLogReach
from backend.commands.service import SendRefused, SendRequest
from backend.control.desk import ControlDesk
from backend.control.model import iso
from backend.mission_log.store import LogWriteError
from vehicle_contract.fleet import SINGLE_VEHICLE


class MissionLogReachSource(Protocol):
    """What tells the gate whether the log's database is reached
    (:class:`backend.control.sync.LogSync`)."""

    def mission_log(self) -> MissionLogReach: ...


class NotInControl(SendRefused):
    """A send from a console that is not in control of the vehicle (nothing was written or
    transmitted)."""

    status = 409


class ControlGate:
    """The check the command service makes of every send (see the module's doc).
    ``reach``: what the console knows of its log's database now (None: a SQLite file)."""

    def __init__(self, desk: ControlDesk, reach: MissionLogReachSource | None = None) -> None:
        self.desk = desk
        self.reach = reach

    def check(self, request: SendRequest) -> None:
        """Let ``request`` through or refuse it.

        Raises:
            LogWriteError: the log's database is out of reach (not for Surface).
            NotInControl: another console, or nobody, is in control of the vehicle.
        """
        if request.pattern == "surface":
            return
        reach = self.reach.mission_log() if self.reach is not None else None
        if reach is not None and not reach.reachable:
            raise LogWriteError(
                f"its database is unreachable since {reach.since} ({reach.problem}); sends "
                "are refused until it is back",
                outcome="nothing was transmitted",
            )
        # the vehicle's name: the request's, once a fleet's requests name one
        vehicle = getattr(request, "vehicle", None) or SINGLE_VEHICLE
        held, row, now = self.desk.in_control(vehicle)
        owner = row.owner(now, self.desk.timeout_s)
        sender = self.desk.console if request.relayed is None else request.relayed.console
        allowed = held if request.relayed is None else owner == sender
        if allowed:
            return
        who = "this console" if request.relayed is None else "the console it came from"
        ask = "request control first (POST /api/control, action request)"
        if owner is None:
            raise NotInControl(f"nobody is in control of vehicle {vehicle}: {ask}")
        raise NotInControl(
            f"console {owner!r} (operator {row.operator!r}) is in control of vehicle {vehicle} "
            f"since {iso(row.since_s)}; {who} ({sender!r}) is not: {ask}"
        )
