"""Recovery of what a stopped console left on its way: ``MissionLog.recover_interrupted`` on
every state, and end to end a SIGKILLed ``nemesys console`` on a one-way TCP link whose
transmitted command is interrupted at the next start and retried to ``sent``, its frames
decoded on the loopback listener: both on SQLite and on PostgreSQL (``log_backend``). Older
SQLite logs (the first release's format, and the previous version's, migrated by columns
added at open and with no migration version) are brought to the newest migration at open."""

from __future__ import annotations

import re
import sqlite3
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from backend.commands.lifecycle import ON_ITS_WAY, State
from backend.mission_log.migrating import head
from backend.mission_log.store import MissionLog
from bench._gateway import FrameGateway
from bench._server import ConsoleProcess, start_console
from tests.backend.conftest import CIRCLE, TOKEN, clear_nemesys_env, command_fields, wait_until
from tests.backend.log_backend import LogBackend

#: `nemesys console` subprocesses, killed and restarted: make test, not make test-fast.
pytestmark = pytest.mark.slow

AUTH = {"Authorization": f"Bearer {TOKEN}"}
#: The line ``nemesys console`` prints when it recovered records (before its URL).
RECOVERED_LINE = re.compile(
    r"^(\d+) commands? an earlier run left queued or transmitted (?:is|are) now interrupted",
    re.M,
)
URL_LINE = re.compile(r"^\s*http://\S+/\?token=", re.M)

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


# --- (a) the log's recovery --------------------------------------------------------------


def test_recovery_interrupts_exactly_what_was_on_its_way(log_backend: LogBackend) -> None:
    log = log_backend.open()
    try:
        dive = log.new_dive("tcp://127.0.0.1:9")
        ids: dict[State, int] = {}
        for i, state in enumerate(State):
            rec = log.insert_command(
                dive, {**command_fields("circle", **{**CIRCLE, "radius": 3.0 + i}), "copies": 3}
            )
            ids[state] = rec["id"]
            if state != State.QUEUED:
                log.update_command(rec["id"], state=state, reason=f"was {state}", attempts=1)
        before = {s: log.command(cid) for s, cid in ids.items()}
        last = max(r["updated_at"] for r in before.values() if r is not None)

        assert log.recover_interrupted() == len(ON_ITS_WAY) == 2

        for state, cid in ids.items():
            got, old = log.command(cid), before[state]
            assert got is not None and old is not None
            if state in ON_ITS_WAY:
                assert got["state"] == "interrupted", state
                assert got["reason"] == (
                    f"the console stopped while this command was {state} (the log was last "
                    f"written at {last}); whether the vehicle received it is not known"
                )
                assert got["updated_at"] >= last
                assert all(
                    got[k] == old[k] for k in old if k not in ("state", "reason", "updated_at")
                )
            else:
                assert got == old, state  # terminal: untouched, to the field
        assert log.recover_interrupted() == 0  # idempotent
        assert [r["state"] for r in log.commands(state="interrupted")] == ["interrupted"] * 3
    finally:
        log.close()


def test_recovery_of_an_empty_log_is_nothing(log_backend: LogBackend) -> None:
    log = log_backend.open()
    try:
        assert log.recover_interrupted() == 0
    finally:
        log.close()


# --- (b) an old-format log ----------------------------------------------------------------


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


# --- (c) end to end: SIGKILL, restart, retry ---------------------------------------------


@pytest.fixture
def listener() -> Iterator[FrameGateway]:
    server = FrameGateway()
    yield server
    server.close()


@pytest.fixture
def start_server(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    listener: FrameGateway,
    log_backend: LogBackend,
) -> Iterator[Callable[[], ConsoleProcess]]:
    """``nemesys console`` on a one-way TCP link to ``listener``, copies 0.5 s apart, its log
    on ``log_backend``."""
    clear_nemesys_env(monkeypatch)
    servers: list[ConsoleProcess] = []

    def start() -> ConsoleProcess:
        server = start_console(
            tmp_path / f"console-{len(servers)}.log",
            TOKEN,
            *log_backend.console_args(),
            *("--target", f"tcp://127.0.0.1:{listener.port}"),
            env={
                "NEMESYS_COPY_INTERVAL_S": "0.5",
                "NO_PROXY": "127.0.0.1,localhost",
                **log_backend.console_env(),
            },
        )
        servers.append(server)
        assert server.host == "127.0.0.1"
        return server

    yield start
    for server in servers:
        server.stop(timeout_s=10)


def get(c: httpx.Client, command_id: int) -> dict[str, Any]:
    r = c.get(f"/api/commands/{command_id}")
    assert r.status_code == 200, r.text
    rec: dict[str, Any] = r.json()
    return rec


def test_a_killed_console_interrupts_and_retries_on_restart(
    start_server: Callable[[], ConsoleProcess], listener: FrameGateway, log_backend: LogBackend
) -> None:
    first = start_server()
    with first.client() as c:
        r = c.post(
            "/api/commands",
            json={"pattern": "circle", "params": CIRCLE, "copies": 20},
            headers=AUTH,
        )
        assert r.status_code == 202, r.text
        cmd = r.json()
        assert cmd["state"] == "queued" and cmd["copies"] == 20
        on_way = wait_until(
            lambda: (
                (rec := get(c, cmd["id"]))["state"] == "transmitted"
                and rec["copies_sent"] >= 1
                and rec
            ),
            timeout_s=10.0,
            what="the command transmitted, one copy out",
        )
        assert on_way["copies_sent"] < 20  # 20 copies 0.5 s apart: still going out
    first.kill()
    wait_until(lambda: listener.closed == 1, what="the killed console's connection closed")
    before_kill = listener.frames(0)
    assert before_kill and set(before_kill) == {cmd["hex"]}
    # as the kill left it, read over a connection of its own
    assert log_backend.query("SELECT state FROM commands WHERE id = ?", (cmd["id"],)) == [
        ("transmitted",)
    ]

    second = start_server()
    printed = second.log_path.read_text()
    recovered, url = RECOVERED_LINE.search(printed), URL_LINE.search(printed)
    assert recovered is not None and url is not None, printed
    assert recovered.group(1) == "1"
    assert recovered.start() < url.start()  # the recovery is done before the URL is shown
    with second.client() as c:
        rows = c.get("/api/commands").json()
        assert [r["id"] for r in rows] == [cmd["id"]]
        assert not [r for r in rows if r["state"] in ("queued", "transmitted")]
        rec = get(c, cmd["id"])
        assert rec["state"] == "interrupted"
        assert rec["reason"].startswith("the console stopped while this command was transmitted")
        assert rec["copies_sent"] >= 1 and rec["attempts"] == rec["copies_sent"]

        r = c.post(f"/api/commands/{cmd['id']}/retry", json={"copies": 2}, headers=AUTH)
        assert r.status_code == 202, r.text
        retried = r.json()
        assert retried["state"] == "queued" and retried["retry_of"] == cmd["id"]
        done = wait_until(
            lambda: (
                (got := get(c, retried["id"]))["state"] not in ("queued", "transmitted") and got
            ),
            timeout_s=10.0,
            what="the retry ended",
        )
        assert get(c, cmd["id"]) == rec  # the interrupted record stays as it was
    assert done["state"] == "sent", done
    assert done["attempts"] == 2 and done["copies_sent"] == 2
    assert done["reason"] is None and done["hex"] == cmd["hex"]
    # the listener got the retry's two copies on the restarted console's connection
    assert listener.connections == 2 and not listener.rejected
    assert listener.frames(1) == [cmd["hex"]] * 2
