"""What the relay tests share: a shore's outbox row written straight into the shared log (as a
shore console writes it), and the transmitting console's decision on it, waited for."""

from __future__ import annotations

from backend.mission_log import outbox
from backend.mission_log.outbox import OutboxRow
from backend.mission_log.store import MissionLog
from tests.backend.conftest import CIRCLE, wait_until


def shore_row_decided(url: str, vehicle: str) -> OutboxRow:
    """A circle for ``vehicle`` written as console ``shore`` (operator ``bob``) would, and the
    row once a console holding the transmitter decided it."""
    log = MissionLog(url)
    try:
        log.name_console("shore")
        row = outbox.put(
            log,
            console="shore",
            operator="bob",
            vehicle=vehicle,
            origin="api",
            kind="command",
            pattern="circle",
            params=CIRCLE,
            override=False,
            copies=None,
            retry_of=None,
        )
        decided: OutboxRow = wait_until(
            lambda: (got := outbox.get(log, row.id)) is not None and got.state != "waiting" and got
        )
        return decided
    finally:
        log.close()
