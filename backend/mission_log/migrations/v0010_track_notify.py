"""Issue 24 (a shore console following the mission): on PostgreSQL, the track's points told
to the other consoles as the console that hears the vehicle writes them, so that a console
without a transmitter (``NEMESYS_TARGET=relay``) shows where the vehicle is
(:mod:`backend.relay.telemetry`).

The track is written in batches (:mod:`backend.mission_log.track`: a commit of up to
:data:`~backend.mission_log.track.TRACK_BATCH` points within
:data:`~backend.mission_log.track.TRACK_FLUSH_S`) and has no key of its own, so the trigger
tells the batch's dive, not a row: migration 0007's ``nemesys_notify('dive')`` for each row
inserted, whose payloads (``{"table": "track", "id": <dive>, "console": "ship"}``) are the same
for every row of a batch, and PostgreSQL delivers identical notifications of one transaction
once: one notification per batch (per dive in it), at its commit. The listening console reads
the dive's newest point. SQLite has one console: nothing to tell.
"""

from __future__ import annotations

from alembic import op

revision = "0010"
down_revision = "0009"


def upgrade() -> None:
    if op.get_bind().dialect.name != "postgresql":
        return
    op.execute("DROP TRIGGER IF EXISTS track_notify ON track")
    op.execute(
        "CREATE TRIGGER track_notify AFTER INSERT ON track FOR EACH ROW "
        "EXECUTE FUNCTION nemesys_notify('dive')"
    )
