"""Which command the vehicle runs, on a link that says nothing back (pure).

Each command sent since the last known state reached the vehicle with its own probability
``p_i`` (its record's ``p_delivered``: at least one of the copies that actually left decoded).
The vehicle runs the newest command that reached it, so command ``i`` is the one running when
it arrived and none newer did::

    P(i runs) = p_i * prod_{j newer than i} (1 - p_j)

and with probability ``prod_j (1 - p_j)`` none arrived: the vehicle still does what it was
last known to do (or what nobody knows). The probabilities sum to 1.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

__all__ = ["running_odds"]


def running_odds(p_delivered: Sequence[float]) -> tuple[list[float], float]:
    """P(each command is the one running), oldest first as given, and P(none arrived).

    Args:
        p_delivered: each command's delivery probability, oldest first (wire order).

    Raises:
        ValueError: a probability that is not a finite number in [0, 1], naming its index.
    """
    for i, p in enumerate(p_delivered):
        if not (isinstance(p, int | float) and math.isfinite(p) and 0.0 <= p <= 1.0):
            raise ValueError(f"p_delivered[{i}] must be a probability in [0, 1], got {p!r}")
    odds = [0.0] * len(p_delivered)
    none_newer = 1.0  # P(no command newer than the one at hand arrived)
    for i in reversed(range(len(p_delivered))):
        odds[i] = p_delivered[i] * none_newer
        none_newer *= 1.0 - p_delivered[i]
    return odds, none_newer
