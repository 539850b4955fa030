"""``nemesys sim --vehicles``: a fleet on one bridge from the command line. A bad fleet is
refused with :mod:`vehicle_contract.fleet`'s message (exit 2); a good one is served, and a
third-party client (roslibpy) reads one vehicle by its namespace. Loopback only."""

from __future__ import annotations

import io
import json

import pytest
import roslibpy

from cli.main import main
from codec import encode_frame
from tests.rosbridge.helpers import Inbox, ros_client
from tests.sim.sim_process import nemesys_sim
from vehicle_contract.fleet import FleetError, parse_vehicles


@pytest.mark.parametrize(
    "value",
    [
        "0",
        "16",
        "three",
        "[]",
        '[{"name": "Auv", "address": 1}]',
        '[{"name": "a", "address": 1}, {"name": "b", "address": 1}]',
        '[{"name": "a", "address": 0}]',
    ],
)
def test_a_bad_fleet_is_refused_with_the_fleet_parsers_message(
    value: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(FleetError) as expected:
        parse_vehicles(value)
    status = main(["sim", "--vehicles", value, "--port", "0"], out=io.StringIO())
    err = capsys.readouterr().err
    assert status == 2
    assert err == f"nemesys sim: --vehicles: {expected.value}\n"


def test_a_fleet_that_cannot_start_within_range_is_refused(
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = ["sim", "--vehicles", "11", "--range", "100", "--port", "0"]
    assert main(argv, out=io.StringIO()) == 2
    err = capsys.readouterr().err
    assert "vehicle auv5 would start 120 m from the transmitter" in err
    assert "beyond the link's range of 100 m" in err


@pytest.mark.interop
@pytest.mark.slow  # a `nemesys sim` subprocess
def test_roslibpy_reads_the_second_vehicle_of_a_fleet_by_its_namespace() -> None:
    fleet = '[{"name": "auv1", "address": 1}, {"name": "auv2", "address": 2}, ' + (
        '{"name": "auv3", "address": 3}]'
    )
    with nemesys_sim("--vehicles", fleet, "--time-scale", "5") as port, ros_client(port) as ros:
        assert {"/auv2/nemesys/pose", "/auv2/nemesys/frame"} <= set(ros.get_topics())
        assert ros.get_topic_type("/auv2/nemesys/pose") == "geometry_msgs/msg/PoseStamped"
        poses, missions = Inbox(), Inbox()
        pose = roslibpy.Topic(ros, "/auv2/nemesys/pose", "geometry_msgs/msg/PoseStamped")
        pose.subscribe(poses)
        mission = roslibpy.Topic(ros, "/auv2/nemesys/mission", "std_msgs/msg/String")
        mission.subscribe(missions)
        (first,) = poses.wait(1, timeout=5)[:1]
        position = first["pose"]["position"]
        # auv2 starts 30 m east of auv1 (NED: y east), at the depth of a single vehicle
        assert (position["x"], position["y"]) == pytest.approx((0.0, 30.0), abs=0.5)
        assert first["header"]["frame_id"] == "map_ned"
        frames = roslibpy.Topic(ros, "/nemesys/frame", "std_msgs/msg/UInt8MultiArray")
        frames.advertise()
        ros.get_topics()  # the subscriptions are in before the frame
        surface_all = encode_frame("surface", address=0).frame.to_bytes()
        frames.publish(roslibpy.Message({"data": list(surface_all)}))
        (raw,) = missions.wait(1, timeout=5)[:1]
        ack = json.loads(raw["data"])
        assert ack["outcome"] == "accepted" and ack["address"] == 0
        assert ack["command"]["pattern"] == "surface"
        frames.unadvertise()
