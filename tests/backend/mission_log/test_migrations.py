"""The mission log's one migration history (Alembic, backend/mission_log/migrations/): older
SQLite logs (the first release's format, and the previous versions', migrated by columns added
at open and with no migration version) are brought to the newest migration at open with their
rows; on both back-ends (``log_backend``) a new log's track has the columns the previous
version declared, a migration failing half-way leaves no table behind, and a log a newer
console migrated is refused unchanged."""

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
#: Issue 20's tables, written out (``git show 1a02d10:backend/mission_log/schema.py``, its
#: ``SCHEMA``): every column, made and completed by ``create_or_migrate`` at open, and no
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
#: Issue 22's track (``git show fefcc4b:backend/mission_log/schema.py``, its ``TRACK_TABLE``):
#: the position nullable (a status point while the navigation is not valid), three columns more.
ISSUE_22_TRACK = """
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
    nav_age_s REAL
);
"""
_ISSUE_20_TRACK = PREVIOUS_SCHEMA[
    PREVIOUS_SCHEMA.index("CREATE TABLE IF NOT EXISTS track") : PREVIOUS_SCHEMA.index(
        "CREATE INDEX IF NOT EXISTS track_dive"
    )
]
#: Issue 20's dives and track alone (an older log, for the exports' tests).
ISSUE_20_TRACK = (
    PREVIOUS_SCHEMA[: PREVIOUS_SCHEMA.index("CREATE TABLE IF NOT EXISTS commands")]
    + _ISSUE_20_TRACK
    + "CREATE INDEX IF NOT EXISTS track_dive ON track(dive, t_s);\n"
)
#: The version before the migrations (issue 22's ``create_or_migrate``): issue 20's tables with
#: issue 22's track.
ISSUE_22_SCHEMA = PREVIOUS_SCHEMA.replace(_ISSUE_20_TRACK, ISSUE_22_TRACK.lstrip())


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


@pytest.mark.parametrize("version", ["issue 20", "issue 22"])
def test_a_log_of_a_previous_version_is_stamped_and_keeps_its_rows(
    tmp_path: Path, version: str
) -> None:
    """Logs ``create_or_migrate`` made (no migration version): issue 22's is only stamped, not
    a table changed; issue 20's track is made again by 0006 (its position nullable, three
    columns more) with its rows, every other table unchanged."""
    db = tmp_path / "previous.sqlite3"
    fields = command_fields()
    with sqlite3.connect(db) as raw:
        raw.executescript(PREVIOUS_SCHEMA if version == "issue 20" else ISSUE_22_SCHEMA)
        raw.execute("INSERT INTO dives VALUES (1, '2026-01-01T10:00:00.000+00:00', 'sim')")
        raw.execute(
            "INSERT INTO commands (dive, created_at, updated_at, operator, target, kind, pattern, "
            "pattern_id, params, requested, bits, hex, state, copies, origin, first_sent_at) "
            "VALUES (1, 't0', 't1', 'operator', 'sim', 'command', ?, ?, '{}', '{}', ?, ?, "
            "'acknowledged', 3, 'api', 't0')",
            (fields["pattern"], fields["pattern_id"], fields["bits"], fields["hex"]),
        )
        raw.execute("INSERT INTO events (dive, at, kind, detail) VALUES (1, 't2', 'datum', 'x')")
        for t_s in (1.5, 0.5):
            raw.execute(
                "INSERT INTO track (dive, t_s, x_m, y_m, z_m, heading_deg, depth_m, mode, at) "
                "VALUES (1, ?, 1, 2, 3, 90, 2.5, 'auto', 't1')",
                (t_s,),
            )
    raw.close()
    before = table_sql(db)

    MissionLog(db).close()

    after = table_sql(db)
    rebuilt = {"track", "track_dive"} if version == "issue 20" else set()
    # 0007 (issue 24) adds the console that wrote a command, and the control table; 0008 the
    # relay's outbox (and its index) and transmitters; 0009 (issue 23) the fleet's vehicle of
    # a command, a track point and an event
    grown = {"commands", "events", "track"}
    kept = {name: sql for name, sql in before.items() if name not in rebuilt | grown}
    assert {name: after[name] for name in kept} == kept  # not a column added or changed
    assert after["commands"].startswith(before["commands"].rstrip(")"))
    assert after["commands"].endswith("console TEXT, vehicle TEXT)")
    assert after["events"] == before["events"].rstrip(")") + ", vehicle TEXT)"
    assert set(after) - set(before) == {
        "alembic_version",
        "control",
        "outbox",
        "outbox_state",
        "transmitters",
    }
    assert track_columns(db) == {**declared(ISSUE_22_TRACK), "vehicle": ("TEXT", True)}
    log = MissionLog(db)
    try:
        (rec,) = log.commands()
        assert rec["state"] == "acknowledged" and rec["copies"] == 3 and rec["origin"] == "api"
        assert rec["hex"] == fields["hex"]
        assert [e["kind"] for e in log.events()] == ["datum"]
        point = log.track_rows(1)[1]
        assert point["depth_m"] == 2.5 and point["mode"] == "auto" and point["t_s"] == 1.5
        assert point["nav_valid"] is None and point["commanded_depth_m"] is None
    finally:
        log.close()
    with sqlite3.connect(db) as raw:
        assert raw.execute("SELECT version_num FROM alembic_version").fetchall() == [(head(),)]
        assert raw.execute("SELECT t_s FROM track ORDER BY rowid").fetchall() == [(1.5,), (0.5,)]
    raw.close()


#: A declared column type as each back-end names it.
TYPE_NAMES = {
    "sqlite": {"REAL": "REAL", "INTEGER": "INTEGER", "TEXT": "TEXT"},
    "postgresql": {"REAL": "double precision", "INTEGER": "integer", "TEXT": "text"},
}


def declared(create_table: str, kind: str = "sqlite") -> dict[str, tuple[str, bool]]:
    """``name: (type, nullable)`` of each column ``create_table`` declares."""
    out = {}
    for line in create_table.strip().splitlines()[1:-1]:
        name, decl, *rest = line.strip().rstrip(",").split()
        out[name] = (TYPE_NAMES[kind][decl], "NOT NULL" not in " ".join(rest))
    return out


def track_columns(db: Path) -> dict[str, tuple[str, bool]]:
    with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as raw:
        rows = raw.execute("PRAGMA table_info(track)").fetchall()
    raw.close()
    return {str(r[1]): (str(r[2]), not r[3]) for r in rows}


def test_a_new_logs_track_has_the_columns_the_previous_version_declared(
    log_backend: LogBackend,
) -> None:
    """0001..0006 make the track issue 22's ``TRACK_TABLE`` declared (the same columns,
    types and nullability, in its order), with its index; 0009 adds the fleet's vehicle."""
    log_backend.open().close()
    if log_backend.postgres:
        rows = log_backend.query(
            "SELECT column_name, data_type, is_nullable FROM information_schema.columns "
            "WHERE table_schema = current_schema() AND table_name = 'track' "
            "ORDER BY ordinal_position"
        )
        columns = {str(name): (str(kind), nullable == "YES") for name, kind, nullable in rows}
        index = log_backend.query("SELECT indexdef FROM pg_indexes WHERE indexname = 'track_dive'")
        assert [r[0] for r in index] == [
            "CREATE INDEX track_dive ON public.track USING btree (dive, t_s)"
        ]
    else:
        columns = track_columns(log_backend.path)
        assert log_backend.query("PRAGMA index_info(track_dive)") == [(0, 0, "dive"), (1, 1, "t_s")]
    expected = declared(ISSUE_22_TRACK, log_backend.kind)
    expected["vehicle"] = (TYPE_NAMES[log_backend.kind]["TEXT"], True)
    assert list(columns.items()) == list(expected.items())


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
