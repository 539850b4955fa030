"""A fleet on one ME link: each vehicle's name (its ROS 2 namespace) and its frame address.

The one place a fleet is read (``NEMESYS_VEHICLES`` on the console, ``nemesys sim --vehicles``):
either a count, ``3`` (vehicles ``auv1``, ``auv2``, ``auv3`` with addresses 1, 2, 3), or a JSON
list, ``[{"name": "alpha", "address": 4}, ...]``. A vehicle's name is its namespace on the ROS
graph (:func:`vehicle_contract.names.topic_name`: ``/auv1/nemesys/pose``) and its address the
one its frames carry (:mod:`codec`'s addressed frame, 1 to :data:`codec.MAX_ADDRESS`; 0 is
every vehicle and is no vehicle's own). No fleet (an empty setting) is the single vehicle of
today, whose frames carry no address.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from typing import Final

from codec import BROADCAST_ADDRESS, MAX_ADDRESS

#: A vehicle's name: a lower-case letter, then lower-case letters, digits or underscores (a ROS 2
#: namespace token that also reads well in a URL and a file name).
NAME_PATTERN: Final = re.compile(r"[a-z][a-z0-9_]{0,31}")
#: The name the console gives "every vehicle" (``POST /api/surface {"vehicle": "all"}``).
ALL_VEHICLES: Final = "all"
#: The name of the single vehicle when no fleet is configured (the belief's key since issue 20).
SINGLE_VEHICLE: Final = "nemesys"
#: Most vehicles a fleet can have: one per address.
MAX_VEHICLES: Final = MAX_ADDRESS - BROADCAST_ADDRESS


class FleetError(ValueError):
    """A fleet setting that cannot be used; the message names what is wrong and what is
    allowed."""


@dataclass(frozen=True, slots=True)
class FleetVehicle:
    """One vehicle of a fleet: ``name`` (its namespace, unique) and ``address`` (1 to
    :data:`codec.MAX_ADDRESS`, unique)."""

    name: str
    address: int

    @property
    def namespace(self) -> str:
        """Its namespace on the ROS graph (``/auv1``)."""
        return f"/{self.name}"


def parse_vehicles(text: str) -> tuple[FleetVehicle, ...]:
    """The fleet a setting names: ``""`` (none: the single vehicle), a count, or a JSON list of
    ``{"name", "address"}`` objects.

    Raises:
        FleetError: naming the setting's fault and what is allowed.
    """
    text = text.strip()
    if not text:
        return ()
    if text.isdigit():
        count = int(text)
        if not 1 <= count <= MAX_VEHICLES:
            raise FleetError(
                f"NEMESYS_VEHICLES={text}: a fleet has 1 to {MAX_VEHICLES} vehicles (one per "
                "frame address); leave it empty for a single vehicle"
            )
        return tuple(FleetVehicle(f"auv{i}", i) for i in range(1, count + 1))
    try:
        items = json.loads(text)
    except json.JSONDecodeError as err:
        raise FleetError(
            f"NEMESYS_VEHICLES is neither a count nor JSON ({err.msg} at character {err.pos}): "
            'give a count, e.g. 3, or a list such as [{"name": "auv1", "address": 1}]'
        ) from None
    if not isinstance(items, list) or not items:
        raise FleetError(
            'NEMESYS_VEHICLES as JSON must be a non-empty list such as [{"name": "auv1", '
            '"address": 1}]'
        )
    return check_fleet([_vehicle(i, item) for i, item in enumerate(items)])


def _vehicle(index: int, item: object) -> FleetVehicle:
    where = f"NEMESYS_VEHICLES[{index}]"
    if not isinstance(item, dict) or set(item) != {"name", "address"}:
        raise FleetError(f'{where}: each vehicle is an object {{"name": ..., "address": ...}}')
    name, address = item["name"], item["address"]
    if not isinstance(name, str) or not NAME_PATTERN.fullmatch(name) or name == ALL_VEHICLES:
        raise FleetError(
            f"{where}: name {name!r}: a lower-case letter, then up to 31 lower-case letters, "
            f"digits or underscores, and not {ALL_VEHICLES!r}"
        )
    if isinstance(address, bool) or not isinstance(address, int):
        raise FleetError(f"{where}: address {address!r}: a whole number 1-{MAX_ADDRESS}")
    return FleetVehicle(name, address)


def check_fleet(vehicles: list[FleetVehicle]) -> tuple[FleetVehicle, ...]:
    """``vehicles`` as a fleet: at most :data:`MAX_VEHICLES`, addresses in range, names and
    addresses unique.

    Raises:
        FleetError: naming the first fault.
    """
    if len(vehicles) > MAX_VEHICLES:
        raise FleetError(f"a fleet has at most {MAX_VEHICLES} vehicles (got {len(vehicles)})")
    names: set[str] = set()
    addresses: set[int] = set()
    for v in vehicles:
        if not BROADCAST_ADDRESS < v.address <= MAX_ADDRESS:
            raise FleetError(
                f"vehicle {v.name}: address {v.address}: 1-{MAX_ADDRESS} "
                f"({BROADCAST_ADDRESS} is every vehicle, no vehicle's own)"
            )
        if v.name in names:
            raise FleetError(f"vehicle name {v.name!r} is given twice: names are unique")
        if v.address in addresses:
            raise FleetError(f"address {v.address} is given twice: each vehicle has its own")
        names.add(v.name)
        addresses.add(v.address)
    return tuple(vehicles)
