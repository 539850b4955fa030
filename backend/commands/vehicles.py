"""The vehicles the command manager delivers to, each with what delivery keeps of it.

Without a fleet there is one, :data:`vehicle_contract.fleet.SINGLE_VEHICLE`, with no address
(its frames are today's, bit for bit). With a fleet (``NEMESYS_VEHICLES``) there is one per
vehicle, each with its address (its frames are addressed: docs/protocol.md, "Addressing"),
and :data:`vehicle_contract.fleet.ALL_VEHICLES` names them all for a Surface (address 0).

Each :class:`Addressee` keeps what is that vehicle's alone: the link it reports back over (its
capability decides one copy and an acknowledgement, or repeated copies), the mirror of what it
flies, the ledger of its frames and their fate (its link health, its BER estimate), the last
command sent to it and when it last acknowledged anything.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from backend.commands.ledger import FrameLedger
from backend.commands.mirror import VehicleMirror
from station.link import Link
from vehicle_contract.fleet import ALL_VEHICLES, SINGLE_VEHICLE

__all__ = ["ALL_VEHICLES", "SINGLE_VEHICLE", "Addressee", "UnknownVehicle"]


@dataclass(eq=False)
class Addressee:
    """One vehicle as the command manager sees it (see the module's doc)."""

    name: str
    #: Its frames' address (1-15); None: the single vehicle's unaddressed frames.
    address: int | None
    #: What it reports back over (a fleet on a one-way modem: the shared transmitter's link).
    link: Link
    mirror: VehicleMirror
    ledger: FrameLedger = field(default_factory=FrameLedger)
    #: The command to it whose first copy left most recently: ``{id, pattern, pattern_id,
    #: params}`` (None: none yet).
    last_sent: dict[str, Any] | None = None
    #: When its last acknowledgement arrived (the manager's clock, s; None: none yet).
    last_ack_s: float | None = None

    @property
    def acknowledges(self) -> bool:
        """Its acknowledgements come back (one copy, then the answer), else repeated copies."""
        return self.link.acknowledges


class UnknownVehicle(ValueError):
    """A vehicle name that is not one of the console's; the message names the known ones."""

    def __init__(self, name: object, known: list[str], *, surface: bool = False) -> None:
        allowed = ", ".join(known)
        extra = f", or {ALL_VEHICLES!r} (Surface only)" if surface else ""
        super().__init__(f"no vehicle {name!r:.40}: the console's vehicles are {allowed}{extra}")
        self.name = name
        self.known = known
