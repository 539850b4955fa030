"""The send policy on what the checks found: a hard violation is refused on every path, a
soft one needs the operator's explicit override, and an override covers only what the operator
was shown (a relayed command's: the violations its operator saw on the console it came from,
not a stricter console's own).
"""

from __future__ import annotations

from dataclasses import dataclass

from backend.commands.checks import CheckLine, SendViolation
from backend.commands.refusals import LimitRefused, OverrideNeeded
from codec import Encoded

__all__ = ["Accepted", "Assessment", "ViolationKey", "decide", "key"]


@dataclass(frozen=True)
class Assessment:
    """A command as the checks see it: the frame that would leave, and what it breaks."""

    enc: Encoded
    violations: tuple[SendViolation, ...] = ()
    #: Every check's line (what the confirm dialog shows).
    lines: tuple[CheckLine, ...] = ()

    @property
    def hard(self) -> tuple[SendViolation, ...]:
        return tuple(v for v in self.violations if v.kind == "hard")

    @property
    def soft(self) -> tuple[SendViolation, ...]:
        return tuple(v for v in self.violations if v.kind == "soft")


def decide(
    assessment: Assessment, override: bool, accepted: Accepted | None = None
) -> tuple[SendViolation, ...]:
    """The policy on what the checks found: the violations the operator overrode (empty when
    there were none). ``accepted``: a relayed command's, the soft violations its operator was
    shown and overrode on the console it came from (None: asked here, where the override
    covers what these checks find).

    Raises:
        LimitRefused: a hard violation (whatever ``override`` says).
        OverrideNeeded: a soft violation without ``override``, or one the relaying console's
            operator never saw (this console's limits stricter than theirs).
    """
    if assessment.hard:
        raise LimitRefused("limit violation: no operator can override it", assessment.violations)
    if assessment.soft and not override:
        raise OverrideNeeded("limit violation: send with override to accept it", assessment.soft)
    unseen = tuple(v for v in assessment.soft if accepted is not None and key(v) not in accepted)
    if unseen:
        raise OverrideNeeded(
            "limit violation of this console's own limits, which the operator's override did "
            "not cover (they were not shown it): send with override again to accept it",
            unseen,
        )
    return assessment.soft


#: A soft violation as an operator accepts it: its check and parameter.
ViolationKey = tuple[str, str]
#: The soft violations an operator accepted.
Accepted = frozenset[ViolationKey]


def key(v: SendViolation) -> ViolationKey:
    return (v.check, v.param)
