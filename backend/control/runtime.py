"""Control and live sync as the console runs them: what :class:`backend.console.Console`
starts after its command manager and stops before it.

On a log shared by consoles (PostgreSQL): the console's name goes into the log's session
(its notifications and records carry it), the listener starts (:mod:`backend.control.sync`),
the console takes control of each vehicle nobody controls (``control_at_start``) and beats
its heartbeat; at a clean stop it releases what it holds. On a SQLite log only the desk (the
actions, logged) and the gate (which then never refuses for control).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from typing import TYPE_CHECKING

from backend.commands.health import MissionLogReach
from backend.control.desk import ControlDesk
from backend.control.gate import ControlGate
from backend.control.identity import console_name
from backend.control.sync import LogSync
from backend.fleet.views import link_news
from backend.mission_log.store import LogWriteError

if TYPE_CHECKING:
    from backend.console import Console

logger = logging.getLogger("backend.control")


class ControlRuntime:
    """The desk, the gate and (shared log) the sync and the heartbeat of one console."""

    def __init__(self, desk: ControlDesk, sync: LogSync | None) -> None:
        self.desk = desk
        self.sync = sync
        self.gate = ControlGate(desk, sync)
        #: The heartbeat's task (shared log; cancelled, the console's control times out).
        self.heartbeat: asyncio.Task[None] | None = None

    @property
    def console(self) -> str:
        """This console's name."""
        return self.desk.console

    def mission_log(self) -> MissionLogReach:
        """Whether the log's database is reached now (a SQLite file always is)."""
        return self.sync.mission_log() if self.sync is not None else MissionLogReach()

    async def stop(self) -> None:
        if self.heartbeat is not None:
            self.heartbeat.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self.heartbeat
        if self.sync is not None:
            await self.sync.stop()
            if self.sync.mission_log().reachable:
                self.desk.release_all()


def start_control(rt: Console) -> ControlRuntime:
    """The console's control, started (its log, dives and command manager already are).

    Raises:
        backend.control.identity.ConsoleNameError: the kept name cannot be used.
        LogWriteError: the log cannot be written at start (taking control).
    """
    s = rt.settings
    assert rt.log is not None and rt.dives is not None and rt.commands is not None
    name = console_name(s)
    rt.log.name_console(name)
    shared = rt.log.kind == "postgresql"
    desk = ControlDesk(
        rt.log,
        rt.dives,
        rt.hub,
        console=name,
        operator=s.operator,
        vehicles=tuple(rt.fleet.names),  # "nemesys" without a fleet
        timeout_s=s.control_timeout_s,
        shared=shared,
    )
    if not shared:
        return ControlRuntime(desk, None)

    def push_link() -> None:
        if rt.link is not None and rt.commands is not None:
            for news in link_news(rt):  # each vehicle's, named in a fleet
                rt.hub.publish(news)

    sync = LogSync(s.database_url, rt.log, rt.hub, desk, rt.commands, on_reach=push_link)
    runtime = ControlRuntime(desk, sync)
    if s.control_at_start:
        try:
            desk.claim_at_start()
        except LogWriteError as err:
            logger.error("could not take control at start: %s", err)
    sync.start()
    runtime.heartbeat = asyncio.create_task(desk.run(), name="control heartbeat")
    logger.info("console %r on a shared mission log (control timeout %g s)", name, desk.timeout_s)
    return runtime
