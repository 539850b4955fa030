"""Other consoles' writes, as PostgreSQL tells them: a dedicated connection that ``LISTEN``\\ s.

Migration 0007's triggers ``pg_notify`` the key of every command written, event added and
control changed (0008's an outbox row, 0010's a batch of track points: its dive), from inside
the writing transaction: the notification is delivered only if it commits, in commit order.
Its payload is the key alone (``{"table": "commands", "id": 12, "console": "ship"}``); the
listening console re-reads the row over its own log connection.

psycopg 3 delivers notifications on an autocommit connection, and waiting for them blocks
that connection's other statements (psycopg #340): so :class:`Listener` has a connection of
its own, used for nothing else but a liveness probe (``SELECT 1``) after every
:data:`PROBE_S` without a notification, bounded by :data:`PROBE_TIMEOUT_S` (a server that
stopped answering is as gone as one that closed the socket). A connection that fails is the
database lost (``on_lost`` with the driver's reason, once); the listener connects again
after :data:`BACKOFF_S` (growing), and once it listens again ``on_back`` runs, to re-read what
the console missed meanwhile (notifications are not kept for a session that was not there).
A console's own writes are not told back to it (their ``console`` is its own).
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Final

from backend.mission_log.database import APPLICATION_NAME, CONNECT_TIMEOUT_S, one_line

if TYPE_CHECKING:
    import psycopg

logger = logging.getLogger("backend.mission_log.listen")

#: The channel migration 0007's triggers notify.
CHANNEL: Final = "nemesys_log"
#: Time without a notification after which the connection is probed (s).
PROBE_S: Final = 1.0
#: The longest a probe may take before the server counts as gone (s).
PROBE_TIMEOUT_S: Final = 3.0
#: Waits before each attempt to connect again, the last repeated (s).
BACKOFF_S: Final = (0.2, 0.5, 1.0, 2.0)
#: The listener's name on the server (pg_stat_activity).
LISTEN_APPLICATION_NAME: Final = f"{APPLICATION_NAME} listen"


@dataclass(frozen=True)
class Notice:
    """A row another console wrote: its ``table`` and key (``id``, or the vehicle of
    ``control``), and the writing ``console`` (None: a session that gave no name)."""

    table: str
    key: int | str
    console: str | None


def parse_notice(payload: str) -> Notice | None:
    """A notification's payload as a :class:`Notice` (None: not one of ours)."""
    try:
        doc = json.loads(payload)
    except ValueError:
        return None
    if not isinstance(doc, dict):
        return None
    table, key, console = doc.get("table"), doc.get("id"), doc.get("console")
    if not isinstance(table, str) or not isinstance(key, int | str) or isinstance(key, bool):
        return None
    return Notice(table, key, console if isinstance(console, str) and console else None)


class Listener:
    """Listens on :data:`CHANNEL` of the database at ``url`` for console ``console`` (see the
    module's doc). The callbacks run on the event loop :meth:`run` runs on."""

    def __init__(
        self,
        url: str,
        console: str,
        *,
        on_notice: Callable[[Notice], None],
        on_lost: Callable[[str], None],
        on_back: Callable[[], None],
        probe_s: float = PROBE_S,
        probe_timeout_s: float = PROBE_TIMEOUT_S,
        backoff_s: tuple[float, ...] = BACKOFF_S,
    ) -> None:
        self.url = url
        self.console = console
        self.on_notice = on_notice
        self.on_lost = on_lost
        self.on_back = on_back
        self.probe_s = probe_s
        self.probe_timeout_s = probe_timeout_s
        self.backoff_s = backoff_s
        #: Whether it listens now (the database is reachable).
        self.listening = False
        #: Notifications handled (another console's), for the tests and the bench.
        self.notices = 0

    async def run(self) -> None:
        """Listen until cancelled, connecting again whenever the connection is lost."""
        import psycopg

        attempt = 0
        while True:
            try:
                conn = await psycopg.AsyncConnection.connect(
                    self.url,
                    autocommit=True,
                    connect_timeout=CONNECT_TIMEOUT_S,
                    application_name=LISTEN_APPLICATION_NAME,
                )
            except (psycopg.Error, OSError) as err:
                self._lost(one_line(str(err)) or type(err).__name__)
                await asyncio.sleep(self.backoff_s[min(attempt, len(self.backoff_s) - 1)])
                attempt += 1
                continue
            try:
                async with conn:
                    await conn.execute(f"LISTEN {CHANNEL}")
                    attempt = 0
                    self.listening = True
                    self._call(self.on_back)
                    await self._listen(conn)
            except (psycopg.Error, OSError, TimeoutError) as err:
                reason = "no answer" if isinstance(err, TimeoutError) else one_line(str(err))
                self._lost(reason or type(err).__name__)
                await asyncio.sleep(self.backoff_s[0])

    async def _listen(self, conn: psycopg.AsyncConnection[object]) -> None:
        while True:
            async for note in conn.notifies(timeout=self.probe_s):
                notice = parse_notice(note.payload)
                if notice is None or notice.console == self.console:
                    continue
                self.notices += 1
                self._call(self.on_notice, notice)
            async with asyncio.timeout(self.probe_timeout_s):
                await conn.execute("SELECT 1")

    def _lost(self, reason: str) -> None:
        """Told at every failed attempt (the reason may change: refused, then no answer)."""
        self.listening = False
        self._call(self.on_lost, reason)

    @staticmethod
    def _call(fn: Callable[..., None], *args: object) -> None:
        """A callback's failure is the console's bug, said, never the listener's end."""
        try:
            fn(*args)
        except Exception:
            logger.exception("a mission log notification's handler failed")
