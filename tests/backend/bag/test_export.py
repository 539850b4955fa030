"""A dive exported as MCAP and as rosbag2, read back by two independent readers (``mcap``'s
reader with ``mcap_ros2``'s decoder, and rosbags' AnyReader): every topic, as many messages as
the log has rows, log times that never go back, a pose equal to its row; on both back-ends (the
dive's log on SQLite, then on PostgreSQL: ``dive_log``); an older SQLite log exported without
being migrated; outputs never half written."""

from __future__ import annotations

import json
import math
import sqlite3
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pymap3d
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader

from backend.bag import messages as m
from backend.bag.export import export_files
from backend.bag.msgdefs import typestore
from backend.bag.write import ExportExists
from backend.chart.geo import Datum
from backend.mission_log.dive_reader import NoSuchDive, open_read_only
from backend.mission_log.read_only import ReadOnlyDatabase
from backend.mission_log.store import MissionLog
from bench._dive_log import DATUM
from tests.backend.bag.conftest import DiveLog
from tests.backend.log_backend import LogBackend
from tests.backend.mission_log.test_migrations import ISSUE_20_TRACK
from vehicle_contract.frames import EnuPose, enu_to_ned


@pytest.fixture(scope="module")
def db(dive_log: DiveLog) -> Iterator[ReadOnlyDatabase]:
    conn = open_read_only(dive_log.where)
    yield conn
    conn.close()


@pytest.fixture(scope="module")
def exported(
    dive_log: DiveLog, db: ReadOnlyDatabase, tmp_path_factory: pytest.TempPathFactory
) -> dict[str, Path]:
    out = tmp_path_factory.mktemp("out")
    export_files(db, dive_log.filled.dive, mcap=out / "dive.mcap", rosbag2=out / "dive_bag")
    return {"mcap": out / "dive.mcap", "rosbag2": out / "dive_bag"}


@pytest.fixture(scope="module")
def log_rows(dive_log: DiveLog) -> dict[str, Any]:
    """The dive as the store reads it back (not the exporter's reader)."""
    log = MissionLog(dive_log.where)
    try:
        dive = dive_log.filled.dive
        commands = log.commands(dive=dive, limit=10_000, oldest_first=True)
        return {
            "track": log.track_rows(dive, positioned=False),
            "commands": commands,
            "events": log.events(dive),
        }
    finally:
        log.close()


def expected_counts(rows: dict[str, Any]) -> dict[str, int]:
    positioned = sum(1 for r in rows["track"] if r["x_m"] is not None)
    acks = sum(1 for c in rows["commands"] if c.get("ack") is not None)
    return {
        m.ODOM.name: positioned,
        m.FIX.name: positioned,  # the log has a datum from the dive's start
        m.STATUS.name: len(rows["track"]),
        m.FRAME.name: sum(1 for c in rows["commands"] if c.get("first_sent_at")),
        m.COMMANDS.name: len(rows["commands"]),
        m.ACK.name: acks,
        m.MISSION.name: acks,
        m.EVENTS.name: len(rows["events"]),
    }


def decoded_mcap(path: Path) -> list[tuple[str, int, Any]]:
    """(topic, log time, decoded message) of every message in file order, with mcap's reader
    and the ROS 2 decoder."""
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [
            (channel.topic, message.log_time, decoded)
            for _, channel, message, decoded in reader.iter_decoded_messages(log_time_order=False)
        ]


def test_every_topic_and_as_many_messages_as_the_log_has_rows_mcap_reader(
    exported: dict[str, Path], log_rows: dict[str, Any]
) -> None:
    got = decoded_mcap(exported["mcap"])
    want = expected_counts(log_rows)
    assert set(want) == {t.name for t in m.TOPICS}
    assert all(n > 0 for n in want.values()), want  # the dive has every kind of row
    assert Counter(topic for topic, _, _ in got) == want
    times = [t for _, t, _ in got]
    assert times == sorted(times), "log times go back in the file"
    with exported["mcap"].open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None and summary.statistics is not None
    assert summary.statistics.message_count == sum(want.values())
    # what ros2 bag play and Foxglove seek by: chunk indexes naming each chunk's message indexes
    assert summary.chunk_indexes and all(c.message_index_offsets for c in summary.chunk_indexes)
    types = {summary.schemas[c.schema_id].name for c in summary.channels.values()}
    assert types == {t.type for t in m.TOPICS}


def test_a_pose_and_its_fix_decode_to_the_logs_row(
    exported: dict[str, Path], log_rows: dict[str, Any]
) -> None:
    row = next(r for r in log_rows["track"][500:] if r["x_m"] is not None)
    got = decoded_mcap(exported["mcap"])

    def at(topic: str) -> Any:
        return next(
            msg
            for t, _, msg in got
            if t == topic and msg.header.stamp.sec + msg.header.stamp.nanosec / 1e9 == row["t_s"]
        )

    pose = at(m.ODOM.name).pose.pose
    q = pose.orientation
    yaw_deg = math.degrees(2 * math.atan2(q.z, q.w))
    ned = enu_to_ned(EnuPose(pose.position.x, pose.position.y, pose.position.z, yaw_deg))
    assert ned.x_north_m == pytest.approx(row["x_m"]) and ned.y_east_m == pytest.approx(row["y_m"])
    assert ned.z_down_m == pytest.approx(row["z_m"])
    assert ned.heading_deg == pytest.approx(row["heading_deg"], abs=1e-9)
    # the fix against an independent geodesy (pymap3d), about the log's datum
    fix = at(m.FIX.name)
    lat, lon, _ = pymap3d.ned2geodetic(row["x_m"], row["y_m"], 0.0, *DATUM, 0.0)
    assert fix.latitude == pytest.approx(float(lat), abs=1e-9)
    assert fix.longitude == pytest.approx(float(lon), abs=1e-9)
    status = at(m.STATUS.name)
    assert status.battery_pct == pytest.approx(row["battery_pct"])
    assert status.commanded_depth_m == row["commanded_depth_m"] and status.nav_valid is True
    faults = [msg for t, _, msg in got if t == m.STATUS.name and not msg.nav_valid]
    assert len(faults) == sum(1 for r in log_rows["track"] if r["nav_valid"] is False) > 0
    assert all(math.isnan(f.x_m) and f.mode == "nav_fault" for f in faults)


def read_any(paths: list[Path]) -> tuple[Counter[str], list[int], dict[str, list[Any]]]:
    """Counts per topic, timestamps in read order and the decoded acks and mission strings,
    with rosbags' AnyReader (the NemeSys types from the same .msg files)."""
    counts: Counter[str] = Counter()
    times: list[int] = []
    kept: dict[str, list[Any]] = {m.ACK.name: [], m.MISSION.name: []}
    with AnyReader(paths, default_typestore=typestore()) as reader:
        for connection, timestamp, raw in reader.messages():
            counts[connection.topic] += 1
            times.append(timestamp)
            if connection.topic in kept:
                kept[connection.topic].append(reader.deserialize(raw, connection.msgtype))
    return counts, times, kept


@pytest.mark.parametrize("form", ["mcap", "rosbag2"])
def test_rosbags_reads_both_forms_the_same(
    exported: dict[str, Path], log_rows: dict[str, Any], form: str
) -> None:
    counts, times, kept = read_any([exported[form]])
    assert counts == expected_counts(log_rows)
    assert times == sorted(times)
    acked = [c for c in log_rows["commands"] if c.get("ack") is not None]
    assert [a.outcome for a in kept[m.ACK.name]] == [c["ack"]["outcome"] for c in acked]
    assert "rejected" in [a.outcome for a in kept[m.ACK.name]]
    first = kept[m.ACK.name][0]
    assert first.frame_hex == acked[0]["hex"] and first.corrected_bits == 1
    assert first.header.stamp.sec == math.floor(acked[0]["ack"]["t_s"])  # the vehicle's clock
    # the contract's JSON form: the acknowledgement as the vehicle sent it
    assert [json.loads(s.data) for s in kept[m.MISSION.name]] == [c["ack"] for c in acked]


def test_the_rosbag2_directory_has_its_metadata_and_one_mcap(exported: dict[str, Path]) -> None:
    bag = exported["rosbag2"]
    assert sorted(p.name for p in bag.iterdir()) == ["dive_bag.mcap", "metadata.yaml"]
    meta = (bag / "metadata.yaml").read_text()
    assert "storage_identifier: mcap" in meta and "nemesys.dive: '1'" in meta
    for topic in m.TOPICS:
        assert f"name: {topic.name}" in meta and f"type: {topic.type}" in meta


def test_without_a_datum_there_is_no_fix_and_a_given_one_places_it(
    log_backend: LogBackend, tmp_path: Path
) -> None:
    log = log_backend.open()
    dive = log.new_dive("sim")
    for k in range(5):
        log.add_track(dive, float(k), 10.0, 5.0, 1.0, 0.0)
    log.close()
    db = open_read_only(log_backend.where)
    try:
        (bare,) = export_files(db, dive, mcap=tmp_path / "bare.mcap")
        (placed,) = export_files(db, dive, mcap=tmp_path / "placed.mcap", datum=Datum(43.0, 5.0))
    finally:
        db.close()
    assert m.FIX.name not in bare.topics and bare.topics[m.ODOM.name] == 5
    assert placed.topics[m.FIX.name] == 5
    fix = next(msg for t, _, msg in decoded_mcap(tmp_path / "placed.mcap") if t == m.FIX.name)
    assert fix.latitude == pytest.approx(float(pymap3d.ned2geodetic(10, 5, 0, 43, 5, 0)[0]))


def test_an_older_log_is_exported_as_it_is_without_migrating_it(tmp_path: Path) -> None:
    path = tmp_path / "old.sqlite3"
    raw = sqlite3.connect(path)
    raw.executescript(
        ISSUE_20_TRACK
        + "CREATE TABLE commands (id INTEGER PRIMARY KEY, dive INTEGER, created_at TEXT, "
        "updated_at TEXT, kind TEXT, pattern TEXT, pattern_id INTEGER, params TEXT, hex TEXT, "
        "state TEXT, sent_at TEXT, acked_at TEXT, ack TEXT);"
        "CREATE TABLE events (id INTEGER PRIMARY KEY, dive INTEGER, at TEXT, kind TEXT, "
        "detail TEXT, data TEXT);"
    )
    raw.execute("INSERT INTO dives VALUES (1, '2024-05-01T10:00:00.000+00:00', 'sim')")
    for k in range(3):  # the oldest rows had no arrival time: placed from the dive's start
        raw.execute(
            "INSERT INTO track (dive, t_s, x_m, y_m, z_m, heading_deg) VALUES (1, ?, 1, 2, 3, 4)",
            (50.0 + k,),
        )
    raw.execute(
        "INSERT INTO commands VALUES (1, 1, '2024-05-01T10:00:01.000+00:00', "
        "'2024-05-01T10:00:03.000+00:00', 'command', 'circle', 3, "
        '\'{"speed": 0.18, "depth": 3, "radius": 5, "direction": "cw"}\', '
        "'aaaa7c3121e5a0000008e1570', 'acknowledged', '2024-05-01T10:00:01.500+00:00', "
        "'2024-05-01T10:00:02.000+00:00', '{\"outcome\": \"accepted\"}')"
    )
    raw.commit()
    raw.close()
    before = path.read_bytes()
    db = open_read_only(path)
    try:
        (written,) = export_files(db, 1, mcap=tmp_path / "old.mcap")
    finally:
        db.close()
    assert path.read_bytes() == before  # read, never migrated
    assert written.topics == {
        m.ODOM.name: 3,
        m.STATUS.name: 3,
        m.COMMANDS.name: 1,
        m.FRAME.name: 1,  # the last copy's time: the log had no first_sent_at
        m.ACK.name: 1,
        m.MISSION.name: 1,
    }
    times = [(t, topic) for topic, t, _ in decoded_mcap(tmp_path / "old.mcap")]
    assert times == sorted(times, key=lambda x: x[0])
    start_ns = 1714557600 * 10**9
    odom_times = [t for t, topic in times if topic == m.ODOM.name]
    assert odom_times == [start_ns, start_ns + 10**9, start_ns + 2 * 10**9]


def test_an_unknown_dive_is_named_and_nothing_is_written(
    db: ReadOnlyDatabase, tmp_path: Path
) -> None:
    with pytest.raises(NoSuchDive, match=r"no dive 7 in the mission log \(its only dive is 1\)"):
        export_files(db, 7, mcap=tmp_path / "x.mcap", rosbag2=tmp_path / "x_bag")
    assert list(tmp_path.iterdir()) == []


def test_an_existing_output_is_replaced_only_when_asked(
    db: ReadOnlyDatabase, tmp_path: Path
) -> None:
    target = tmp_path / "dive.mcap"
    target.write_bytes(b"mine")
    with pytest.raises(ExportExists, match="exists: give --force"):
        export_files(db, 1, mcap=target)
    assert target.read_bytes() == b"mine"
    export_files(db, 1, mcap=target, force=True)
    assert target.read_bytes()[:8] == b"\x89MCAP0\r\n"
    folder = tmp_path / "not_a_bag"
    folder.mkdir()
    with pytest.raises(ExportExists, match="not a rosbag2 directory"):
        export_files(db, 1, rosbag2=folder, force=True)
    assert list(folder.iterdir()) == []


@pytest.mark.parametrize("form", ["mcap", "rosbag2"])
def test_a_failure_midway_leaves_nothing_behind(
    db: ReadOnlyDatabase, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, form: str
) -> None:
    calls = 0
    status = m.status

    def failing(row: dict[str, Any]) -> m.Msg:
        nonlocal calls
        calls += 1
        if calls == 300:
            raise OSError("disk full")
        return status(row)

    monkeypatch.setattr(m, "status", failing)
    target = tmp_path / ("dive.mcap" if form == "mcap" else "dive_bag")
    with pytest.raises(OSError, match="disk full"):
        export_files(db, 1, **{form: target})  # type: ignore[arg-type]
    assert calls == 300 and list(tmp_path.iterdir()) == []
