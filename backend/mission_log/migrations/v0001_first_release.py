"""The first release's log: dives, commands (their lifecycle, the frame, the acknowledgement)
and the track (positions only).

Created where missing: a log from before the migrations has them already.
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

from backend.mission_log.migrating import REAL, id_column

revision = "0001"
down_revision: str | None = None


def upgrade() -> None:
    op.create_table(
        "dives",
        id_column(),
        sa.Column("started_at", sa.Text, nullable=False),
        sa.Column("target", sa.Text, nullable=False),
        if_not_exists=True,
    )
    op.create_table(
        "commands",
        id_column(),
        sa.Column("dive", sa.Integer, sa.ForeignKey("dives.id"), nullable=False),
        *(
            sa.Column(name, sa.Text, nullable=False)
            for name in ("created_at", "updated_at", "operator", "target", "kind", "pattern")
        ),
        sa.Column("pattern_id", sa.Integer, nullable=False),
        *(
            sa.Column(name, sa.Text, nullable=False)
            for name in ("params", "requested", "bits", "hex", "state")
        ),
        sa.Column("attempts", sa.Integer, nullable=False, server_default=sa.text("0")),
        *(sa.Column(name, sa.Text) for name in ("sent_at", "acked_at", "ack", "reason")),
        if_not_exists=True,
    )
    op.create_index("commands_dive", "commands", ["dive"], if_not_exists=True)
    op.create_table(
        "track",
        sa.Column("dive", sa.Integer, sa.ForeignKey("dives.id"), nullable=False),
        *(
            sa.Column(name, REAL, nullable=False)
            for name in ("t_s", "x_m", "y_m", "z_m", "heading_deg")
        ),
        if_not_exists=True,
    )
    op.create_index("track_dive", "track", ["dive", "t_s"], if_not_exists=True)
