"""The bit-error rate the copies are chosen from, and where it comes from.

In training it is the emulated channel's (the truth the operator set). On a real link it is
the operator's choice (``copies_from``): the BER assumed of the link (the ``link_ber``
setting, changed with ``PUT /api/link``), or the upper end of the online estimate's 95 %
interval (:mod:`station.channel_estimate`, fed by every acknowledgement of the dive through
the frames' ledger). Until the estimate exists the assumed BER is used, and the link's health
says so (``ber_source``). The choice is written to the mission log, naming the operator,
before it takes effect.

On a two-way link a command goes out once and a Surface repeats until acknowledged whatever
the BER; there the choice shows in the records' ``p_delivered``, and it decides the copies as
soon as the link stops acknowledging (a one-way link, or a vehicle whose capability is not
known after a reconnection).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final, Literal, get_args

from pydantic import BaseModel, Field

from station.channel_estimate import BerEstimate, ChannelEstimator

#: The operator's choice of the BER the copies follow on a real link.
CopiesFrom = Literal["assumed", "estimate_upper"]
COPIES_FROM: Final[tuple[str, ...]] = get_args(CopiesFrom)
#: Where the BER the copies follow comes from now.
BerSource = Literal["emulated", "assumed", "estimate_upper"]

#: The choices in the operator's words (the mission log's events).
COPIES_FROM_WORDS: Final[dict[str, str]] = {
    "assumed": "the assumed bit-error rate (link_ber)",
    "estimate_upper": "the upper end of the estimate's 95 % interval",
}


class ChannelEstimateView(BaseModel):
    """The link's bit-error rate estimated from the dive's acknowledgements
    (``/api/vehicle`` -> ``link.channel``)."""

    frames: int = Field(
        description="acknowledged frames it rests on: decoded, or refused by the decoder"
    )
    min_frames: int = Field(description="frames needed before an estimate is given")
    ber: float | None = Field(description="maximum-likelihood bit-error rate; null: none yet")
    low: float | None = Field(description="lower end of the interval; null: no estimate yet")
    high: float | None = Field(description="upper end of the interval; null: no estimate yet")
    confidence: float = Field(description="the interval's confidence (0.95)")
    not_decoded: int = Field(
        description="of the frames, those the decoder refused (sync or codeword errors beyond "
        "its reach)"
    )
    ignored: int = Field(
        description="acknowledgements that say nothing of the channel (malformed, unknown "
        "reason): not counted"
    )


def estimate_view(estimator: ChannelEstimator) -> ChannelEstimateView:
    counts, est = estimator.counts, estimator.estimate()
    return ChannelEstimateView(
        frames=counts.frames,
        min_frames=estimator.min_frames,
        ber=None if est is None else est.ber,
        low=None if est is None else est.low,
        high=None if est is None else est.high,
        confidence=0.95 if est is None else est.confidence,
        not_decoded=counts.not_decoded,
        ignored=estimator.ignored,
    )


@dataclass(frozen=True, slots=True)
class BerNow:
    """The (bit-error rate, whole-frame loss) the copies are chosen from, and its source."""

    ber: float
    loss: float
    source: BerSource


class BerChoice:
    """The BER assumed of a real link and the operator's choice of what the copies follow."""

    def __init__(self, assumed_ber: float) -> None:
        self.assumed_ber = assumed_ber
        self.copies_from: CopiesFrom = "assumed"

    def now(self, emulated: tuple[float, float] | None, estimate: BerEstimate | None) -> BerNow:
        """``emulated``: the training channel's (BER, loss), which the copies follow there."""
        if emulated is not None:
            return BerNow(emulated[0], emulated[1], "emulated")
        if self.copies_from == "estimate_upper" and estimate is not None:
            return BerNow(estimate.high, 0.0, "estimate_upper")
        return BerNow(self.assumed_ber, 0.0, "assumed")
