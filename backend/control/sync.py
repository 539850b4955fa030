"""Live sync: what other consoles sharing the mission log wrote, told to this console's pages
as its own changes are; and whether the log's database is reached at all.

On PostgreSQL, :class:`backend.mission_log.listen.Listener` hands over the key of every row
another console committed (a command written, an event added, a vehicle's control changed);
:class:`LogSync` re-reads the row over the log's own connection and publishes it on the hub,
the messages a page already knows: ``command`` (the record, every state change), ``event``,
``control``; a row of the relay's outbox written or decided goes to :attr:`LogSync.on_outbox`
(:mod:`backend.relay`), and a batch of track points (its dive) to :attr:`LogSync.on_track`
(a console without a transmitter shows the vehicle from them: :mod:`backend.relay.telemetry`).
A command of another console that is on its way supersedes this console's commands still
going out (the one rule, across consoles: a Surface from the ship stops the
shore's repeated copies). The delay is the commit's notification and one read: well under a
second on one network (``bench control-sync``).

When the listener loses the database (a closed connection, a probe unanswered), the console
says so (``link.mission_log`` in ``/api/vehicle`` and every ``link`` message, pushed at once:
the page's header shows "mission log unreachable — sends refused") and the send gate refuses
every send but Surface with 503 (:mod:`backend.control.gate`). When the listener is back it
re-reads what the console missed: the commands updated since shortly before the loss
(:data:`RESYNC_SLACK_S` for the consoles' clocks, which stamp ``updated_at``), the events
after the last one seen, and every vehicle's control; then the header clears. A SQLite log has
one console: no sync, always reached.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections import deque
from collections.abc import Callable
from datetime import datetime, timedelta
from typing import Any, Final

from backend.clock import CONSOLE_UTC
from backend.commands.health import MissionLogReach
from backend.commands.supersede import Superseding
from backend.control.desk import ControlDesk
from backend.messages import CommandMessage, EventMessage
from backend.mission_log.command_rows import command_row
from backend.mission_log.listen import Listener, Notice
from backend.mission_log.records import command_record, log_event
from backend.mission_log.store import LogWriteError, MissionLog, now_iso
from backend.telemetry import TelemetryHub

logger = logging.getLogger("backend.control.sync")

#: Commands updated this long before the loss are read again when the database is back (s):
#: the margin for the other consoles' clocks, which stamp ``updated_at``.
RESYNC_SLACK_S: Final = 60.0
#: Other consoles' commands remembered as already seen on their way (for the supersede).
SEEN_MAX: Final = 1000


class LogSync:
    """This console's live view of the others (see the module's doc)."""

    def __init__(
        self,
        url: str,
        log: MissionLog,
        hub: TelemetryHub,
        desk: ControlDesk,
        commands: Superseding,
        *,
        on_reach: Callable[[], None] = lambda: None,
    ) -> None:
        self.log = log
        self.hub = hub
        self.desk = desk
        self.commands = commands
        #: Called when the database is lost or back (the console pushes its link health).
        self.on_reach = on_reach
        #: Called with the id of an outbox row another console wrote or decided (the relay's
        #: worker or sender: :mod:`backend.relay.runtime` sets it).
        self.on_outbox: Callable[[int], None] = lambda _row_id: None
        #: Called with the dive of track points another console committed and the console
        #: that wrote them (None: not named), or ``(None, None)`` when the database is back
        #: (read the newest again): :mod:`backend.relay.runtime` sets it on a relay console.
        self.on_track: Callable[[int | None, str | None], None] = lambda _dive, _by: None
        self.listener = Listener(
            url, desk.console, on_notice=self.notice, on_lost=self.lost, on_back=self.back
        )
        self._reach = MissionLogReach()
        self._started = False
        self._lost_at: str | None = None
        self._last_event = self._newest_event()
        self._seen: deque[int] = deque(maxlen=SEEN_MAX)
        self._task: asyncio.Task[None] | None = None
        #: Notices handled and rows published (for the tests and the bench).
        self.published = 0

    def mission_log(self) -> MissionLogReach:
        """Whether the database is reached now (the gate's and the link health's)."""
        return self._reach

    def start(self) -> None:
        self._task = asyncio.create_task(self.listener.run(), name="mission log sync")

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task

    # --- the listener's callbacks ---------------------------------------------------------

    def notice(self, n: Notice) -> None:
        """Another console committed row ``n``: read it and tell the pages."""
        try:
            if n.table == "commands" and isinstance(n.key, int):
                self._command(n.key)
            elif n.table == "events" and isinstance(n.key, int):
                self._events(after=n.key - 1, upto=n.key)
            elif n.table == "control" and isinstance(n.key, str) and n.key in self.desk.vehicles:
                self.desk.told(n.key)
            elif n.table == "outbox" and isinstance(n.key, int):
                self.on_outbox(n.key)
            elif n.table == "track" and isinstance(n.key, int):
                self.on_track(n.key, n.console)
        except LogWriteError as err:  # the listener finds the loss itself, if it is one
            logger.warning("%s %s not read again: %s", n.table, n.key, err)

    def lost(self, reason: str) -> None:
        changed = self._reach.reachable or self._reach.problem != reason
        if self._reach.reachable:
            self._lost_at = now_iso()
            logger.error("mission log unreachable, sends refused: %s", reason)
        since = self._lost_at or now_iso()
        self._reach = MissionLogReach(reachable=False, problem=reason, since=since)
        if changed:
            self.on_reach()

    def back(self) -> None:
        """Listening again (or for the first time): read what was missed, then say so."""
        if not self._started:
            self._started = True
            return
        if self._reach.reachable:
            return
        try:
            self._resync()
        except LogWriteError as err:
            logger.warning("what was missed could not be read yet: %s", err)
        logger.warning("mission log reachable again (since %s it was not)", self._reach.since)
        self._reach = MissionLogReach()
        self._lost_at = None
        self.on_reach()

    # --- reading again ---------------------------------------------------------------------

    def _command(self, command_id: int) -> None:
        row = self.log.command(command_id)
        if row is not None:
            self._record(row)

    def _record(self, row: dict[str, Any]) -> None:
        """Another console's command: told to the pages; the first time it is seen, it
        supersedes this console's older commands still going out (whatever its state by now:
        a Surface acknowledged before this read still came after them)."""
        record = command_record(row)
        if record.console == self.desk.console:
            return
        self.hub.publish(CommandMessage(command=record))
        self.published += 1
        if record.id in self._seen:
            return
        self._seen.append(record.id)
        stopped = self.commands.superseded_elsewhere(record.id, record.console, record.vehicle)
        if stopped:
            logger.warning(
                "commands %s superseded by command %s of console %r",
                stopped,
                record.id,
                record.console,
            )

    def _events(self, *, after: int, upto: int | None = None) -> None:
        for event in self.log.events(after=after):
            if upto is not None and event["id"] > upto:
                break
            self.hub.publish(EventMessage(event=log_event(event)))
            self.published += 1
            self._last_event = max(self._last_event, event["id"])

    def _resync(self) -> None:
        since = CONSOLE_UTC.now() - timedelta(seconds=RESYNC_SLACK_S)
        if self._lost_at is not None:
            since = datetime.fromisoformat(self._lost_at) - timedelta(seconds=RESYNC_SLACK_S)
        stamp = since.isoformat(timespec="milliseconds")
        with self.log.connection() as db, db.writing():
            rows = db.execute(
                "SELECT * FROM commands WHERE updated_at >= ? ORDER BY id", (stamp,)
            ).fetchall()
        for row in rows:
            self._record(command_row(row))
        self._events(after=self._last_event)
        for vehicle in self.desk.vehicles:
            self.desk.told(vehicle)
        self.on_track(None, None)

    def _newest_event(self) -> int:
        with self.log.connection() as db, db.writing():
            got = db.execute("SELECT MAX(id) AS newest FROM events").fetchone()
        return int(got["newest"] or 0)
