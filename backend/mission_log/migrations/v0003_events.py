"""Events: what the vehicle or the operator did that the log keeps beside the commands (an
echo mismatch, a datum, the BER the copies follow, a script run stopped)."""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

from backend.mission_log.migrating import id_column

revision = "0003"
down_revision = "0002"


def upgrade() -> None:
    op.create_table(
        "events",
        id_column(),
        sa.Column("dive", sa.Integer, sa.ForeignKey("dives.id"), nullable=False),
        sa.Column("at", sa.Text, nullable=False),
        sa.Column("kind", sa.Text, nullable=False),
        sa.Column("detail", sa.Text, nullable=False),
        sa.Column("data", sa.Text),
        if_not_exists=True,
    )
    op.create_index("events_dive", "events", ["dive"], if_not_exists=True)
