"""Issue 19: the path a command came by, the command a retry retries, the operator's
overrides (JSON: who, which violations) and the time its first copy left (the wire order)."""

from __future__ import annotations

import sqlalchemy as sa

from backend.mission_log.migrating import add_missing

revision = "0004"
down_revision = "0003"


def upgrade() -> None:
    add_missing(
        "commands",
        sa.Column("origin", sa.Text),
        sa.Column("retry_of", sa.Integer),
        sa.Column("overrides", sa.Text),
        sa.Column("first_sent_at", sa.Text),
    )
