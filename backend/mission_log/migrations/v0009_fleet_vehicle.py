"""Issue 23 (a fleet on one ME link): the vehicle each command is for, each track point is of
and each event concerns, by its name (``NEMESYS_VEHICLES``); null without a fleet (the single
vehicle's rows are as they were) and, for an event, one that concerns the whole fleet. The
console filters on it (``GET /api/commands?vehicle=``, a dive's track and records per vehicle)
and the CSV export carries it.
"""

from __future__ import annotations

import sqlalchemy as sa

from backend.mission_log.migrating import add_missing

revision = "0009"
down_revision = "0008"

#: The tables that gain ``vehicle`` (TEXT, null).
TABLES = ("commands", "track", "events")


def upgrade() -> None:
    for table in TABLES:
        add_missing(table, sa.Column("vehicle", sa.Text))
