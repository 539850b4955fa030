"""The contract's words: the reason a rejection gives and the mode a status reports; and the
numbers the onboard path needs: the acknowledgement deadline and how many recent
acknowledgements a status carries.

The vehicle contract (:mod:`vehicle_contract.contract`) owns them; the onboard agent and
guidance (:mod:`onboard`), which a real vehicle installs, import them from here. So this module
is on the onboard path and stays as light as it: ``codec`` (already loaded there, with its
:class:`codec.compat.StrEnum`), no :mod:`enum`, :mod:`typing` or :mod:`dataclasses`
(``bench/_reconfig_memory.py``, ``tests/codec/test_imports.py``).
"""

from __future__ import annotations

from codec import RejectReason
from codec.compat import StrEnum

#: A frame that decoded but is no flyable plan (the planner refused it).
INVALID_PLAN = "invalid_plan"
#: A frame that decoded to a plan beyond the vehicle's limits.
LIMIT_VIOLATION = "limit_violation"
#: A frame that decoded, but the vehicle has no navigation to plan from (none yet, or stale).
NO_NAVIGATION = "no_navigation"

#: A frame addressed to another vehicle (or, at a vehicle with an address, an unaddressed one
#: other than surface): the codec's own reason (docs/protocol.md, "Addressing").
OTHER_VEHICLE = RejectReason.OTHER_VEHICLE.value

#: Every ``reason`` a rejection may give: the codec's (the frame did not decode, or is not for
#: this vehicle) and the agent's (it decoded but is no flyable plan within the vehicle's
#: limits, or there is no navigation to plan it from).
REJECT_REASONS = (*(r.value for r in RejectReason), INVALID_PLAN, LIMIT_VIOLATION, NO_NAVIGATION)

#: Addresses on a link shared by a fleet: 0 is every vehicle's, a vehicle's own is 1 to 15
#: (:mod:`codec._address`, spelt out here so the contract loads no more of the codec).
BROADCAST_ADDRESS = 0
MAX_ADDRESS = 15


class Mode(StrEnum):
    """What the vehicle is doing: the ``mode`` of the status."""

    IDLE = "idle"  # no command yet: holding the start pose
    RUNNING = "running"  # following a pattern
    HOLDING = "holding"  # a finite pattern is complete, or a hover: station keeping
    SURFACING = "surfacing"
    SURFACED = "surfaced"
    BATTERY_EMPTY = "battery_empty"
    #: Navigation went stale: the vehicle holds or surfaces (its setting) from where it last
    #: knew it was, until a new command is accepted with navigation valid again.
    NAV_FAULT = "nav_fault"


#: The words of ``mode`` in the status (what guidance is doing).
MODES = tuple(m.value for m in Mode)

#: A vehicle acknowledges a frame within this long of receiving it (s): reception is the
#: message reaching the vehicle's node (or its own ME receiver synchronising on the frame).
#: One made later carries ``late: true``.
ACK_DEADLINE_S = 1.0

#: The status carries the acknowledgements of this long (s, ROS time), at most
#: :data:`RECENT_ACKS_MAX` of them: a console that reconnects within it loses none.
RECENT_ACKS_S = 30.0
RECENT_ACKS_MAX = 10
