"""Issue 20 (the plots and the replay read the dive back from the log): each track point
keeps the status then (null where the vehicle did not say), the active command the vehicle
reported (JSON) and the station's clock when the point arrived."""

from __future__ import annotations

import sqlalchemy as sa

from backend.mission_log.migrating import REAL, add_missing

revision = "0005"
down_revision = "0004"


def upgrade() -> None:
    add_missing(
        "track",
        sa.Column("depth_m", REAL),
        sa.Column("speed_mps", REAL),
        sa.Column("battery_pct", REAL),
        sa.Column("mode", sa.Text),
        sa.Column("active", sa.Text),
        sa.Column("at", sa.Text),
    )
