"""The frames' ledger: every frame that left the station and what became of it, over the last
:data:`WINDOW` frames and since the dive began, and what the dive's acknowledgements say of
the channel (its bit-error rate estimate: :mod:`station.channel_estimate`).

The command records (:mod:`backend.commands.records`) write it as frames leave and answers
come; the link's health (:mod:`backend.commands.health`) reads its totals.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Final, Literal

from pydantic import BaseModel

from station.channel_estimate import ChannelEstimator

#: Frames in the "recent" window.
WINDOW: Final = 20

Outcome = Literal["sent", "awaiting", "acknowledged", "rejected", "timed_out"]


class FrameCounts(BaseModel):
    """Frames that left the station, and what became of them."""

    #: Every frame that left.
    frames: int = 0
    #: Frames no acknowledgement was expected for (one-way link, or replaced before one came).
    sent: int = 0
    acknowledged: int = 0
    rejected: int = 0
    timed_out: int = 0


def _counts(frames: int = 0) -> FrameCounts:
    """Counts with every field given (a count left at its default would be "unset", and
    left out of a document serialised with ``exclude_unset``)."""
    return FrameCounts(frames=frames, sent=0, acknowledged=0, rejected=0, timed_out=0)


class FrameTotals(BaseModel):
    recent: FrameCounts
    dive: FrameCounts


@dataclass
class _Slot:
    command_id: int
    outcome: Outcome


class FrameLedger:
    """Frames out and their fate: the last :data:`WINDOW` and the dive's totals."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """A new dive."""
        self._recent: deque[_Slot] = deque(maxlen=WINDOW)
        self._dive = _counts()
        self._awaiting: dict[int, int] = {}  # command id -> its frames awaiting an answer
        #: Every acknowledgement of the dive, as evidence of the channel's bit-error rate.
        self.channel = ChannelEstimator()

    def frame_out(self, command_id: int, *, answer_expected: bool) -> None:
        self._dive.frames += 1
        if answer_expected:
            self._awaiting[command_id] = self._awaiting.get(command_id, 0) + 1
            self._recent.append(_Slot(command_id, "awaiting"))
        else:
            self._dive.sent += 1
            self._recent.append(_Slot(command_id, "sent"))

    def settle(self, command_id: int, outcome: Outcome) -> None:
        """The command's frames awaiting an answer got ``outcome`` (``sent``: none will
        come, e.g. it was replaced)."""
        count = self._awaiting.pop(command_id, 0)
        setattr(self._dive, outcome, getattr(self._dive, outcome) + count)
        for slot in self._recent:
            if slot.command_id == command_id and slot.outcome == "awaiting":
                slot.outcome = outcome

    def totals(self) -> FrameTotals:
        recent = _counts(len(self._recent))
        for slot in self._recent:
            if slot.outcome != "awaiting":
                setattr(recent, slot.outcome, getattr(recent, slot.outcome) + 1)
        return FrameTotals(recent=recent, dive=self._dive.model_copy())
