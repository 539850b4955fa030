"""The console's control desk: its actions on who is in control of each vehicle, its
heartbeat, and what every page is told of it.

The rules and the table are :mod:`backend.mission_log.control`; the desk adds the console's
own name and operator, the dive the events go into, and the news: every change is an
``event`` and a ``control`` message on ``/ws`` of this console, and (PostgreSQL's
notifications, :mod:`backend.control.sync`) of every other console sharing the log.

**Shared** (a PostgreSQL log, several consoles): the console in control beats every
:attr:`ControlDesk.heartbeat_s` (a third of the timeout); any console releases a control
whose heartbeat is older than the timeout (on the database's clock), logged once; at start it
takes control of each vehicle nobody controls (``control_at_start``) and at a clean stop it
releases what it holds. **Not shared** (a SQLite file: one console): the console is in
control implicitly (``implicit`` in the view); its actions still work and are logged, and no
send is ever refused for control.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Sequence
from typing import Final

from backend.control.model import ControlAction, ControlResult, ControlView, control_view
from backend.dives import Dives
from backend.messages import ControlMessage, EventMessage
from backend.mission_log import control
from backend.mission_log.control import Actor, ControlChange, ControlRow
from backend.mission_log.records import log_event
from backend.mission_log.store import LogWriteError, MissionLog
from backend.telemetry import TelemetryHub

logger = logging.getLogger("backend.control")

#: The shortest time between two heartbeats (s), whatever the timeout.
MIN_HEARTBEAT_S: Final = 0.2


class UnknownVehicle(ValueError):
    """A vehicle this console does not know; the message names those it does."""


class ControlDesk:
    """This console's side of control (see the module's doc)."""

    def __init__(
        self,
        log: MissionLog,
        dives: Dives,
        hub: TelemetryHub,
        *,
        console: str,
        operator: str,
        vehicles: Sequence[str],
        timeout_s: float,
        shared: bool,
    ) -> None:
        self.log = log
        self.dives = dives
        self.hub = hub
        self.console = console
        self.operator = operator
        #: The vehicles' names (opaque keys; "nemesys" without a fleet).
        self.vehicles = tuple(vehicles)
        self.timeout_s = timeout_s
        #: Several consoles may share the log (PostgreSQL): control is enforced.
        self.shared = shared
        self.heartbeat_s = max(MIN_HEARTBEAT_S, timeout_s / 3)

    @property
    def actor(self) -> Actor:
        return Actor(self.console, self.operator)

    def vehicle(self, name: str | None) -> str:
        """``name`` checked (None: the one vehicle without a fleet, the first with one).

        Raises:
            UnknownVehicle: not one of :attr:`vehicles`.
        """
        if name is None:
            return self.vehicles[0]
        if name not in self.vehicles:
            known = ", ".join(self.vehicles)
            raise UnknownVehicle(f"unknown vehicle {name[:40]!r}; this console's vehicles: {known}")
        return name

    # --- reading ---------------------------------------------------------------------------

    def row(self, vehicle: str) -> tuple[ControlRow, float]:
        """``vehicle``'s row and the database's clock (LogWriteError: cannot be read)."""
        return control.row(self.log, vehicle)

    def in_control(self, vehicle: str) -> tuple[bool, ControlRow, float]:
        """Whether this console may send to ``vehicle`` now (always, on a log not shared)."""
        row, now = self.row(vehicle)
        return (not self.shared or row.owner(now, self.timeout_s) == self.console), row, now

    def view(self, vehicle: str) -> ControlView:
        row, now = self.row(vehicle)
        return self._view(row, now)

    def views(self) -> list[ControlView]:
        """Every vehicle's control, in :attr:`vehicles`' order."""
        found, now = control.rows(self.log)
        return [self._view(found.get(v, ControlRow(v)), now) for v in self.vehicles]

    def _view(self, row: ControlRow, now: float) -> ControlView:
        implicit = None if self.shared else (self.console, self.operator)
        return control_view(row, now, self.timeout_s, implicit_owner=implicit)

    # --- acting ----------------------------------------------------------------------------

    def act(
        self,
        action: ControlAction,
        vehicle: str | None = None,
        takeover_allowed: bool | None = None,
    ) -> ControlResult:
        """Do ``action`` for this console's operator; every change is logged and told.

        Raises:
            UnknownVehicle: naming the vehicles this console has.
            backend.mission_log.control.ControlRefused: the rules do not allow it.
            LogWriteError: the log cannot be written (nothing changed).
        """
        name = self.vehicle(vehicle)
        dive = self.dives.ensure()
        changes = control.act(
            self.log, dive, name, action, self.actor, self.timeout_s, takeover_allowed
        )
        self._tell(changes)
        return ControlResult(outcome=changes[-1].outcome, control=self.view(name))

    def _tell(self, changes: Sequence[ControlChange]) -> None:
        for change in changes:
            logger.info("%s", change.event["detail"])
            self.hub.publish(EventMessage(event=log_event(change.event)))
        if changes:
            self.told(changes[-1].after.vehicle)

    def told(self, vehicle: str) -> None:
        """``vehicle``'s control changed (here, or another console's change was told): every
        page gets it."""
        self.hub.publish(ControlMessage(control=self.view(vehicle)))

    # --- shared: start, heartbeat, timeouts, stop --------------------------------------------

    def claim_at_start(self) -> None:
        """Take control of each vehicle nobody controls (a log shared by consoles)."""
        for vehicle in self.vehicles:
            row, now = self.row(vehicle)
            if row.owner(now, self.timeout_s) is None:
                self.act("request", vehicle)

    def beat(self) -> None:
        """One heartbeat of what this console controls, then release any control timed out
        (LogWriteError: the log cannot be written)."""
        control.heartbeat(self.log, self.console, self.timeout_s)
        for vehicle in control.expired(self.log, self.timeout_s):
            change = control.release_expired(self.log, self.dives.ensure(), vehicle, self.timeout_s)
            if change is not None:  # another console may have released it first
                self._tell([change])

    async def run(self) -> None:
        """Beat every :attr:`heartbeat_s` until cancelled (a log that cannot be written is
        said, and tried again at the next beat)."""
        while True:
            try:
                self.beat()
            except LogWriteError as err:
                logger.warning("control heartbeat not written: %s", err)
            await asyncio.sleep(self.heartbeat_s)

    def release_all(self) -> None:
        """A clean stop: release every vehicle this console controls (a failure is said)."""
        if not self.shared:
            return
        for vehicle in self.vehicles:
            try:
                held, _row, _now = self.in_control(vehicle)
                if held:
                    self.act("release", vehicle)
            except (LogWriteError, control.ControlRefused) as err:
                logger.warning("control of %s not released at stop: %s", vehicle, err)
