"""The parts of delivery that hold no state of the console: how many copies, one attempt's
bookkeeping, the rate limit and which record an acknowledgement answers."""

from __future__ import annotations

import asyncio
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Final

from backend.clock import SYSTEM_CLOCK, Clock
from codec import Encoded, RejectReason, copies_for
from station.transmit import ack_match

#: A Surface on a one-way link goes out at least this many times...
MIN_SURFACE_COPIES: Final = 3
#: ... and enough times for this delivery probability at the link's bit-error rate.
SURFACE_DELIVERY_TARGET: Final = 0.999999
#: Rejections that mean the channel damaged the copy (the station sends only valid frames):
#: while copies remain, the command waits for the next one. Not ``other_vehicle``: that frame
#: decoded fine, at a vehicle it was not for (a fleet's; it answers none of this one's).
DAMAGE_REASONS: Final = frozenset(r.value for r in RejectReason) - {RejectReason.OTHER_VEHICLE}


class RateLimited(Exception):
    """Too many transmissions; ``retry_after_s`` until the next is allowed."""

    def __init__(self, retry_after_s: float, limit: int) -> None:
        super().__init__(
            f"at most {limit} transmissions a minute; try again in {retry_after_s:.0f} s "
            "(Surface is never limited)"
        )
        self.retry_after_s = retry_after_s


class RateLimiter:
    """At most ``per_minute`` transmissions in any 60 s (Surface does not ask)."""

    def __init__(self, per_minute: int, clock: Clock = SYSTEM_CLOCK) -> None:
        self.per_minute = per_minute
        self._clock = clock
        self._sends: deque[float] = deque()

    def take(self) -> None:
        """Count one transmission now.

        Raises:
            RateLimited: the limit is reached; nothing is counted.
        """
        now = self._clock.monotonic()
        while self._sends and now - self._sends[0] > 60.0:
            self._sends.popleft()
        if len(self._sends) >= self.per_minute:
            raise RateLimited(60.0 - (now - self._sends[0]), self.per_minute)
        self._sends.append(now)


def planned_copies(
    kind: str, acknowledges: bool, ber: float, loss: float, target: float
) -> int | None:
    """Copies a command of ``kind`` gets: on a two-way link one (a Surface: ``None``, until
    acknowledged); on a one-way link the fewest reaching ``target`` at ``ber`` and ``loss``
    (a Surface: at least :data:`MIN_SURFACE_COPIES`, reaching :data:`SURFACE_DELIVERY_TARGET`).
    """
    if kind == "surface":
        if acknowledges:
            return None
        return copies_for(ber, SURFACE_DELIVERY_TARGET, loss=loss, minimum=MIN_SURFACE_COPIES)
    return 1 if acknowledges else copies_for(ber, target, loss=loss)


@dataclass(eq=False)
class Delivery:
    """One attempt at getting a record to the vehicle: its copies, spaced in time."""

    command_id: int
    enc: Encoded
    kind: str
    two_way: bool
    #: Copies planned in this attempt; ``None``: until acknowledged (two-way Surface).
    copies: int | None
    interval_s: float
    ber: float
    loss: float
    tried: int = 0  # copies handed to the link in this attempt, failed ones too
    last_failure: str | None = None
    wake: asyncio.Event = field(default_factory=asyncio.Event)
    task: asyncio.Task[None] | None = None
    #: The records its frame carries, each with whether its vehicle's acknowledgement is
    #: expected: the command's own (``command_id``); a Surface to all, one per vehicle.
    members: dict[int, bool] = field(default_factory=dict)
    #: Its frame is addressed to all vehicles (a fleet's Surface to all, address 0).
    to_all: bool = False
    #: When its next copy may leave (the manager's clock, s): the airtime budget's schedule.
    next_s: float = 0.0

    def __post_init__(self) -> None:
        if not self.members:
            self.members = {self.command_id: self.two_way}

    def more(self) -> bool:
        return self.copies is None or self.tried < self.copies


def best_match(awaiting: Mapping[int, Encoded], ack: Mapping[str, Any]) -> int | None:
    """The record an acknowledgement answers, among those awaiting one (oldest first): the
    exact frame, else one within the BCH correction radius, else the oldest."""
    best: tuple[int, int] | None = None  # (rank, id): exact 0, near 1, by order 2
    for cid, enc in awaiting.items():
        how = ack_match(enc.frame, dict(ack))
        rank = {"exact": 0, "near": 1}.get(how or "", 2)
        if best is None or rank < best[0]:
            best = (rank, cid)
    return best[1] if best is not None else None


def delivery_kind(kind: str, pattern: str) -> str:
    """How a command is delivered: ``surface`` for every surface frame (never rate limited,
    its own count of copies, joined by a later press), else its kind."""
    return "surface" if pattern == "surface" else kind
