"""Commands sent as several copies: how many planned and sent, the delivery probability and
the bit-error rate they were chosen from, whether an acknowledgement was expected, and the
command that superseded this one."""

from __future__ import annotations

import sqlalchemy as sa

from backend.mission_log.migrating import REAL, add_missing

revision = "0002"
down_revision = "0001"


def upgrade() -> None:
    add_missing(
        "commands",
        sa.Column("copies", sa.Integer),
        sa.Column("copies_sent", sa.Integer, nullable=False, server_default=sa.text("0")),
        sa.Column("p_delivered", REAL, nullable=False, server_default=sa.text("0")),
        sa.Column("ber", REAL),
        sa.Column("two_way", sa.Integer),  # a boolean as 0/1, as SQLite keeps it
        sa.Column("superseded_by", sa.Integer),
    )
