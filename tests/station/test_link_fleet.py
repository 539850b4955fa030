"""A fleet's link (issue 23): one transmitter for every vehicle's frames, and each vehicle's own
link for what it reports: a view of the modem on a one-way link, its own rosbridge under its
namespace with telemetry, the un-namespaced frame topic as the channel on a rosbridge."""

from __future__ import annotations

import pytest

from station.link import Capability, RosbridgeLink
from station.link_fleet import FleetLink, SharedTransmitter, open_fleet_link
from station.link_modem import ModemLink
from vehicle_contract.fleet import parse_vehicles

FLEET = parse_vehicles("2")


def test_a_modem_alone_gives_each_vehicle_a_view_of_the_one_transmitter() -> None:
    link = open_fleet_link("tcp://127.0.0.1:9", 36_000, FLEET)
    assert isinstance(link.frames, ModemLink)
    views = list(link.vehicles.values())
    assert all(isinstance(v, SharedTransmitter) and v.frames is link.frames for v in views)
    assert all(v.capability is Capability.NONE and not v.acknowledges for v in views)
    assert views[0].connection_problem == link.frames.connection_problem
    assert views[0].capability_problems == link.frames.capability_problems


def test_telemetry_gives_each_vehicle_its_own_rosbridge_under_its_namespace() -> None:
    link = open_fleet_link("tcp://127.0.0.1:9", 36_000, FLEET, "ws://127.0.0.1:9090")
    assert isinstance(link.frames, ModemLink)
    for name, own in link.vehicles.items():
        assert isinstance(own, RosbridgeLink) and not own.frames
        assert own.names.pose == f"/{name}/nemesys/pose"


def test_a_rosbridge_fleet_publishes_on_the_channel_topic_each_reporting_under_its_name() -> None:
    link = open_fleet_link("ws://127.0.0.1:9090", 36_000, FLEET)
    assert isinstance(link.frames, RosbridgeLink) and link.frames.frames
    assert link.frames.names.frame == "/nemesys/frame"
    assert [v.names.status for v in link.vehicles.values()] == [  # type: ignore[attr-defined]
        "/auv1/nemesys/status",
        "/auv2/nemesys/status",
    ]
    with pytest.raises(ValueError, match="carries telemetry"):
        open_fleet_link("ws://127.0.0.1:9090", 36_000, FLEET, "ws://127.0.0.1:9091")


def test_a_fleet_link_is_what_its_transmitter_is() -> None:
    link = open_fleet_link("tcp://127.0.0.1:9", 36_000, FLEET)
    assert link.capability is link.frames.capability and link.target == link.frames.target
    with pytest.raises(AttributeError):
        link.capability = Capability.ACKS_AND_TELEMETRY
    with pytest.raises(ValueError, match="at least one vehicle"):
        FleetLink(link.frames, {})
