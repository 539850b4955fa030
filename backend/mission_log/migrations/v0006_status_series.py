"""Issue 22 (the status series): each track point keeps the depth the active command asks for,
whether the vehicle's navigation was valid (0/1; null: not said) and its age; a point made
from a status while the navigation was not valid has no position, so the position and the
heading may be null.

SQLite cannot drop a ``NOT NULL``: ``batch_alter_table`` makes the track again (a new table
with the same columns, the rows copied in their order, the old one dropped, the new one
renamed, its index ``track_dive`` made again), inside the migrations' one transaction, so a
console killed half-way leaves the old table as it was. PostgreSQL alters the columns in place.
What a log already has is left as it is (the previous version's ``create_or_migrate`` gave its
logs these columns and a nullable position, without a migration version).
"""

from __future__ import annotations

from typing import Any

import sqlalchemy as sa
from alembic import op

from backend.mission_log.migrating import REAL

revision = "0006"
down_revision = "0005"

#: The columns added: name and type.
ADDED: tuple[tuple[str, Any], ...] = (
    ("commanded_depth_m", REAL),
    ("nav_valid", sa.Integer),  # a boolean as 0/1, as SQLite keeps it
    ("nav_age_s", REAL),
)
#: The position's columns, NOT NULL before.
POSITION = ("x_m", "y_m", "z_m", "heading_deg")


def upgrade() -> None:
    have = {str(c["name"]): c for c in sa.inspect(op.get_bind()).get_columns("track")}
    added = [sa.Column(name, kind) for name, kind in ADDED if name not in have]
    not_null = [name for name in POSITION if not have[name]["nullable"]]
    if not added and not not_null:
        return
    with op.batch_alter_table("track", recreate="auto") as track:
        for column in added:
            track.add_column(column)
        for name in not_null:
            track.alter_column(name, existing_type=REAL, nullable=True)
