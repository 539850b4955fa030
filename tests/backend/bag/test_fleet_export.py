"""A fleet's dive exported (issue 23, Build item 7): the console with ``NEMESYS_VEHICLES=3`` on
three in-memory vehicles behind the real onboard agent (the light fleet client of
``tests/backend/fleet/test_fleet_console.py``), each on its own lane, a command to two of them,
Surface all, an event of one vehicle's and one naming none; on both back-ends (``log_backend``).

Every vehicle is in the one export, each vehicle's topics under ``/<name>`` (the live Foxglove
view's naming), each pose, command, frame and acknowledgement on its own vehicle's topics and
never another's, its odometry's child frame ``<name>/base_link``, the events naming no vehicle
on the plain topic; read back by the same two readers as the single vehicle's export
(``mcap``'s with ``mcap_ros2``'s decoder, and rosbags' AnyReader), and through the API's
streamed download. The single vehicle's topics are test_export.py's (unchanged)."""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from io import BytesIO
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader

from backend.bag import messages as m
from backend.bag.export import export_files
from backend.bag.msgdefs import typestore
from backend.chart.geo import Datum
from backend.mission_log.dive_reader import open_read_only
from station.link_fleet import FleetLink
from tests.agent_link import agent_fleet
from tests.backend.conftest import (
    AUTH,
    CIRCLE,
    SQUARE,
    MakeLightClient,
    console_of,
    wait_state,
    wait_until,
)
from tests.backend.log_backend import LogBackend
from vehicle_contract.fleet import parse_vehicles

FLEET = parse_vehicles("3")
NAMES = [v.name for v in FLEET]
#: Each vehicle's lane (m east), and the track points added to it.
LANE_M = 20.0
POINTS = 6
DATUM = Datum(43.1, 5.9)


@dataclass(frozen=True)
class FleetDive:
    """The fleet's console and its dive, written to the log."""

    client: TestClient
    dive: int
    where: Path | str


@pytest.fixture
def fleet_dive(make_light_client: MakeLightClient, log_backend: LogBackend) -> Iterator[FleetDive]:
    link: FleetLink = agent_fleet(FLEET, spacing_m=LANE_M)
    client = make_light_client(link, vehicles="3", **log_backend.settings())  # type: ignore[arg-type]
    wait_until(lambda: all(v["pose"] for v in client.get("/api/vehicles").json()))
    console = console_of(client)
    log, dive = console.log, console.dive
    assert log is not None and dive is not None
    for name, pattern, params in (("auv2", "circle", CIRCLE), ("auv1", "square", SQUARE)):
        body = {"pattern": pattern, "params": params, "vehicle": name}
        r = client.post("/api/commands", json=body, headers=AUTH)
        assert r.status_code == 202, r.text
        wait_state(client, r.json()["id"], ("acknowledged",))
    r = client.post("/api/surface", json={"vehicle": "all"}, headers=AUTH)
    assert r.status_code == 202, r.text
    for record in r.json()["commands"]:
        wait_state(client, record["id"], ("acknowledged",))
    start = max(row["t_s"] for row in log.track_rows(dive, positioned=False))
    for k in range(1, POINTS + 1):
        for i, name in enumerate(NAMES):
            status = {"battery_pct": 90.0 - i, "nav_valid": True}
            log.add_track(dive, start + k, 1.5 * k, LANE_M * i, 2.0, 0.0, status, vehicle=name)
    log.add_event(dive, "echo_mismatch", "auv3 runs another", vehicle="auv3")
    log.add_event(dive, "note", "the console's own")
    log.flush_track()
    yield FleetDive(client, dive, log_backend.where)


def topic(base: m.Topic, vehicle: str | None) -> str:
    """The oracle's topic name, spelt out (not the exporter's function)."""
    return base.name if vehicle is None else f"/{vehicle}{base.name}"


def expected_counts(fleet: FleetDive) -> Counter[str]:
    """Messages per topic from the mission log's own API, vehicle by vehicle."""
    log = console_of(fleet.client).log
    assert log is not None
    want: Counter[str] = Counter()
    for name in NAMES:
        track = log.track_rows(fleet.dive, positioned=False, vehicle=name)
        positioned = sum(1 for r in track if r["x_m"] is not None)
        commands = log.commands(dive=fleet.dive, vehicle=name, limit=1000)
        acks = sum(1 for c in commands if c.get("ack") is not None)
        want[topic(m.ODOM, name)] = want[topic(m.FIX, name)] = positioned
        want[topic(m.STATUS, name)] = len(track)
        want[topic(m.COMMANDS, name)] = len(commands)
        want[topic(m.FRAME, name)] = sum(1 for c in commands if c.get("first_sent_at"))
        want[topic(m.ACK, name)] = want[topic(m.MISSION, name)] = acks
    for event in log.events(fleet.dive):
        want[topic(m.EVENTS, event.get("vehicle"))] += 1
    return +want  # the topics with no message are left out of an export


def decoded_mcap(data: bytes) -> list[tuple[str, int, Any]]:
    reader = make_reader(BytesIO(data), decoder_factories=[DecoderFactory()])
    return [
        (channel.topic, message.log_time, decoded)
        for _, channel, message, decoded in reader.iter_decoded_messages(log_time_order=False)
    ]


def test_every_vehicle_is_in_one_export_on_its_own_topics(
    fleet_dive: FleetDive, tmp_path: Path
) -> None:
    log = console_of(fleet_dive.client).log
    assert log is not None
    db = open_read_only(fleet_dive.where)
    try:
        mcap_out, bag_out = tmp_path / "fleet.mcap", tmp_path / "fleet_bag"
        export_files(db, fleet_dive.dive, mcap=mcap_out, rosbag2=bag_out, datum=DATUM)
    finally:
        db.close()
    want = expected_counts(fleet_dive)
    for name in NAMES:  # every vehicle has poses, fixes, status, commands, frames, acks
        own = [t for t in want if t.startswith(f"/{name}/")]
        assert len(own) == (8 if name == "auv3" else 7), (name, own)  # auv3's event too
    assert [t for t in want if not t.startswith(tuple(f"/{n}/" for n in NAMES))] == [m.EVENTS.name]

    # mcap's reader: the counts, the log times, each vehicle's poses on its own lane
    got = decoded_mcap(mcap_out.read_bytes())
    assert Counter(t for t, _, _ in got) == want
    times = [t for _, t, _ in got]
    assert times == sorted(times), "log times go back in the file"
    for i, name in enumerate(NAMES):
        poses = [msg for t, _, msg in got if t == topic(m.ODOM, name)]
        assert {p.child_frame_id for p in poses} == {f"{name}/base_link"}
        last = poses[-1].pose.pose.position  # ENU: x east (its lane), y north
        assert (last.x, last.y) == pytest.approx((LANE_M * i, 1.5 * POINTS))
        statuses = [msg for t, _, msg in got if t == topic(m.STATUS, name)]
        assert statuses[-1].battery_pct == 90.0 - i
        ids = [msg.id for t, _, msg in got if t == topic(m.COMMANDS, name)]
        commands = log.commands(dive=fleet_dive.dive, vehicle=name, limit=1000)
        assert sorted(ids) == sorted(c["id"] for c in commands)
        hexes = {c["hex"] for c in commands if c.get("first_sent_at")}
        frames = [msg for t, _, msg in got if t == topic(m.FRAME, name)]
        assert {bytes(f.data).hex()[:27] for f in frames} == {h.lower() for h in hexes}
        acks = [msg for t, _, msg in got if t == topic(m.ACK, name)]
        assert {a.outcome for a in acks} == {"accepted"} and len(acks) == len(commands)
    events = [json.loads(msg.data) for t, _, msg in got if t == topic(m.EVENTS, "auv3")]
    assert [e["detail"] for e in events] == ["auv3 runs another"]
    shared = [json.loads(msg.data)["detail"] for t, _, msg in got if t == m.EVENTS.name]
    assert "the console's own" in shared and "auv3 runs another" not in shared
    with mcap_out.open("rb") as f:
        (meta,) = list(make_reader(f).iter_metadata())
    assert meta.metadata["vehicles"] == ",".join(NAMES)

    # rosbags' reader, of both forms: the same topics and counts
    for path in (mcap_out, bag_out):
        counts: Counter[str] = Counter()
        with AnyReader([path], default_typestore=typestore()) as reader:
            for connection, _, _ in reader.messages():
                counts[connection.topic] += 1
        assert counts == want, path
    meta_yaml = (bag_out / "metadata.yaml").read_text()
    assert "nemesys.vehicles: auv1,auv2,auv3" in meta_yaml
    assert "name: /auv2/nemesys/odom" in meta_yaml and "name: /nemesys/odom" not in meta_yaml

    # the API's streamed download: the same topics
    r = fleet_dive.client.get(f"/api/dives/{fleet_dive.dive}/export.mcap")
    assert r.status_code == 200, r.text
    streamed = Counter(t for t, _, _ in decoded_mcap(r.content))
    if console_of(fleet_dive.client).datum is None:  # nor in its log: no fix
        want = Counter({t: n for t, n in want.items() if not t.endswith(m.FIX.name)})
    assert streamed == want
