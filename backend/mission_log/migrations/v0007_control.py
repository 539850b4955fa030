"""Issue 24 (several consoles on one log): who is in control of each vehicle, which console
wrote each command, and on PostgreSQL a notification at every commit that other consoles need
to see.

* ``control``: one row per vehicle (its name, an opaque key): the console and operator in
  control (null: nobody), an ``epoch`` that grows at every change of who is in control,
  whether the owner allows a takeover, since when (``since_s``) and its last heartbeat
  (``heartbeat_s``), both in seconds since 1970 on the database's clock, and the one request
  waiting for the owner's answer (``request_console``, ``request_operator``, ``request_s``).
  The SQL is :mod:`backend.mission_log.control`.
* ``commands.console``: the console that wrote the record (null: a record from before).
* PostgreSQL only: triggers that ``pg_notify('nemesys_log', ...)`` the row's key when a command
  is written, an event added or a vehicle's control changes (not a heartbeat alone). A trigger
  runs in the writing transaction, so the notification is delivered only when it commits, in
  commit order (PostgreSQL's ``NOTIFY``); the payload is the key, under 8000 bytes whatever
  the row: ``{"table": "commands", "id": 12, "console": "ship"}``. ``console`` is the writing
  session's ``nemesys.console`` setting (:meth:`backend.mission_log.store.MissionLog.
  name_console`; null for a session that did not set it). SQLite has one console: nothing to
  tell.
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

from backend.mission_log.migrating import REAL, add_missing

revision = "0007"
down_revision = "0006"

#: The channel every console listens on (:mod:`backend.mission_log.listen`).
CHANNEL = "nemesys_log"

NOTIFY_FUNCTION = f"""
CREATE OR REPLACE FUNCTION nemesys_notify() RETURNS trigger AS $$
BEGIN
  PERFORM pg_notify('{CHANNEL}', json_build_object(
    'table', TG_TABLE_NAME,
    'id', to_jsonb(NEW) -> TG_ARGV[0],
    'console', current_setting('nemesys.console', true))::text);
  RETURN NULL;
END
$$ LANGUAGE plpgsql
"""

#: (trigger, table, events, key column, condition).
TRIGGERS = (
    ("commands_notify", "commands", "INSERT OR UPDATE", "id", ""),
    ("events_notify", "events", "INSERT", "id", ""),
    (
        "control_notify",
        "control",
        "UPDATE",
        "vehicle",
        # a heartbeat alone is nobody else's news
        "WHEN (OLD.epoch IS DISTINCT FROM NEW.epoch "
        "OR OLD.console IS DISTINCT FROM NEW.console "
        "OR OLD.operator IS DISTINCT FROM NEW.operator "
        "OR OLD.takeover_allowed IS DISTINCT FROM NEW.takeover_allowed "
        "OR OLD.request_console IS DISTINCT FROM NEW.request_console "
        "OR OLD.request_s IS DISTINCT FROM NEW.request_s)",
    ),
)


def upgrade() -> None:
    op.create_table(
        "control",
        sa.Column("vehicle", sa.Text, primary_key=True),
        sa.Column("console", sa.Text),
        sa.Column("operator", sa.Text),
        sa.Column("epoch", sa.Integer, nullable=False, server_default="0"),
        sa.Column("takeover_allowed", sa.Integer, nullable=False, server_default="0"),
        sa.Column("since_s", REAL),
        sa.Column("heartbeat_s", REAL),
        sa.Column("request_console", sa.Text),
        sa.Column("request_operator", sa.Text),
        sa.Column("request_s", REAL),
        if_not_exists=True,
    )
    add_missing("commands", sa.Column("console", sa.Text))
    if op.get_bind().dialect.name != "postgresql":
        return
    op.execute(NOTIFY_FUNCTION)
    for name, table, events, key, when in TRIGGERS:
        op.execute(f"DROP TRIGGER IF EXISTS {name} ON {table}")
        op.execute(
            f"CREATE TRIGGER {name} AFTER {events} ON {table} FOR EACH ROW {when} "
            f"EXECUTE FUNCTION nemesys_notify('{key}')"
        )
