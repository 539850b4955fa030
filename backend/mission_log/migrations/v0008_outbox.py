"""Issue 24, commands from a console without the transmitter (the relay): the ``outbox`` of
commands a console with no target of its own (``NEMESYS_TARGET=relay``: the shore) has checked
and hands to the console that holds the transmitter, and the ``transmitters`` those consoles
say they hold.

* ``outbox``: one row per relayed command, as the shore's operator asked for it (``pattern``,
  ``params`` as JSON text, ``override``, ``copies``, ``kind``, ``retry_of``, the shore's path
  ``origin``), from ``console`` and its ``operator``, for ``vehicle``; ``created_s`` on the
  database's clock (a row that waited too long is refused as stale). ``state``: ``waiting``,
  then ``taken`` (``command_id``: the record the transmitting console made, in the same
  transaction), ``refused`` (``status``: the HTTP status of the refusal, ``reason`` in words,
  ``detail``: the refusal's JSON, its limit violations) or ``withdrawn`` (the shore stopped
  waiting for an answer; nothing was sent); ``decided_by`` and ``decided_s`` say which console
  decided and when. The SQL is :mod:`backend.mission_log.outbox`.
* ``transmitters``: one row per console that holds a transmitter on a shared log: its
  ``target``, the health of its link as JSON (``health``) and ``seen_s``, refreshed every
  second on the database's clock; the shore's page shows "relay via <console>" from it.
* PostgreSQL only: the ``outbox`` tells every other console of a row written or decided
  (the 0007 trigger function, its key ``id``); ``transmitters`` is read when needed, not told.
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

from backend.mission_log.migrating import REAL, id_column

revision = "0008"
down_revision = "0007"


def upgrade() -> None:
    op.create_table(
        "outbox",
        id_column(),
        sa.Column("created_at", sa.Text, nullable=False),
        sa.Column("created_s", REAL, nullable=False),
        sa.Column("console", sa.Text, nullable=False),
        sa.Column("operator", sa.Text, nullable=False),
        sa.Column("vehicle", sa.Text, nullable=False),
        sa.Column("origin", sa.Text, nullable=False),
        sa.Column("kind", sa.Text, nullable=False),
        sa.Column("pattern", sa.Text, nullable=False),
        sa.Column("params", sa.Text, nullable=False),
        sa.Column("override", sa.Integer, nullable=False, server_default="0"),
        sa.Column("copies", sa.Integer),
        sa.Column("retry_of", sa.Integer),
        sa.Column("state", sa.Text, nullable=False, server_default="waiting"),
        sa.Column("command_id", sa.Integer, sa.ForeignKey("commands.id")),
        sa.Column("status", sa.Integer),
        sa.Column("reason", sa.Text),
        sa.Column("detail", sa.Text),
        sa.Column("decided_by", sa.Text),
        sa.Column("decided_s", REAL),
    )
    op.create_index("outbox_state", "outbox", ["state", "id"])
    op.create_table(
        "transmitters",
        sa.Column("console", sa.Text, primary_key=True),
        sa.Column("target", sa.Text, nullable=False),
        sa.Column("health", sa.Text, nullable=False),
        sa.Column("seen_s", REAL, nullable=False),
    )
    if op.get_bind().dialect.name != "postgresql":
        return
    op.execute("DROP TRIGGER IF EXISTS outbox_notify ON outbox")
    op.execute(
        "CREATE TRIGGER outbox_notify AFTER INSERT OR UPDATE ON outbox FOR EACH ROW "
        "EXECUTE FUNCTION nemesys_notify('id')"
    )
