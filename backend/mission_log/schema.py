"""The mission log's tables, and the columns added to an older log when it is opened."""

from __future__ import annotations

import sqlite3

SCHEMA = """
CREATE TABLE IF NOT EXISTS dives (
    id INTEGER PRIMARY KEY,
    started_at TEXT NOT NULL,
    target TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS commands (
    id INTEGER PRIMARY KEY,
    dive INTEGER NOT NULL REFERENCES dives(id),
    created_at TEXT NOT NULL,
    updated_at TEXT NOT NULL,
    operator TEXT NOT NULL,
    target TEXT NOT NULL,
    kind TEXT NOT NULL,
    pattern TEXT NOT NULL,
    pattern_id INTEGER NOT NULL,
    params TEXT NOT NULL,
    requested TEXT NOT NULL,
    bits TEXT NOT NULL,
    hex TEXT NOT NULL,
    state TEXT NOT NULL,
    attempts INTEGER NOT NULL DEFAULT 0,
    sent_at TEXT,
    acked_at TEXT,
    ack TEXT,
    reason TEXT,
    copies INTEGER,
    copies_sent INTEGER NOT NULL DEFAULT 0,
    p_delivered REAL NOT NULL DEFAULT 0,
    ber REAL,
    two_way INTEGER,
    superseded_by INTEGER,
    origin TEXT,
    retry_of INTEGER,
    overrides TEXT,
    first_sent_at TEXT
);
CREATE INDEX IF NOT EXISTS commands_dive ON commands(dive);
CREATE TABLE IF NOT EXISTS track (
    dive INTEGER NOT NULL REFERENCES dives(id),
    t_s REAL NOT NULL,
    x_m REAL NOT NULL,
    y_m REAL NOT NULL,
    z_m REAL NOT NULL,
    heading_deg REAL NOT NULL,
    depth_m REAL,
    speed_mps REAL,
    battery_pct REAL,
    mode TEXT,
    active TEXT,
    at TEXT
);
CREATE INDEX IF NOT EXISTS track_dive ON track(dive, t_s);
CREATE TABLE IF NOT EXISTS events (
    id INTEGER PRIMARY KEY,
    dive INTEGER NOT NULL REFERENCES dives(id),
    at TEXT NOT NULL,
    kind TEXT NOT NULL,
    detail TEXT NOT NULL,
    data TEXT
);
CREATE INDEX IF NOT EXISTS events_dive ON events(dive);
"""

#: Columns added since the first release: (name, declaration), added to an older log at open.
ADDED_COLUMNS = (
    ("copies", "INTEGER"),
    ("copies_sent", "INTEGER NOT NULL DEFAULT 0"),
    ("p_delivered", "REAL NOT NULL DEFAULT 0"),
    ("ber", "REAL"),
    ("two_way", "INTEGER"),
    ("superseded_by", "INTEGER"),
    # issue 19: the path a command came by, the command a retry retries, the operator's
    # overrides (JSON: who, which violations), the time its first copy left (wire order)
    ("origin", "TEXT"),
    ("retry_of", "INTEGER"),
    ("overrides", "TEXT"),
    ("first_sent_at", "TEXT"),
)
#: Columns of the track added since (issue 20: the plots and the replay read the dive back
#: from the log): the status at the point (null where the vehicle did not say), the active
#: command the vehicle reported (JSON), and the station's clock when the point arrived.
ADDED_TRACK_COLUMNS = (
    ("depth_m", "REAL"),
    ("speed_mps", "REAL"),
    ("battery_pct", "REAL"),
    ("mode", "TEXT"),
    ("active", "TEXT"),
    ("at", "TEXT"),
)


def create_or_migrate(db: sqlite3.Connection) -> None:
    """Create the tables a new log lacks, and add the columns an older log lacks (values of
    old rows: the declared defaults)."""
    db.executescript(SCHEMA)
    for table, added in (("commands", ADDED_COLUMNS), ("track", ADDED_TRACK_COLUMNS)):
        have = {row[1] for row in db.execute(f"PRAGMA table_info({table})")}
        for name, declaration in added:
            if name not in have:
                db.execute(f"ALTER TABLE {table} ADD COLUMN {name} {declaration}")
