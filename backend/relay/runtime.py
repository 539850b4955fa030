"""The relay as the console runs it: what :class:`backend.console.Console` makes after its
control (the sync's notifications) and before its command service, starts once the service
is made, and stops before the control.

* a console without a transmitter (``NEMESYS_TARGET=relay``, always on PostgreSQL: the
  settings refuse it otherwise): its :class:`RelayLink` reads the transmitting consoles from
  the log, its :class:`RelaySender` is the command service's relay, woken by the outbox rows'
  notifications, and its :class:`RelayedTelemetry` shows the vehicle from the track points
  the transmitting console writes, woken by their notifications;
* a console with a transmitter on a shared log: its :class:`RelayWorker` takes the outbox
  through the command service, woken by the notifications, sweeping every second;
* on a SQLite log (one console): nothing.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from typing import TYPE_CHECKING, Any

from backend.commands.service import CommandService
from backend.relay.link import RelayLink
from backend.relay.model import RelayView
from backend.relay.ship import RelayWorker
from backend.relay.shore import RelaySender
from backend.relay.telemetry import RelayedTelemetry
from station.link import Link
from station.link_fleet import FleetLink

if TYPE_CHECKING:
    from backend.console import Console

logger = logging.getLogger("backend.relay")


class RelayRuntime:
    """This console's end of the relay (both None: a SQLite log)."""

    def __init__(self, rt: Console) -> None:
        self._rt = rt
        self.sender: RelaySender | None = None
        self.worker: RelayWorker | None = None
        self.telemetry: RelayedTelemetry | None = None
        self._task: asyncio.Task[None] | None = None
        control, log = rt.control, rt.log
        assert control is not None and log is not None
        self.link = relay_of(rt.link)
        if self.link is not None:
            self.link.attach(log)
            self.sender = RelaySender(
                log, control.console, rt.settings.operator, rt.settings.relay_wait_s
            )
            self.telemetry = RelayedTelemetry(rt, self.link.view)

    @property
    def shared(self) -> bool:
        return self._rt.control is not None and self._rt.control.sync is not None

    def start(self, service: CommandService) -> None:
        """Listen for the outbox's rows (a shared log), and on a console with a transmitter
        take them through ``service``."""
        rt, sync = self._rt, self._rt.control.sync if self._rt.control else None
        if sync is None:
            return
        if self.sender is not None:
            sync.on_outbox = self.sender.notice
            logger.info("no transmitter here: commands relayed through the shared log")
            if self.telemetry is not None:
                sync.on_track = self.telemetry.notice
                self.telemetry.notice(None, None)  # where the vehicle last was, if known
            return
        assert rt.log is not None and rt.commands is not None and rt.dives is not None
        self.worker = RelayWorker(
            rt.log,
            service,
            rt.commands,
            rt.dives,
            rt.hub,
            console=sync.desk.console,
            vehicles=sync.desk.vehicles,
            target=rt.settings.target,
            max_age_s=rt.settings.relay_max_age_s,
            health=self._health,
        )
        sync.on_outbox = self.worker.wake
        self._task = asyncio.create_task(self.worker.run(), name="relay outbox")

    def _health(self) -> dict[str, Any]:
        h = self._rt.link_health()
        keys = ("connected", "capability", "acknowledges", "level", "problems")
        d = self._rt.datum  # the origin of the track's positions, for the relaying consoles
        datum = None if d is None else {"lat_deg": d.lat_deg, "lon_deg": d.lon_deg}
        # the vehicles it takes commands for (a relaying console with another fleet is told)
        said = h.model_dump(include=set(keys), mode="json")
        return {**said, "datum": datum, "vehicles": self._rt.fleet.names}

    def view(self, vehicle: str | None = None) -> RelayView | None:
        """What the page shows of the relay (to a fleet's ``vehicle``: the console that has
        it); None: this console holds a transmitter."""
        if self.link is None:
            return None
        via = None if self.telemetry is None else self.telemetry.via_of(vehicle)
        return self.link.view(vehicle).model_copy(update={"telemetry_via": via})

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task


def relay_of(link: Link | None) -> RelayLink | None:
    """The relay link of a console without a transmitter (a fleet's: its one
    :class:`RelayLink`); None: this console holds a transmitter."""
    if isinstance(link, FleetLink):
        link = link.frames
    return link if isinstance(link, RelayLink) else None
