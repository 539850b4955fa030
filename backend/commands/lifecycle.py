"""The command lifecycle as one table: every state, every event and where it leads.

A command is written ``queued`` before anything is transmitted. Then:

* **one-way links** (an ME modem, or a ROS 2 vehicle without the onboard agent): its ``copies``
  go out spaced in time (``transmitted`` while they do) and it ends ``sent``: nothing more can
  be known from the station;
* **two-way links** (a vehicle running the onboard agent): it ends ``acknowledged`` or
  ``rejected`` by the vehicle's acknowledgement, or ``timed_out`` when none comes in time.

On either kind it may end ``failed`` (no copy left the station), ``superseded`` (a newer
command or a Surface replaced it while its copies were still going out) or ``interrupted`` (the
console stopped, crashed or the training vehicle was reset while it was on its way). Every state
but ``queued`` and ``transmitted`` is terminal; ``interrupted``, ``timed_out``, ``failed``,
``rejected`` and ``superseded`` may be retried: a new attempt of the same record.

:func:`advance` is the only way a state changes; ``docs/api.md`` draws this table.
"""

from __future__ import annotations

from enum import StrEnum
from types import MappingProxyType
from typing import Final


class State(StrEnum):
    QUEUED = "queued"
    TRANSMITTED = "transmitted"
    SENT = "sent"
    ACKNOWLEDGED = "acknowledged"
    REJECTED = "rejected"
    TIMED_OUT = "timed_out"
    FAILED = "failed"
    SUPERSEDED = "superseded"
    INTERRUPTED = "interrupted"


class Event(StrEnum):
    #: One copy left the station.
    COPY_SENT = "copy_sent"
    #: One-way link: the last copy is out.
    COPIES_OUT = "copies_out"
    #: Every planned copy failed to leave the station (link down, port gone).
    NO_COPY_LEFT = "no_copy_left"
    #: The vehicle's acknowledgement: accepted / rejected.
    ACCEPTED = "accepted"
    REJECTED = "rejected"
    #: Two-way link: no acknowledgement within the timeout after the last copy.
    ACK_TIMEOUT = "ack_timeout"
    #: A newer command or a Surface replaced it while its copies were still going out.
    SUPERSEDED = "superseded"
    #: Shutdown, a crash found at the next start, or a training reset.
    INTERRUPTED = "interrupted"


#: States a command is still on its way in (the rest are terminal).
ON_ITS_WAY: Final = frozenset({State.QUEUED, State.TRANSMITTED})
#: Terminal states the operator may retry: a retry is a new command (``retry_of`` names the
#: old one), and the old record keeps its state.
RETRYABLE: Final = frozenset(
    {State.INTERRUPTED, State.TIMED_OUT, State.FAILED, State.REJECTED, State.SUPERSEDED}
)
TERMINAL: Final = frozenset(State) - ON_ITS_WAY

#: event -> (the states it may happen in, the state it leads to).
TRANSITIONS: Final = MappingProxyType(
    {
        Event.COPY_SENT: (ON_ITS_WAY, State.TRANSMITTED),
        Event.COPIES_OUT: (frozenset({State.TRANSMITTED}), State.SENT),
        Event.NO_COPY_LEFT: (frozenset({State.QUEUED}), State.FAILED),
        # an acknowledgement may overtake the bookkeeping of the copy it answers
        Event.ACCEPTED: (ON_ITS_WAY, State.ACKNOWLEDGED),
        Event.REJECTED: (ON_ITS_WAY, State.REJECTED),
        Event.ACK_TIMEOUT: (frozenset({State.TRANSMITTED}), State.TIMED_OUT),
        Event.SUPERSEDED: (ON_ITS_WAY, State.SUPERSEDED),
        Event.INTERRUPTED: (ON_ITS_WAY, State.INTERRUPTED),
    }
)


class IllegalTransition(Exception):
    """An event that cannot happen in the command's state."""

    def __init__(self, state: str, event: Event) -> None:
        allowed = ", ".join(sorted(TRANSITIONS[event][0]))
        super().__init__(f"{event} cannot happen to a {state} command (only when {allowed})")
        self.state = state
        self.event = event


def advance(state: str, event: Event) -> State:
    """The state ``event`` leads to from ``state``.

    Raises:
        IllegalTransition: the event cannot happen in that state.
    """
    sources, target = TRANSITIONS[event]
    if state not in sources:
        raise IllegalTransition(state, event)
    return target
