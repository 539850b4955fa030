"""The mission log, on SQLite and on PostgreSQL (``log_backend``): commands inserted, updated
field by field, filtered and ordered; JSON columns; tracks in batches; dives; the CSV export;
persistence across reopening; the tables at the newest migration."""

from __future__ import annotations

import csv
import io
import json
import sqlite3
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from backend.mission_log.export import csv_rows
from backend.mission_log.migrating import head
from backend.mission_log.store import FINAL_STATES, STATES, LogWriteError, MissionLog, now_iso
from tests.backend.conftest import SQUARE, command_fields
from tests.backend.log_backend import LogBackend

#: The export's columns, written out: the contract (not imported from the store).
CSV_HEADER = [
    "id",
    "dive",
    "created_at",
    "operator",
    "target",
    "kind",
    "pattern",
    "params",
    "hex",
    "bits",
    "state",
    "attempts",
    "sent_at",
    "acked_at",
    "reason",
    "copies",
    "copies_sent",
    "p_delivered",
    "superseded_by",
    "corrected_bits",
    "decode_latency_ms",
    "replan_latency_ms",
]


ACK: dict[str, Any] = {
    "outcome": "accepted",
    "corrected_bits": 1,
    "decode_latency_ms": 0.25,
    "replan_latency_ms": 1.5,
    "from": {"x_m": 1.0, "y_m": -2.0, "z_m": 2.0},
    "active": {"pattern": "circle", "params": {"radius": 5.0}},
    "waypoints": [1, 2, 3],
}


@pytest.fixture
def log(log_backend: LogBackend) -> Iterator[MissionLog]:
    opened = log_backend.open()
    yield opened
    opened.close()


def test_now_iso_is_utc_with_milliseconds() -> None:
    stamp = now_iso()
    assert stamp.endswith("+00:00")
    assert len(stamp.split(".")[1]) == len("123+00:00")


def test_opening_creates_the_folder_and_uses_wal(tmp_path: Path) -> None:
    db = tmp_path / "log" / "missions.sqlite3"
    log = MissionLog(db)
    try:
        assert db.exists() and log.kind == "sqlite"
        with sqlite3.connect(db) as raw:
            assert raw.execute("PRAGMA journal_mode").fetchone() == ("wal",)
        assert log.commands() == [] and log.dives() == []
    finally:
        log.close()


def test_opening_makes_the_tables_of_the_newest_migration(
    log_backend: LogBackend, log: MissionLog
) -> None:
    assert log.kind == log_backend.kind
    assert log_backend.query("SELECT version_num FROM alembic_version") == [(head(),)]
    tables = (
        "SELECT name FROM sqlite_master WHERE type = 'table'"
        if log_backend.kind == "sqlite"
        else "SELECT table_name FROM information_schema.tables WHERE table_schema = 'public'"
    )
    names = {row[0] for row in log_backend.query(tables)}
    assert {"dives", "commands", "track", "events", "alembic_version"} <= names
    assert log.commands() == [] and log.dives() == [] and log.events() == []
    log.close()
    again = log_backend.open()  # at the newest already: nothing to do, nothing changed
    try:
        assert log_backend.query("SELECT version_num FROM alembic_version") == [(head(),)]
    finally:
        again.close()


def test_insert_is_queued_with_its_fields(log: MissionLog) -> None:
    dive = log.new_dive("sim")
    fields = command_fields()
    rec = log.insert_command(dive, fields)
    assert rec["id"] == 1 and rec["dive"] == dive
    assert rec["state"] == "queued" and rec["attempts"] == 0
    assert rec["created_at"] == rec["updated_at"]
    for key, value in fields.items():
        assert rec[key] == value, key
    assert rec["sent_at"] is None and rec["acked_at"] is None
    assert rec["ack"] is None and rec["reason"] is None
    assert log.command(rec["id"]) == rec
    assert log.command(99) is None


def test_insert_needs_an_existing_dive(log: MissionLog, log_backend: LogBackend) -> None:
    with pytest.raises(log_backend.integrity_error):
        log.insert_command(42, command_fields())
    assert log.commands() == []


def test_update_sets_fields_and_the_update_time(log: MissionLog) -> None:
    dive = log.new_dive("sim")
    rec = log.insert_command(dive, command_fields())
    sent = now_iso()
    rec2 = log.update_command(rec["id"], state="transmitted", attempts=1, sent_at=sent)
    assert rec2["state"] == "transmitted" and rec2["attempts"] == 1 and rec2["sent_at"] == sent
    assert rec2["updated_at"] >= rec["updated_at"]
    assert rec2["created_at"] == rec["created_at"]
    rec3 = log.update_command(rec["id"], state="acknowledged", acked_at=now_iso(), ack=ACK)
    assert rec3["ack"] == ACK  # JSON round trip, nested
    assert rec3["attempts"] == 1  # untouched fields stay
    rec4 = log.update_command(rec["id"], state="rejected", reason="limit_violation: speed")
    assert rec4["reason"] == "limit_violation: speed"
    rec5 = log.update_command(rec["id"], reason=None, ack=None)
    assert rec5["reason"] is None and rec5["ack"] is None
    assert log.command(rec["id"]) == rec5


@pytest.mark.parametrize(
    "fields",
    [
        {"pattern": "square"},
        {"id": 7},
        {"dive": 2},
        {"created_at": "x"},
        {"hex": "00"},
        {"state": "queued", "bits": "0"},
    ],
)
def test_update_refuses_columns_that_cannot_change(log: MissionLog, fields: dict[str, Any]) -> None:
    rec = log.insert_command(log.new_dive("sim"), command_fields())
    with pytest.raises(ValueError, match="cannot update"):
        log.update_command(rec["id"], **fields)
    assert log.command(rec["id"]) == rec


@pytest.mark.parametrize("state", ["lost", "ACKNOWLEDGED", "", "done"])
def test_update_refuses_unknown_states(log: MissionLog, state: str) -> None:
    rec = log.insert_command(log.new_dive("sim"), command_fields())
    with pytest.raises(ValueError, match="unknown state"):
        log.update_command(rec["id"], state=state)
    assert log.command(rec["id"]) == rec


def test_every_state_is_accepted(log: MissionLog) -> None:
    rec = log.insert_command(log.new_dive("sim"), command_fields())
    for state in STATES:
        assert log.update_command(rec["id"], state=state)["state"] == state
    assert set(STATES) > FINAL_STATES
    assert {"queued", "transmitted"}.isdisjoint(FINAL_STATES)


def test_update_of_an_unknown_command_is_a_key_error(log: MissionLog) -> None:
    with pytest.raises(KeyError):
        log.update_command(5, state="failed")


def test_json_columns_round_trip(log: MissionLog, log_backend: LogBackend) -> None:
    dive = log.new_dive("sim")
    fields = command_fields()
    fields["requested"] = {"speed": 0.18, "depth": 3, "radius": 5.1, "direction": "cw", "x": None}
    rec = log.insert_command(dive, fields)
    assert rec["params"] == fields["params"] and isinstance(rec["params"], dict)
    assert rec["requested"] == fields["requested"]
    assert isinstance(rec["params"]["speed"], float)
    assert rec["params"]["direction"] == "cw"
    ack = {"unicode": "µ ≥ 1°", "nested": {"list": [1, 2.5, None, True]}}
    assert log.update_command(rec["id"], ack=ack)["ack"] == ack
    (text,) = log_backend.query("SELECT params, ack FROM commands")  # stored as JSON text
    assert json.loads(text[0]) == fields["params"] and json.loads(text[1]) == ack


def test_commands_filters_and_ordering(log: MissionLog) -> None:
    def at(second: int) -> dict[str, str]:
        return {"created_at": f"2026-01-01T00:00:0{second}.000+00:00"}

    d1 = log.new_dive("sim")
    a = log.insert_command(d1, {**command_fields(), **at(1)})
    b = log.insert_command(d1, {**command_fields("square", **SQUARE), **at(2)})
    d2 = log.new_dive("ws://vehicle:9090")
    c = log.insert_command(d2, {**command_fields(), "target": "ws://vehicle:9090", **at(3)})
    d = log.insert_command(d2, {**command_fields("surface"), "kind": "surface", **at(4)})
    log.update_command(a["id"], state="acknowledged")
    log.update_command(c["id"], state="acknowledged")
    log.update_command(b["id"], state="timed_out")

    def ids(**kw: Any) -> list[int]:
        return [r["id"] for r in log.commands(**kw)]

    assert ids() == [d["id"], c["id"], b["id"], a["id"]]  # newest first
    assert ids(oldest_first=True) == [a["id"], b["id"], c["id"], d["id"]]
    assert ids(state="acknowledged") == [c["id"], a["id"]]
    assert ids(state="queued") == [d["id"]]
    assert ids(pattern="circle") == [c["id"], a["id"]]
    assert ids(pattern="circle", state="acknowledged", dive=d2) == [c["id"]]
    assert ids(target="ws://vehicle:9090") == [c["id"]]
    assert ids(dive=d1) == [b["id"], a["id"]]
    assert ids(dive=99) == []
    assert ids(limit=2) == [d["id"], c["id"]]
    assert ids(limit=1, oldest_first=True) == [a["id"]]
    assert ids(since=c["created_at"]) == [d["id"], c["id"]]  # inclusive
    assert ids(until=b["created_at"]) == [b["id"], a["id"]]
    assert ids(since=b["created_at"], until=c["created_at"]) == [c["id"], b["id"]]
    assert ids(since="9999") == [] and ids(until="0000") == []
    assert ids(pattern="x'; DROP TABLE commands; --") == []  # parameters, not SQL
    assert len(ids()) == 4


def test_track_is_written_in_batches_and_flushed_on_read(
    log: MissionLog, log_backend: LogBackend
) -> None:
    dive = log.new_dive("sim")

    def stored() -> int:
        count: int = log_backend.scalar("SELECT COUNT(*) FROM track")
        return count

    for i in range(9):
        log.add_track(dive, float(i), i * 0.5, -i * 0.25, 2.0, 90.0)
    assert stored() == 0  # buffered
    log.add_track(dive, 9.0, 4.5, -2.25, 2.0, 90.0)
    assert stored() == 10  # a batch of ten
    log.add_track(dive, 10.0, 5.0, -2.5, 2.0, 90.0)
    assert stored() == 10
    track = log.track(dive)  # reading flushes
    assert stored() == 11
    assert len(track) == 11
    assert track[3] == {"t_s": 3.0, "x_m": 1.5, "y_m": -0.75, "z_m": 2.0, "heading_deg": 90.0}
    assert [p["t_s"] for p in track] == [float(i) for i in range(11)]


def test_track_is_per_dive_and_ordered_by_time(log: MissionLog) -> None:
    d1, d2 = log.new_dive("sim"), log.new_dive("sim")
    for t in (3.0, 1.0, 2.0):
        log.add_track(d1, t, t, 0.0, 1.0, 0.0)
    log.add_track(d2, 0.5, 9.0, 9.0, 9.0, 9.0)
    assert [p["t_s"] for p in log.track(d1)] == [1.0, 2.0, 3.0]
    assert [p["x_m"] for p in log.track(d2)] == [9.0]
    assert log.track(99) == []


def test_dives_listing(log: MissionLog) -> None:
    d1 = log.new_dive("sim")
    d2 = log.new_dive("loop://")
    assert (d1, d2) == (1, 2)
    for _ in range(2):
        log.insert_command(d1, command_fields())
    for i in range(10):
        log.add_track(d1, float(i), 0.0, 0.0, 2.0, 0.0)
    dives = log.dives()
    assert [d["id"] for d in dives] == [d2, d1]  # newest first
    assert dives[1]["target"] == "sim" and dives[0]["target"] == "loop://"
    assert dives[1]["commands"] == 2 and dives[1]["track_points"] == 10
    assert dives[0]["commands"] == 0 and dives[0]["track_points"] == 0
    assert dives[0]["started_at"] >= dives[1]["started_at"]
    assert log.dive_exists(d1) and log.dive_exists(d2) and not log.dive_exists(3)


def test_dives_listing_counts_buffered_track_points(log: MissionLog) -> None:
    dive = log.new_dive("sim")
    for i in range(3):
        log.add_track(dive, float(i), 0.0, 0.0, 2.0, 0.0)
    assert log.dives()[0]["track_points"] == len(log.track(dive)) == 3


def test_csv_rows_header_and_values(log: MissionLog) -> None:
    dive = log.new_dive("sim")
    a = log.insert_command(dive, command_fields())
    a = log.update_command(
        a["id"], state="acknowledged", attempts=1, sent_at=now_iso(), acked_at=now_iso(), ack=ACK
    )
    b = log.insert_command(dive, command_fields("square", **SQUARE))
    b = log.update_command(b["id"], state="rejected", reason="limit_violation: speed, too fast")
    rows = list(csv_rows([a, b]))
    assert rows[0] == CSV_HEADER
    assert all(len(r) == len(CSV_HEADER) for r in rows)
    ra = dict(zip(CSV_HEADER, rows[1], strict=True))
    assert ra["id"] == str(a["id"]) and ra["dive"] == str(dive)
    assert ra["pattern"] == "circle" and ra["state"] == "acknowledged" and ra["attempts"] == "1"
    assert json.loads(ra["params"]) == a["params"]
    assert ra["hex"] == a["hex"] and ra["bits"] == a["bits"]
    assert ra["corrected_bits"] == "1"
    assert ra["decode_latency_ms"] == "0.25" and ra["replan_latency_ms"] == "1.5"
    assert ra["reason"] == "" and ra["sent_at"] == a["sent_at"]
    rb = dict(zip(CSV_HEADER, rows[2], strict=True))
    assert rb["state"] == "rejected" and rb["reason"] == "limit_violation: speed, too fast"
    assert rb["corrected_bits"] == "" and rb["sent_at"] == "" and rb["acked_at"] == ""
    # through the csv module the commas and quotes of the JSON survive
    buf = io.StringIO()
    csv.writer(buf).writerows(rows)
    assert list(csv.reader(io.StringIO(buf.getvalue()))) == rows
    assert list(csv_rows([])) == [CSV_HEADER]


def test_persists_across_reopening(log_backend: LogBackend) -> None:
    first = log_backend.open()
    dive = first.new_dive("sim")
    rec = first.insert_command(dive, command_fields())
    rec = first.update_command(rec["id"], state="acknowledged", ack=ACK, attempts=1)
    for i in range(3):  # fewer than a batch: written on close
        first.add_track(dive, float(i), float(i), 0.0, 2.0, 45.0)
    first.close()

    second = log_backend.open()
    try:
        assert second.command(rec["id"]) == rec
        assert [p["t_s"] for p in second.track(dive)] == [0.0, 1.0, 2.0]
        assert second.dives()[0]["id"] == dive
        assert second.new_dive("sim") == dive + 1  # ids continue
        nxt = second.insert_command(dive + 1, command_fields("square", **SQUARE))
        assert nxt["id"] == rec["id"] + 1
    finally:
        second.close()


def test_committed_rows_are_visible_to_another_connection(
    log: MissionLog, log_backend: LogBackend
) -> None:
    """Every insert and update is committed at once (autocommit): a reader sees it while the
    log is still open, as after a killed process."""
    dive = log.new_dive("sim")
    rec = log.insert_command(dive, command_fields())
    assert log_backend.query("SELECT state FROM commands WHERE id = ?", (rec["id"],)) == [
        ("queued",)
    ]
    log.update_command(rec["id"], state="transmitted")
    assert log_backend.query("SELECT state FROM commands") == [("transmitted",)]


def test_concurrent_writers_are_serialised(log: MissionLog) -> None:
    dive = log.new_dive("sim")
    errors: list[BaseException] = []

    def write() -> None:
        try:
            for _ in range(20):
                rec = log.insert_command(dive, command_fields())
                log.update_command(rec["id"], state="transmitted", attempts=1)
                log.add_track(dive, 0.0, 0.0, 0.0, 0.0, 0.0)
        except BaseException as err:  # pragma: no cover - reported below
            errors.append(err)

    threads = [threading.Thread(target=write) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    rows = log.commands(limit=1000)
    assert len(rows) == 80 and {r["state"] for r in rows} == {"transmitted"}
    assert len({r["id"] for r in rows}) == 80
    assert len(log.track(dive)) == 80


def test_in_memory_log(tmp_path: Path) -> None:
    mem = MissionLog(":memory:")
    try:
        dive = mem.new_dive("sim")
        assert mem.insert_command(dive, command_fields())["id"] == 1
    finally:
        mem.close()
    assert not (Path.cwd() / ":memory:").exists()


def test_a_transaction_writes_all_or_nothing(log: MissionLog, log_backend: LogBackend) -> None:
    dive = log.new_dive("sim")
    old = log.insert_command(dive, command_fields())
    log.update_command(old["id"], state="transmitted")
    with pytest.raises(RuntimeError), log.transaction():
        log.insert_command(dive, command_fields("square", **SQUARE))
        log.update_command(old["id"], state="superseded", superseded_by=old["id"] + 1)
        raise RuntimeError("the process dies here")
    assert [r["id"] for r in log.commands()] == [old["id"]]
    assert log.command(old["id"])["state"] == "transmitted"  # type: ignore[index]
    with log.transaction():
        new = log.insert_command(dive, command_fields("square", **SQUARE))
        with log.transaction():  # nested: part of the outer one
            log.update_command(old["id"], state="superseded", superseded_by=new["id"])
    other = log_backend.open()  # another connection sees both, committed
    try:
        assert other.command(old["id"])["superseded_by"] == new["id"]  # type: ignore[index]
        assert other.command(new["id"]) is not None
    finally:
        other.close()


def test_a_dropped_connection_fails_that_write_and_the_next_is_written(
    log: MissionLog, log_backend: LogBackend
) -> None:
    """PostgreSQL: the server ends the log's session (a restart, an administrator): the write
    that finds it gone is a LogWriteError (503 to a send, nothing transmitted), and the next
    opens a new connection. (SQLite has no session to lose: the write simply goes through.)"""
    dive = log.new_dive("sim")
    if log_backend.postgres:
        log_backend.query(
            "SELECT pg_terminate_backend(pid) FROM pg_stat_activity "
            "WHERE application_name = 'nemesys-console' AND datname = current_database()"
        )
        with pytest.raises(LogWriteError, match="the mission log cannot be written: "):
            log.insert_command(dive, command_fields())
        assert log_backend.scalar("SELECT COUNT(*) FROM commands") == 0
    rec = log.insert_command(dive, command_fields())
    assert log.command(rec["id"]) == rec
    assert log_backend.scalar("SELECT COUNT(*) FROM commands") == 1


def test_consoles_opening_a_new_log_together_migrate_it_once(log_backend: LogBackend) -> None:
    """Several consoles starting at once on one new database: one migrates (the others wait
    for its transaction: PostgreSQL's advisory lock, SQLite's write lock), all open it."""
    opened: list[MissionLog] = []
    errors: list[BaseException] = []

    def open_one() -> None:
        try:
            opened.append(log_backend.open())
        except BaseException as err:  # pragma: no cover - reported below
            errors.append(err)

    threads = [threading.Thread(target=open_one) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    try:
        assert errors == [] and len(opened) == 3
        dives = [log.new_dive("sim") for log in opened]
        assert sorted(dives) == [1, 2, 3]
    finally:
        for log in opened:
            log.close()
    assert log_backend.query("SELECT version_num FROM alembic_version") == [(head(),)]
