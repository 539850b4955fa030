"""The contract's words: the reason a rejection gives and the mode a status reports.

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

#: Every ``reason`` a rejection may give: the codec's (the frame did not decode) and the
#: agent's (it decoded but is no flyable plan within the vehicle's limits).
REJECT_REASONS = (*(r.value for r in RejectReason), INVALID_PLAN, LIMIT_VIOLATION)


class Mode(StrEnum):
    """What the vehicle is doing: the ``mode`` of the status."""

    IDLE = "idle"  # no command yet: holding the start pose
    RUNNING = "running"  # following a pattern
    HOLDING = "holding"  # a finite pattern is complete, or a hover: station keeping
    SURFACING = "surfacing"
    SURFACED = "surfaced"
    BATTERY_EMPTY = "battery_empty"


#: The words of ``mode`` in the status (what guidance is doing).
MODES = tuple(m.value for m in Mode)
