"""Training with a fleet at the simulator level: three twins on one shared ME link, each with
its address, its own channel (errors, range) and its own agent (docs/protocol.md,
"Addressing"). Time is the simulation's own: nothing here waits on the wall clock."""

from __future__ import annotations

import math
from typing import Any

import pytest

from codec import ParamValue, encode_frame
from sim.channel import ChannelConfig
from sim.fleet import (
    DEFAULT_SPACING_M,
    FleetSimulation,
    start_positions,
    vehicle_seed,
)
from sim.simulation import SimConfig, Simulation
from vehicle_contract.codes import Mode
from vehicle_contract.endpoint import FleetEndpoint
from vehicle_contract.fleet import FleetError, FleetVehicle, parse_vehicles
from vehicle_contract.payloads import validate_ack, validate_status

NAMES = ("auv1", "auv2", "auv3")


def _frame(pattern: str, address: int | None, **params: ParamValue) -> bytes:
    return encode_frame(pattern, params, address=address).frame.to_bytes()


SQUARE_TO_2 = _frame("square", 2, speed=0.2, depth=2.5, side_span=6, direction="ccw")
SURFACE_ALL = _frame("surface", 0)


def _fleet(**config: Any) -> FleetSimulation:
    return FleetSimulation(parse_vehicles("3"), SimConfig(**config))


def _acks(fleet: FleetSimulation) -> dict[str, list[dict[str, Any]]]:
    return {v.name: fleet.sim(v.name).take_missions() for v in fleet.vehicles}


def _active(fleet: FleetSimulation, name: str) -> str | None:
    active = fleet.sim(name).agent.active
    return active.pattern if active is not None else None


def _mode(sim: Simulation) -> Mode:
    return sim.mode


def test_the_fleet_is_a_fleet_endpoint_with_each_vehicle_under_its_namespace() -> None:
    fleet = _fleet()
    endpoint: FleetEndpoint = fleet  # checked by mypy
    assert isinstance(endpoint, FleetEndpoint)
    assert not isinstance(Simulation(), FleetEndpoint)
    assert list(fleet.members) == ["/auv1", "/auv2", "/auv3"]
    for v in fleet.vehicles:
        sim = fleet.sim(v.name)
        assert fleet.members[v.namespace] is sim
        assert sim.agent.address == v.address == sim.config.address
        status = sim.status()
        assert status["address"] == v.address
        assert validate_status(status) == []
    with pytest.raises(KeyError, match=r"no vehicle 'auv9' in the fleet .*auv1, auv2, auv3"):
        fleet.sim("auv9")


def test_a_frame_to_one_vehicle_changes_only_that_ones_command() -> None:
    fleet = _fleet()
    fleet.submit_frame(SQUARE_TO_2)
    fleet.advance(0.5)
    acks = _acks(fleet)
    assert [len(a) for a in acks.values()] == [1, 1, 1]  # every vehicle heard the one frame
    (two,) = acks["auv2"]
    assert two["outcome"] == "accepted" and two["address"] == 2
    assert two["active"]["pattern"] == "square"
    for name in ("auv1", "auv3"):
        (ack,) = acks[name]
        assert ack["outcome"] == "rejected" and ack["reason"] == "other_vehicle"
        assert ack["address"] == 2 and ack["active"] is None
        assert validate_ack(ack) == []
    assert [_active(fleet, n) for n in NAMES] == [None, "square", None]
    assert fleet.transmissions == 1
    fleet.advance(20.0)
    assert _mode(fleet.sim("auv2")) is Mode.RUNNING
    assert _mode(fleet.sim("auv1")) is _mode(fleet.sim("auv3")) is Mode.IDLE


def test_surface_all_surfaces_every_vehicle() -> None:
    fleet = _fleet()
    fleet.submit_frame(SQUARE_TO_2)
    fleet.advance(30.0)
    _acks(fleet)
    fleet.submit_frame(SURFACE_ALL)
    fleet.advance(0.5)
    for name, acks in _acks(fleet).items():
        (ack,) = acks
        assert ack["outcome"] == "accepted", name
        assert ack["address"] == 0 and ack["active"]["pattern"] == "surface"
    # every one reaches the surface (waited for in simulated time, bounded)
    while fleet.t_s < 300.0 and any(_mode(fleet.sim(n)) is not Mode.SURFACED for n in NAMES):
        fleet.advance(1.0)
    assert [_mode(fleet.sim(n)) for n in NAMES] == [Mode.SURFACED] * 3
    assert all(fleet.sim(n).vehicle.z < 0.3 for n in NAMES)


def test_a_single_vehicle_surface_reaches_every_vehicle_and_other_unaddressed_frames_none() -> None:
    fleet = _fleet()
    fleet.submit_frame(_frame("hover", None, duration=60, depth=1.5, heading=90))
    fleet.submit_frame(_frame("surface", None))
    fleet.advance(0.5)
    for acks in _acks(fleet).values():
        assert [(a["outcome"], a["reason"]) for a in acks] == [
            ("rejected", "other_vehicle"),
            ("accepted", None),
        ]


def test_each_vehicle_decodes_the_same_transmission_with_its_own_bit_errors() -> None:
    fleet = _fleet(channel=ChannelConfig(ber=0.03))
    sent = 40
    for _ in range(sent):
        fleet.submit_frame(SURFACE_ALL)
        fleet.advance(0.2)
    acks = _acks(fleet)
    assert [len(a) for a in acks.values()] == [sent] * 3  # each copy heard by every vehicle
    received = {name: [a["frame_hex"] for a in got] for name, got in acks.items()}
    flipped = {name: [a["channel_flipped_bits"] for a in got] for name, got in acks.items()}
    outcome = {name: [a["outcome"] for a in got] for name, got in acks.items()}
    sent_hex = encode_frame("surface", address=0).frame.hex
    for name in NAMES:  # what each vehicle decoded is what its own channel made of the frame
        for h, f, o in zip(received[name], flipped[name], outcome[name], strict=True):
            assert (h == sent_hex) == (f == 0)
            assert f > 0 or o == "accepted"
        assert sum(flipped[name]) > 0 and "accepted" in outcome[name]
    # the errors are each vehicle's own: the copies differ, and so do the outcomes of one copy
    assert len({tuple(received[n]) for n in NAMES}) == 3
    split = [k for k in range(sent) if len({outcome[n][k] for n in NAMES}) > 1]
    assert split, "at BER 0.03 some copy is taken by one vehicle and lost by another"
    for k in split:
        assert any(flipped[n][k] > 0 for n in NAMES if outcome[n][k] == "rejected")


def test_a_vehicle_beyond_the_range_hears_nothing() -> None:
    fleet = _fleet()
    # auv1 starts 2 m from the transmitter (its depth), auv2 30 m east, auv3 60 m east
    fleet.set_channel_config(ChannelConfig(range_m=45.0))
    fleet.submit_frame(SURFACE_ALL)
    fleet.advance(0.5)
    acks = _acks(fleet)
    assert [len(acks[n]) for n in NAMES] == [1, 1, 0]
    link = fleet.sim("auv3").status()["link"]
    assert link["frames_in"] == 1 and link["frames_lost"] == 1 and not link["in_range"]
    assert fleet.sim("auv3").channel.stats.frames_lost_range == 1
    assert fleet.channel_config.range_m == 45.0


def test_start_positions_are_apart_within_range_and_deterministic() -> None:
    starts = start_positions(15)
    assert starts[0] == (0.0, 0.0)
    assert starts == start_positions(15)
    gaps = [math.dist(a, b) for i, a in enumerate(starts) for b in starts[i + 1 :]]
    assert min(gaps) == pytest.approx(DEFAULT_SPACING_M)
    fleet = FleetSimulation(parse_vehicles("15"))
    for sim in fleet.members.values():
        assert sim.status()["link"]["in_range"]
    poses = [(s.pose().x_m, s.pose().y_m) for s in fleet.members.values()]
    assert poses == starts
    moved = FleetSimulation(parse_vehicles("2"), SimConfig(start_x_m=5, start_y_m=-5), spacing_m=10)
    assert [(s.pose().x_m, s.pose().y_m) for s in moved.members.values()] == [(5, -5), (5, 5)]
    with pytest.raises(ValueError, match="spacing_m must be a positive number"):
        start_positions(2, spacing_m=0)


def test_a_fleet_that_would_start_out_of_range_or_is_no_fleet_is_refused() -> None:
    with pytest.raises(ValueError, match="vehicle auv3 would start 60 m from the transmitter"):
        FleetSimulation(parse_vehicles("3"), SimConfig(channel=ChannelConfig(range_m=50)))
    with pytest.raises(ValueError, match="at least one vehicle"):
        FleetSimulation(())
    with pytest.raises(FleetError, match="address 3 is given twice"):
        FleetSimulation((FleetVehicle("a", 3), FleetVehicle("b", 3)))


def test_a_run_is_repeatable_and_each_vehicle_has_its_own_streams() -> None:
    def run(seed: int) -> list[list[int]]:
        fleet = _fleet(seed=seed, channel=ChannelConfig(ber=0.02))
        for _ in range(10):
            fleet.submit_frame(SURFACE_ALL)
            fleet.advance(0.2)
        return [[a["channel_flipped_bits"] for a in acks] for acks in _acks(fleet).values()]

    assert run(1) == run(1)
    assert run(1) != run(2)
    assert len({vehicle_seed(s, a) for s in range(3) for a in range(1, 16)}) == 45


def test_reset_starts_every_vehicle_again() -> None:
    fleet = _fleet()
    fleet.submit_frame(SQUARE_TO_2)
    fleet.advance(10.0)
    fleet.reset()
    assert fleet.t_s == 0.0 and fleet.transmissions == 0
    assert [_active(fleet, n) for n in NAMES] == [None, None, None]
    fleet.advance(1.0)
    assert all(s.t_s == pytest.approx(1.0) for s in fleet.members.values())


def test_a_vehicle_without_an_address_still_refuses_the_addressed_frame() -> None:
    """The single-vehicle path is today's: 14 bytes are no frame of its."""
    sim = Simulation()
    sim.submit_frame(SURFACE_ALL)
    sim.advance(0.5)
    (ack,) = sim.take_missions()
    assert ack["reason"] == "malformed" and "address" not in ack
    assert "address" not in sim.status()
