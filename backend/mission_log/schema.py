"""The mission log's tables, and the columns added to an older log when it is opened."""

from __future__ import annotations

import sqlite3

#: The track: a point a second of the vehicle's clock (``backend.mission_log.track``). Its
#: position and heading are null in a point made from a status that said the navigation was not
#: valid (the vehicle sends no pose then: ``backend.dives``).
TRACK_TABLE = """
CREATE TABLE IF NOT EXISTS track (
    dive INTEGER NOT NULL REFERENCES dives(id),
    t_s REAL NOT NULL,
    x_m REAL,
    y_m REAL,
    z_m REAL,
    heading_deg REAL,
    depth_m REAL,
    speed_mps REAL,
    battery_pct REAL,
    mode TEXT,
    active TEXT,
    at TEXT,
    commanded_depth_m REAL,
    nav_valid INTEGER,
    nav_age_s REAL,
    vehicle TEXT
);
"""
TRACK_INDEX = "CREATE INDEX IF NOT EXISTS track_dive ON track(dive, t_s);\n"

_DIVES_AND_COMMANDS = """
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
    first_sent_at TEXT,
    vehicle TEXT
);
CREATE INDEX IF NOT EXISTS commands_dive ON commands(dive);
"""
_EVENTS = """
CREATE TABLE IF NOT EXISTS events (
    id INTEGER PRIMARY KEY,
    dive INTEGER NOT NULL REFERENCES dives(id),
    at TEXT NOT NULL,
    kind TEXT NOT NULL,
    detail TEXT NOT NULL,
    data TEXT,
    vehicle TEXT
);
CREATE INDEX IF NOT EXISTS events_dive ON events(dive);
"""
#: Every table of a new log.
SCHEMA = _DIVES_AND_COMMANDS + TRACK_TABLE + TRACK_INDEX + _EVENTS

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
    # issue 23: the fleet's vehicle a command is for (its name; null without a fleet)
    ("vehicle", "TEXT"),
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
    # issue 22: the rest of the status series (the depth the active command asks for, whether
    # the navigation was valid and its age); see also _track_position_nullable
    ("commanded_depth_m", "REAL"),
    ("nav_valid", "INTEGER"),
    ("nav_age_s", "REAL"),
    # issue 23: the fleet's vehicle the point is of (null without a fleet)
    ("vehicle", "TEXT"),
)
#: Columns of the events added since (issue 23: the fleet's vehicle an event concerns; null
#: without a fleet, or for the whole fleet, e.g. the operator's choice of the copies' BER).
ADDED_EVENT_COLUMNS = (("vehicle", "TEXT"),)
#: The track's position columns, NOT NULL before issue 22.
POSITION_COLUMNS = ("x_m", "y_m", "z_m", "heading_deg")


def create_or_migrate(db: sqlite3.Connection) -> None:
    """Create the tables a new log lacks, add the columns an older log lacks (values of old
    rows: the declared defaults), and let an older track's position be null."""
    db.executescript(SCHEMA)
    for table, added in (
        ("commands", ADDED_COLUMNS),
        ("track", ADDED_TRACK_COLUMNS),
        ("events", ADDED_EVENT_COLUMNS),
    ):
        have = {row[1] for row in db.execute(f"PRAGMA table_info({table})")}
        for name, declaration in added:
            if name not in have:
                db.execute(f"ALTER TABLE {table} ADD COLUMN {name} {declaration}")
    _track_position_nullable(db)


def _track_position_nullable(db: sqlite3.Connection) -> None:
    """An older log's track declared its position NOT NULL, which SQLite cannot drop: the table
    is made again as SQLite's documentation says (a new table, the rows copied in their order,
    the old one dropped, the new one renamed), in one transaction: a crash in between leaves the
    old table as it was, and the next opening does it again."""
    notnull = {row[1]: bool(row[3]) for row in db.execute("PRAGMA table_info(track)")}
    if not any(notnull.get(c) for c in POSITION_COLUMNS):
        return
    columns = ", ".join(notnull)  # every column the old table has (the added ones included)
    db.execute("BEGIN IMMEDIATE")
    try:
        db.execute(TRACK_TABLE.replace("IF NOT EXISTS track", "track_rebuilt"))
        db.execute(
            f"INSERT INTO track_rebuilt (rowid, {columns}) "
            f"SELECT rowid, {columns} FROM track ORDER BY rowid"
        )
        db.execute("DROP TABLE track")
        db.execute("ALTER TABLE track_rebuilt RENAME TO track")
        db.execute(TRACK_INDEX)
        db.execute("COMMIT")
    except BaseException:
        if db.in_transaction:
            db.execute("ROLLBACK")
        raise
