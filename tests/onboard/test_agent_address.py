"""The onboard agent of a fleet's vehicle (an address): it runs frames addressed to it or to
all, and the single-vehicle Surface; it acknowledges another's frame as rejected
``other_vehicle``, changing nothing. With no address it is today's agent."""

from __future__ import annotations

from typing import Any

import pytest

from codec import ADDRESSED_FRAME_BITS, FRAME_BITS, ParamValue, encode_frame
from onboard.agent import OnboardAgent
from onboard.guidance import Guidance
from planner import Limits, VehicleState
from vehicle_contract.payloads import validate_ack

STATE = VehicleState(0.0, 0.0, 2.0, 0.0, 0.0, 12.5)
CIRCLE: dict[str, ParamValue] = {"speed": 0.2, "depth": 2, "radius": 3, "direction": "cw"}


def frame(pattern: str, address: int | None, **params: ParamValue) -> tuple[int, int]:
    enc = encode_frame(pattern, params, address=address)
    return enc.frame.value, len(enc.frame.bits)


def receive(agent: OnboardAgent, sent: tuple[int, int]) -> dict[str, Any]:
    ack, _ = agent.receive(sent[0], sent[1], STATE)
    assert validate_ack(ack) == []
    return ack


def test_its_own_frame_and_frames_to_all_are_run() -> None:
    agent = OnboardAgent(Guidance(), address=4)
    ack = receive(agent, frame("circle", 4, **CIRCLE))
    assert (ack["outcome"], ack["address"], ack["duplicate"]) == ("accepted", 4, False)
    assert len(ack["frame_hex"]) == 27 and agent.active is not None
    ack = receive(agent, frame("circle", 0, **CIRCLE))  # the same command, to all
    assert (ack["outcome"], ack["address"], ack["duplicate"]) == ("accepted", 0, True)


def test_another_vehicles_frame_is_refused_and_changes_nothing() -> None:
    agent = OnboardAgent(Guidance(), address=4)
    receive(agent, frame("circle", 4, **CIRCLE))
    active = agent.active
    ack = receive(agent, frame("surface", 5))
    assert (ack["outcome"], ack["reason"], ack["address"]) == ("rejected", "other_vehicle", 5)
    assert ack["detail"] == "addressed to vehicle 5, not to this vehicle (4)"
    assert agent.active is active and ack["active"]["pattern"] == "circle"


def test_unaddressed_frames_only_surface() -> None:
    agent = OnboardAgent(Guidance(), address=4)
    ack = receive(agent, frame("circle", None, **CIRCLE))
    assert (ack["outcome"], ack["reason"], ack["address"]) == ("rejected", "other_vehicle", None)
    ack = receive(agent, frame("surface", None))
    assert (ack["outcome"], ack["address"]) == ("accepted", None)
    assert ack["command"]["pattern"] == "surface"


def test_surface_to_all_is_run_whatever_the_limits() -> None:
    agent = OnboardAgent(Guidance(), Limits(max_depth_m=1.0), address=9)
    assert receive(agent, frame("circle", 0, **CIRCLE))["reason"] == "limit_violation"
    ack = receive(agent, frame("surface", 0))
    assert (ack["outcome"], ack["address"]) == ("accepted", 0)


def test_lengths_and_damage() -> None:
    agent = OnboardAgent(Guidance(), address=4)
    ack = receive(agent, (0, 64))
    assert ack["reason"] == "malformed" and "108" in ack["detail"]
    value, n_bits = frame("circle", 4, **CIRCLE)
    assert n_bits == ADDRESSED_FRAME_BITS
    damaged = value ^ (0b111 << 40)
    assert receive(agent, (damaged, n_bits))["reason"] == "uncorrectable"


def test_without_an_address_it_is_todays_agent() -> None:
    agent = OnboardAgent(Guidance())
    ack, _ = agent.receive(*frame("circle", 4, **CIRCLE), STATE)
    assert ack["reason"] == "malformed" and "address" not in ack
    ack, _ = agent.receive(*frame("circle", None, **CIRCLE), STATE)
    assert ack["outcome"] == "accepted" and "address" not in ack
    assert FRAME_BITS == 100


@pytest.mark.parametrize("bad", [0, 16, -3])
def test_an_address_out_of_range_is_refused(bad: int) -> None:
    with pytest.raises(ValueError, match="a vehicle's own address is 1 to 15"):
        OnboardAgent(Guidance(), address=bad)


def test_a_fleets_vehicle_loads_nothing_heavy_and_todays_loads_none_of_it() -> None:
    """The addressed path stays on the onboard budget (no standard library but math, no
    console module), and a vehicle with no address never loads it."""
    from tests.codec.test_imports import CONSOLE_ONLY, plain_modules_after
    from tests.onboard.test_imports import ONBOARD, ONBOARD_STDLIB

    fleet = ("codec._address", "codec._address_sync", "onboard._fleet")
    receive = (
        "from planner import VehicleState; "
        "agent = OnboardAgent(Guidance(), address=3); "
        "agent.receive(int('aaaa433c1321473000000f40ee0', 16), 108, VehicleState(0.0, 0.0, 2.0))"
    )
    bare = plain_modules_after("pass")
    loaded = plain_modules_after(f"{ONBOARD}; {receive}")
    assert set(fleet) <= loaded
    ours = ("codec", "planner", "onboard", "vehicle_contract")
    assert {m for m in loaded - bare if m.partition(".")[0] not in ours} == ONBOARD_STDLIB
    assert not set(CONSOLE_ONLY) & loaded
    today = plain_modules_after(f"{ONBOARD}; OnboardAgent(Guidance())")
    assert not set(fleet) & today
