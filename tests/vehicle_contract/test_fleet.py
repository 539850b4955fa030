"""The fleet setting (vehicle_contract/fleet.py): a count or a JSON list, every fault named."""

from __future__ import annotations

import pytest

from codec import MAX_ADDRESS
from vehicle_contract.fleet import FleetError, FleetVehicle, parse_vehicles


def test_no_fleet_is_the_single_vehicle() -> None:
    assert parse_vehicles("") == ()
    assert parse_vehicles("  ") == ()


def test_a_count_names_and_numbers_the_vehicles() -> None:
    fleet = parse_vehicles("3")
    assert fleet == (FleetVehicle("auv1", 1), FleetVehicle("auv2", 2), FleetVehicle("auv3", 3))
    assert fleet[1].namespace == "/auv2"
    assert len(parse_vehicles(str(MAX_ADDRESS))) == MAX_ADDRESS


def test_a_json_list() -> None:
    fleet = parse_vehicles('[{"name": "alpha", "address": 7}, {"name": "b_2", "address": 1}]')
    assert fleet == (FleetVehicle("alpha", 7), FleetVehicle("b_2", 1))


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ("0", "1 to 15 vehicles"),
        ("16", "1 to 15 vehicles"),
        ("three", "neither a count nor JSON"),
        ("[]", "non-empty list"),
        ('{"name": "a", "address": 1}', "non-empty list"),
        ('[{"name": "a"}]', '"address"'),
        ('[{"name": "A1", "address": 1}]', "lower-case letter"),
        ('[{"name": "all", "address": 1}]', "not 'all'"),
        ('[{"name": "a", "address": "1"}]', "whole number"),
        ('[{"name": "a", "address": true}]', "whole number"),
        ('[{"name": "a", "address": 0}]', "0 is every vehicle"),
        ('[{"name": "a", "address": 16}]', "1-15"),
        ('[{"name": "a", "address": 1}, {"name": "a", "address": 2}]', "given twice"),
        ('[{"name": "a", "address": 1}, {"name": "b", "address": 1}]', "given twice"),
    ],
)
def test_every_fault_is_named(text: str, named: str) -> None:
    with pytest.raises(FleetError, match=named.replace("(", r"\(")):
        parse_vehicles(text)
