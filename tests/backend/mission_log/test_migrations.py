"""The mission log's one migration history (Alembic, backend/mission_log/migrations/): older
SQLite logs (the first release's format, and the previous version's, migrated by columns added
at open and with no migration version) are brought to the newest migration at open with their
rows; on both back-ends (``log_backend``) a migration failing half-way leaves no table behind,
and a log a newer console migrated is refused unchanged."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest

from backend.mission_log.migrating import head
from backend.mission_log.store import MissionLog
from tests.backend.conftest import CIRCLE, command_fields
from tests.backend.log_backend import LogBackend

#: The ``commands`` table before copies, copies_sent, p_delivered, ber, two_way and
#: superseded_by (``git show HEAD~3:backend/mission_log/store.py``), written out: the old format.
OLD_SCHEMA = """
CREATE TABLE dives (
    id INTEGER PRIMARY KEY,
    started_at TEXT NOT NULL,
    target TEXT NOT NULL
);
CREATE TABLE commands (
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
    reason TEXT
);
CREATE INDEX commands_dive ON commands(dive);
CREATE TABLE track (
    dive INTEGER NOT NULL REFERENCES dives(id),
    t_s REAL NOT NULL,
    x_m REAL NOT NULL,
    y_m REAL NOT NULL,
    z_m REAL NOT NULL,
    heading_deg REAL NOT NULL
);
CREATE INDEX track_dive ON track(dive, t_s);
"""
NEW_COLUMNS = ("copies", "copies_sent", "p_delivered", "ber", "two_way", "superseded_by")
#: The previous version's tables, written out (``git show 1a02d10:backend/mission_log/schema.py``,
#: its ``SCHEMA``): every column, made and completed by ``create_or_migrate`` at open, and no
#: migration version.
PREVIOUS_SCHEMA = """
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


def test_an_old_format_log_is_migrated_and_readable(tmp_path: Path) -> None:
    db = tmp_path / "old.sqlite3"
    old = command_fields()
    with sqlite3.connect(db) as raw:
        raw.executescript(OLD_SCHEMA)
        raw.execute("INSERT INTO dives VALUES (1, '2024-05-01T10:00:00.000+00:00', 'sim')")
        for cid, state, ack in (
            (1, "acknowledged", '{"outcome": "accepted", "corrected_bits": 0}'),
            (2, "transmitted", None),
        ):
            raw.execute(
                "INSERT INTO commands (id, dive, created_at, updated_at, operator, target, kind, "
                "pattern, pattern_id, params, requested, bits, hex, state, attempts, sent_at, "
                "ack) VALUES (?, 1, ?, ?, 'operator', 'sim', 'command', ?, ?, ?, ?, ?, ?, ?, 1, "
                "?, ?)",
                (
                    cid,
                    f"2024-05-01T10:0{cid}:00.000+00:00",
                    f"2024-05-01T10:0{cid}:01.000+00:00",
                    old["pattern"],
                    old["pattern_id"],
                    '{"speed": 0.18, "depth": 3, "radius": 5.0, "direction": "cw"}',
                    '{"radius": 5.0}',
                    old["bits"],
                    old["hex"],
                    state,
                    f"2024-05-01T10:0{cid}:00.500+00:00",
                    ack,
                ),
            )
    raw.close()

    log = MissionLog(db)
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as raw:
            columns = {r[1] for r in raw.execute("PRAGMA table_info(commands)")}
        raw.close()
        assert set(NEW_COLUMNS) <= columns
        acked = log.command(1)
        assert acked is not None
        assert acked["state"] == "acknowledged" and acked["ack"]["outcome"] == "accepted"
        assert acked["params"]["radius"] == 5.0 and acked["hex"] == old["hex"]
        assert acked["attempts"] == 1 and acked["sent_at"] == "2024-05-01T10:01:00.500+00:00"
        # the declared defaults for what the old format did not record
        assert acked["copies"] is None and acked["ber"] is None and acked["two_way"] is None
        assert acked["copies_sent"] == 0 and acked["p_delivered"] == 0
        assert acked["superseded_by"] is None
        assert log.events() == []  # a table the first release did not have
        assert [r["id"] for r in log.commands()] == [2, 1]
        # the old run left command 2 transmitted: recovered like any other
        assert log.recover_interrupted() == 1
        got = log.command(2)
        assert got is not None and got["state"] == "interrupted"
        assert "(the log was last written at 2024-05-01T10:02:01.000+00:00)" in got["reason"]
        # new records use the new columns
        new = log.insert_command(
            1,
            {
                **command_fields("circle", **{**CIRCLE, "radius": 4.0}),
                "copies": 5,
                "two_way": False,
            },
        )
        assert new["copies"] == 5 and new["two_way"] is False and new["copies_sent"] == 0
    finally:
        log.close()
    MissionLog(db).close()  # opening a migrated log again changes nothing and does not fail
    with sqlite3.connect(db) as raw:
        assert raw.execute("SELECT version_num FROM alembic_version").fetchall() == [(head(),)]
    raw.close()


def table_sql(db: Path) -> dict[str, str]:
    with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as raw:
        rows = raw.execute("SELECT name, sql FROM sqlite_master WHERE sql IS NOT NULL").fetchall()
    raw.close()
    return dict(rows)


def test_a_log_of_the_previous_version_is_stamped_and_keeps_its_rows(tmp_path: Path) -> None:
    db = tmp_path / "previous.sqlite3"
    fields = command_fields()
    with sqlite3.connect(db) as raw:
        raw.executescript(PREVIOUS_SCHEMA)
        raw.execute("INSERT INTO dives VALUES (1, '2026-01-01T10:00:00.000+00:00', 'sim')")
        raw.execute(
            "INSERT INTO commands (dive, created_at, updated_at, operator, target, kind, pattern, "
            "pattern_id, params, requested, bits, hex, state, copies, origin, first_sent_at) "
            "VALUES (1, 't0', 't1', 'operator', 'sim', 'command', ?, ?, '{}', '{}', ?, ?, "
            "'acknowledged', 3, 'api', 't0')",
            (fields["pattern"], fields["pattern_id"], fields["bits"], fields["hex"]),
        )
        raw.execute("INSERT INTO events (dive, at, kind, detail) VALUES (1, 't2', 'datum', 'x')")
        raw.execute(
            "INSERT INTO track (dive, t_s, x_m, y_m, z_m, heading_deg, depth_m, mode, at) "
            "VALUES (1, 1.5, 1, 2, 3, 90, 2.5, 'auto', 't1')"
        )
    raw.close()
    before = table_sql(db)

    MissionLog(db).close()

    after = table_sql(db)
    assert {name: after[name] for name in before} == before  # not a column added or changed
    assert set(after) - set(before) == {"alembic_version"}
    log = MissionLog(db)
    try:
        (rec,) = log.commands()
        assert rec["state"] == "acknowledged" and rec["copies"] == 3 and rec["origin"] == "api"
        assert rec["hex"] == fields["hex"]
        assert [e["kind"] for e in log.events()] == ["datum"]
        (point,) = log.track_rows(1)
        assert point["depth_m"] == 2.5 and point["mode"] == "auto" and point["t_s"] == 1.5
    finally:
        log.close()
    with sqlite3.connect(db) as raw:
        assert raw.execute("SELECT version_num FROM alembic_version").fetchall() == [(head(),)]
    raw.close()


def test_a_migration_that_fails_leaves_the_log_as_it_was(
    log_backend: LogBackend, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The migrations run in one transaction: a console killed (here: a step raising) after
    some of them leaves no table and no version behind, and the next open does them all."""
    from backend.mission_log.migrating import scripts

    step = scripts().get_revision("0004")
    assert step is not None

    def dies() -> None:
        raise RuntimeError("the console dies half-way through the migrations")

    monkeypatch.setattr(step.module, "upgrade", dies)
    with pytest.raises(RuntimeError, match="half-way"):
        log_backend.open()
    tables = (
        "SELECT COUNT(*) FROM sqlite_master WHERE type = 'table'"
        if log_backend.kind == "sqlite"
        else "SELECT COUNT(*) FROM information_schema.tables WHERE table_schema = 'public'"
    )
    assert log_backend.scalar(tables) == 0  # 0001-0003 ran, and were rolled back
    monkeypatch.undo()
    log = log_backend.open()
    try:
        assert log.new_dive("sim") == 1 and log.events() == []
    finally:
        log.close()
    assert log_backend.query("SELECT version_num FROM alembic_version") == [(head(),)]


def test_a_log_a_newer_console_migrated_is_refused_unchanged(log_backend: LogBackend) -> None:
    """Consoles of two versions on one database: the older one does not start on a log the
    newer migrated past what it knows (one line naming the log, the password masked), and
    changes nothing."""
    from backend.mission_log.opening import LogTooNew, open_checked

    log_backend.open().close()
    newer = "9999"
    conn = log_backend.open()
    with conn.transaction():
        conn._db.execute("UPDATE alembic_version SET version_num = ?", (newer,))
    conn.close()
    with pytest.raises(LogTooNew) as refused:
        open_checked(log_backend.where)
    message = str(refused.value)
    assert f"migration {newer}; this console knows up to {head()}" in message
    assert "run the newer console" in message
    if log_backend.postgres:
        assert ":***@" in message and log_backend.url not in message
    assert log_backend.query("SELECT version_num FROM alembic_version") == [(newer,)]
